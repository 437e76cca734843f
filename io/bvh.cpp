#include "io/bvh.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <unordered_set>

#include <glm/gtc/quaternion.hpp>

namespace strata {
namespace {

// The text split into lines of whitespace-separated tokens, each line remembering its 1-based number. The
// hierarchy is free-form (a keyword's arguments may in principle wrap), but MOTION is line-structured: a frame is
// exactly one line, and an error must name that line, so tokens keep their line rather than being one flat stream.
struct Line {
  std::size_t number = 0;
  std::vector<std::string_view> tokens;
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<Line> split_lines(std::string_view text) {
  std::vector<Line> lines;
  std::size_t number = 1;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view row = text.substr(start, end - start);
    Line line;
    line.number = number;
    std::size_t i = 0;
    while (i < row.size()) {
      while (i < row.size() && is_space(row[i])) ++i;
      std::size_t j = i;
      while (j < row.size() && !is_space(row[j])) ++j;
      if (j > i) line.tokens.push_back(row.substr(i, j - i));
      i = j;
    }
    if (!line.tokens.empty()) lines.push_back(std::move(line));
    ++number;
    start = end + 1;
  }
  return lines;
}

class Parser {
 public:
  Parser(std::string_view text, std::string_view source) : source_(source), lines_(split_lines(text)) {}

  BvhMotion parse() {
    BvhMotion motion;
    motion.source = std::string(source_);
    expect_keyword("HIERARCHY");
    const Token root = next("ROOT");
    if (root.text != "ROOT") fail(root.line, "expected ROOT, found '" + std::string(root.text) + "'");
    parse_joint(motion, -1, root.line);
    if (motion.joints.empty()) fail(root.line, "empty hierarchy");

    const Token after = next("MOTION");
    if (after.text == "}") fail(after.line, "unbalanced braces: '}' without a matching '{'");
    if (after.text == "ROOT") fail(after.line, "a second ROOT: only one skeleton per file is supported");
    if (after.text != "MOTION") fail(after.line, "expected MOTION, found '" + std::string(after.text) + "'");

    const Token frames_kw = next("Frames:");
    if (frames_kw.text != "Frames:") fail(frames_kw.line, "expected 'Frames:', found '" + std::string(frames_kw.text) + "'");
    const Token frames_value = next("a frame count");
    const float frames = number(frames_value, "frame count");
    if (frames < 0.0f || frames != std::floor(frames))
      fail(frames_value.line, "frame count must be a non-negative integer, found '" + std::string(frames_value.text) + "'");
    const Token frame_kw = next("Frame Time:");
    const Token time_kw = next("Frame Time:");
    if (frame_kw.text != "Frame" || time_kw.text != "Time:" || time_kw.line != frame_kw.line)
      fail(frame_kw.line, "expected 'Frame Time:', found '" + std::string(frame_kw.text) + "'");
    const Token time_value = next("a frame time");
    motion.frame_time = number(time_value, "frame time");
    if (!(motion.frame_time > 0.0f)) fail(time_value.line, "frame time must be positive");
    if (!at_end() && token_ != 0)
      fail(time_value.line, "unexpected '" + std::string(lines_[line_].tokens[token_]) + "' after the frame time");

    // Checked before anything is sized by it: a hostile "Frames: 1e30" must not allocate (or overflow size_t).
    const std::size_t lines_left = lines_.size() - line_;
    if (frames > static_cast<float>(lines_left))
      fail(last_line(), "'Frames: " + std::string(frames_value.text) + "' but " + std::to_string(lines_left) +
                            " motion lines");
    motion.frame_count = static_cast<std::size_t>(frames);
    for (const BvhJoint& j : motion.joints) motion.channel_count += j.channels.size();
    parse_frames(motion, frames_value.line);
    return motion;
  }

 private:
  struct Token {
    std::string_view text;
    std::size_t line = 0;
  };

  [[noreturn]] void fail(std::size_t line, const std::string& message) const {
    throw LoadError(std::string(source_) + ":" + std::to_string(line) + ": " + message);
  }

  std::size_t last_line() const { return lines_.empty() ? 1 : lines_.back().number; }

  bool at_end() const { return line_ >= lines_.size(); }

  Token peek() const { return {lines_[line_].tokens[token_], lines_[line_].number}; }

  // The next token; at end of text, an error naming what was expected.
  Token next(std::string_view expected) {
    if (at_end()) fail(last_line(), "unexpected end of file, expected " + std::string(expected));
    Token t = peek();
    if (++token_ == lines_[line_].tokens.size()) {
      ++line_;
      token_ = 0;
    }
    return t;
  }

  void expect_keyword(std::string_view keyword) {
    const Token t = next(keyword);
    if (t.text != keyword) fail(t.line, "expected " + std::string(keyword) + ", found '" + std::string(t.text) + "'");
  }

  float number(const Token& t, std::string_view what) const {
    float value = 0.0f;
    std::string_view s = t.text;
    // from_chars rejects a leading '+', which some exporters write.
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(value))
      fail(t.line, std::string(what) + ": '" + std::string(t.text) + "' is not a finite number");
    return value;
  }

  glm::vec3 parse_offset() {
    const Token kw = next("OFFSET");
    if (kw.text != "OFFSET") fail(kw.line, "expected OFFSET, found '" + std::string(kw.text) + "'");
    glm::vec3 v;
    for (int a = 0; a < 3; ++a) {
      const Token t = next("an OFFSET value");
      if (t.line != kw.line) fail(kw.line, "OFFSET has " + std::to_string(a) + " values, expected 3");
      v[a] = number(t, "OFFSET");
    }
    return v;
  }

  std::optional<BvhChannel> channel_of(std::string_view name) const {
    static constexpr std::pair<std::string_view, BvhChannel> kNames[] = {
        {"Xposition", BvhChannel::Xposition}, {"Yposition", BvhChannel::Yposition},
        {"Zposition", BvhChannel::Zposition}, {"Xrotation", BvhChannel::Xrotation},
        {"Yrotation", BvhChannel::Yrotation}, {"Zrotation", BvhChannel::Zrotation}};
    for (const auto& [n, c] : kNames)
      if (n == name) return c;
    return std::nullopt;
  }

  // The name after ROOT/JOINT: the rest of its line, so names with spaces (some exporters write them) survive.
  std::string rest_of_line(std::size_t keyword_line) {
    std::string name;
    while (!at_end() && peek().line == keyword_line) {
      if (!name.empty()) name += ' ';
      name += next("a joint name").text;
    }
    if (name.empty()) fail(keyword_line, "joint without a name");
    return name;
  }

  void expect_open(std::string_view what) {
    const Token t = next("'{'");
    if (t.text != "{") fail(t.line, "expected '{' after " + std::string(what) + ", found '" + std::string(t.text) + "'");
  }

  // Parses the block of one joint (its name comes next), appending it and its descendants to motion.joints.
  void parse_joint(BvhMotion& motion, std::int32_t parent, std::size_t keyword_line, int depth = 0) {
    // Recursive descent, one level per JOINT: a hostile file nesting thousands deep would overflow the stack
    // (found by fuzzing). Human skeletons nest a few dozen levels.
    constexpr int kMaxDepth = 256;
    if (depth > kMaxDepth) fail(keyword_line, "joints nested deeper than " + std::to_string(kMaxDepth) + " levels");
    BvhJoint joint;
    joint.name = rest_of_line(keyword_line);
    joint.parent = parent;
    if (!names_.insert(joint.name).second) fail(keyword_line, "duplicate joint name '" + joint.name + "'");
    expect_open("'" + joint.name + "'");
    joint.offset = parse_offset();

    const Token ch = next("CHANNELS");
    if (ch.text != "CHANNELS") fail(ch.line, "expected CHANNELS, found '" + std::string(ch.text) + "'");
    const Token count_token = next("a channel count");
    const float count = number(count_token, "channel count");
    if (count < 0.0f || count > 6.0f || count != std::floor(count))
      fail(count_token.line, "channel count must be 0..6, found '" + std::string(count_token.text) + "'");
    for (int c = 0; c < static_cast<int>(count); ++c) {
      const Token t = next("a channel name");
      if (t.line != ch.line)
        fail(ch.line, "CHANNELS lists " + std::to_string(c) + " names, expected " + std::to_string(int(count)));
      const std::optional<BvhChannel> channel = channel_of(t.text);
      if (!channel) fail(t.line, "unknown channel '" + std::string(t.text) + "'");
      for (BvhChannel seen : joint.channels)
        if (seen == *channel) fail(t.line, "channel '" + std::string(t.text) + "' listed twice");
      joint.channels.push_back(*channel);
    }
    if (!at_end() && peek().line == ch.line)
      fail(ch.line, "CHANNELS lists more names than its count " + std::to_string(int(count)));

    const auto index = static_cast<std::int32_t>(motion.joints.size());
    motion.joints.push_back(std::move(joint));
    while (true) {
      const Token t = next("'}'");
      if (t.text == "}") return;
      if (t.text == "JOINT") {
        parse_joint(motion, index, t.line, depth + 1);
      } else if (t.text == "End") {
        const Token site = next("Site");
        if (site.text != "Site") fail(site.line, "expected 'End Site', found 'End " + std::string(site.text) + "'");
        if (motion.joints[index].has_end_site)
          fail(t.line, "joint '" + motion.joints[index].name + "' has a second End Site");
        expect_open("End Site");
        const glm::vec3 offset = parse_offset();
        const Token close = next("'}'");
        if (close.text != "}") fail(close.line, "expected '}' closing the End Site, found '" + std::string(close.text) + "'");
        motion.joints[index].has_end_site = true;
        motion.joints[index].end_site = offset;
      } else if (t.text == "MOTION") {
        fail(t.line, "unbalanced braces: MOTION before joint '" + motion.joints[index].name + "' is closed");
      } else {
        fail(t.line, "expected JOINT, End Site or '}', found '" + std::string(t.text) + "'");
      }
    }
  }

  void parse_frames(BvhMotion& motion, std::size_t frames_line) {
    std::uint32_t column = 0;
    for (BvhJoint& j : motion.joints) {
      j.first_channel = column;
      column += static_cast<std::uint32_t>(j.channels.size());
    }
    const std::size_t n = motion.channel_count;
    motion.values.resize(motion.frame_count * n);
    std::size_t f = 0;
    for (; line_ < lines_.size(); ++line_) {
      const Line& line = lines_[line_];
      if (f == motion.frame_count)
        fail(line.number, "more motion lines than 'Frames: " + std::to_string(motion.frame_count) + "'");
      if (line.tokens.size() != n)
        fail(line.number, "frame " + std::to_string(f) + " has " + std::to_string(line.tokens.size()) +
                              " values, expected " + std::to_string(n));
      for (std::size_t c = 0; c < n; ++c)
        motion.values[f * n + c] = number({line.tokens[c], line.number}, "frame " + std::to_string(f));
      ++f;
    }
    if (f != motion.frame_count)
      fail(f == 0 ? frames_line : last_line(), "'Frames: " + std::to_string(motion.frame_count) + "' but " +
                                                   std::to_string(f) + " motion lines");
  }

  std::string_view source_;
  std::vector<Line> lines_;
  std::unordered_set<std::string> names_;  // joint names seen, for the duplicate check
  std::size_t line_ = 0;   // cursor: line index into lines_
  std::size_t token_ = 0;  //         token index within it
};

glm::vec3 axis_of(BvhChannel c) {
  switch (c) {
    case BvhChannel::Xrotation: return {1, 0, 0};
    case BvhChannel::Yrotation: return {0, 1, 0};
    case BvhChannel::Zrotation: return {0, 0, 1};
    default: return {0, 0, 0};
  }
}

}  // namespace

const char* to_string(BvhChannel channel) {
  switch (channel) {
    case BvhChannel::Xposition: return "Xposition";
    case BvhChannel::Yposition: return "Yposition";
    case BvhChannel::Zposition: return "Zposition";
    case BvhChannel::Xrotation: return "Xrotation";
    case BvhChannel::Yrotation: return "Yrotation";
    case BvhChannel::Zrotation: return "Zrotation";
  }
  return "?";
}

std::size_t BvhMotion::end_site_count() const {
  std::size_t n = 0;
  for (const BvhJoint& j : joints) n += j.has_end_site ? 1 : 0;
  return n;
}

std::int32_t BvhMotion::find_joint(std::string_view name) const {
  for (std::size_t j = 0; j < joints.size(); ++j)
    if (joints[j].name == name) return static_cast<std::int32_t>(j);
  return -1;
}

glm::quat BvhMotion::local_rotation(std::size_t joint, std::size_t f) const {
  const BvhJoint& j = joints[joint];
  const float* v = values.data() + f * channel_count + j.first_channel;
  // Accumulated in double: the CMU files carry 1e-11 degree noise on idle channels and long chains of small
  // rotations; float would be enough for display but this keeps retargeting tests independent of rounding order.
  glm::dquat q(1.0, 0.0, 0.0, 0.0);
  for (std::size_t c = 0; c < j.channels.size(); ++c) {
    const glm::vec3 axis = axis_of(j.channels[c]);
    if (axis == glm::vec3(0.0f)) continue;
    q = q * glm::angleAxis(glm::radians(static_cast<double>(v[c])), glm::dvec3(axis));
  }
  return glm::quat(glm::normalize(q));
}

glm::mat3 BvhMotion::local_rotation_matrix(std::size_t joint, std::size_t f) const {
  return glm::mat3_cast(local_rotation(joint, f));
}

glm::vec3 BvhMotion::local_translation(std::size_t joint, std::size_t f) const {
  const BvhJoint& j = joints[joint];
  const float* v = values.data() + f * channel_count + j.first_channel;
  glm::vec3 t = j.offset;
  for (std::size_t c = 0; c < j.channels.size(); ++c) {
    switch (j.channels[c]) {
      case BvhChannel::Xposition: t.x += v[c]; break;
      case BvhChannel::Yposition: t.y += v[c]; break;
      case BvhChannel::Zposition: t.z += v[c]; break;
      default: break;
    }
  }
  return t;
}

glm::vec3 BvhMotion::root_translation(std::size_t f) const {
  if (joints.empty()) return glm::vec3(0.0f);
  return local_translation(0, f) - joints[0].offset;
}

std::vector<glm::vec3> BvhMotion::rest_positions() const {
  std::vector<glm::vec3> p(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j)
    p[j] = joints[j].parent < 0 ? joints[j].offset : p[joints[j].parent] + joints[j].offset;
  return p;
}

void BvhMotion::pose(std::size_t f, std::span<glm::quat> global_rotations,
                     std::span<glm::vec3> global_positions) const {
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const glm::quat local = local_rotation(j, f);
    const glm::vec3 t = local_translation(j, f);
    const std::int32_t p = joints[j].parent;
    if (p < 0) {
      global_rotations[j] = local;
      global_positions[j] = t;
    } else {
      global_rotations[j] = glm::normalize(global_rotations[p] * local);
      global_positions[j] = global_positions[p] + global_rotations[p] * t;
    }
  }
}

BvhMotion load_bvh_text(std::string_view text, std::string_view source_name) {
  return Parser(text, source_name).parse();
}

BvhMotion load_bvh_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path.string() + ": cannot open file: " + std::strerror(errno));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw LoadError(path.string() + ": read error: " + std::strerror(errno));
  return load_bvh_text(text, path.filename().string());
}

}  // namespace strata
