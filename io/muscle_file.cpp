#include "io/muscle_file.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "data/embedded.h"
#include "io/load_error.h"

namespace strata {
namespace {

using Json = nlohmann::json;

constexpr std::uint32_t kMaxPointsPerLine = 64;
constexpr float kMaxOffset = 1.0f;     // metres; an attachment further than this from its joint is a typo
constexpr float kMaxMagnitude = 0.5f;  // metres per unit force factor

class MuscleParser {
 public:
  MuscleParser(std::string_view source, const Skeleton& skeleton) : source_(source), skeleton_(skeleton) {}

  MuscleSet parse(std::string_view text) {
    Json root;
    try {
      root = Json::parse(text.begin(), text.end());
    } catch (const Json::exception& e) {
      // A syntax error's message carries "at line L, column C"; a number too large for a double is an
      // out_of_range error, also reported here as bad input rather than escaping as another exception type.
      fail("", std::string("invalid JSON: ") + e.what());
    }
    if (!root.is_object()) fail("", "expected a JSON object at the top level");
    check_keys(root, "", {"_doc", "format", "version", "min_length_ratio", "muscles"});
    if (!root.contains("format") || root["format"] != "strata-muscles")
      fail("format", "expected \"strata-muscles\"");
    if (!root.contains("version") || !root["version"].is_number_integer() || root["version"].get<int>() != 1)
      fail("version", "expected 1");
    MuscleSet set;
    set.source = std::string(source_);
    if (root.contains("min_length_ratio")) {
      set.min_length_ratio = number(root["min_length_ratio"], "min_length_ratio");
      if (!(set.min_length_ratio >= 0.05f && set.min_length_ratio <= 1.0f))
        fail("min_length_ratio", "must lie in [0.05, 1]");
    }
    if (!root.contains("muscles") || !root["muscles"].is_array() || root["muscles"].empty())
      fail("muscles", "expected a non-empty array of muscles");
    const Json& muscles = root["muscles"];
    for (std::size_t i = 0; i < muscles.size(); ++i) {
      where_ = "muscles[" + std::to_string(i) + "]";
      const Json& m = muscles[i];
      if (!m.is_object()) fail("", "expected an object");
      if (!m.contains("name") || !m["name"].is_string() || m["name"].get<std::string>().empty())
        fail("name", "expected a non-empty string");
      const std::string name = m["name"].get<std::string>();
      where_ += " (" + name + ")";
      if (set.find(name) >= 0) fail("name", "duplicate muscle name");
      ActionLine line = m.contains("mirror_of") ? mirrored(m, set) : parse_line(m);
      line.name = name;
      if (set.point_count + line.point_count > kMaxMusclePoints) fail("control_points", "more than 2048 in the file");
      line.first_point = set.point_count;
      set.point_count += line.point_count;
      set.lines.push_back(std::move(line));
    }
    where_.clear();
    for (const ActionLine& line : set.lines) {
      std::vector<float> lengths(line.point_count);
      action_line_point_lengths(line.origin_rest, line.insertion_rest, line.point_count, lengths.data());
      set.rest_length.insert(set.rest_length.end(), lengths.begin(), lengths.end());
    }
    return set;
  }

 private:
  [[noreturn]] void fail(const std::string& field, const std::string& why) const {
    std::string at = where_;
    if (!field.empty()) at += (at.empty() ? "" : ".") + field;
    throw LoadError(std::string(source_) + (at.empty() ? "" : ": " + at) + ": " + why);
  }

  void check_keys(const Json& object, const std::string& field, std::initializer_list<const char*> allowed) const {
    for (const auto& [key, value] : object.items()) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || key == a;
      if (!ok) fail(field.empty() ? key : field + "." + key, "unknown key");
    }
  }

  float number(const Json& j, const std::string& field) const {
    if (!j.is_number()) fail(field, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v) || std::fabs(v) > 1e6) fail(field, "not a finite number");
    return static_cast<float>(v);
  }

  glm::vec3 vec3(const Json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3) fail(field, "expected an array of 3 numbers");
    return {number(j[0], field), number(j[1], field), number(j[2], field)};
  }

  std::int32_t joint(const Json& j, const std::string& field) const {
    if (!j.is_string()) fail(field, "expected a joint name");
    const std::int32_t index = skeleton_.find_joint(j.get<std::string>());
    if (index < 0) fail(field, "no joint '" + j.get<std::string>() + "' in " + skeleton_.source);
    return index;
  }

  // One end: the joint it rides on and its rest position.
  std::pair<std::int32_t, glm::vec3> attachment(const Json& m, const char* key) const {
    if (!m.contains(key) || !m[key].is_object()) fail(key, "expected an object with 'joint' and 'offset'");
    const Json& a = m[key];
    const std::string f = key;
    check_keys(a, f, {"joint", "offset_from", "offset"});
    if (!a.contains("joint")) fail(f + ".joint", "missing");
    const std::int32_t rides = joint(a["joint"], f + ".joint");
    const std::int32_t from = a.contains("offset_from") ? joint(a["offset_from"], f + ".offset_from") : rides;
    const glm::vec3 offset = a.contains("offset") ? vec3(a["offset"], f + ".offset") : glm::vec3(0.0f);
    if (glm::length(offset) > kMaxOffset) fail(f + ".offset", "further than 1 m from its joint");
    return {rides, skeleton_.centers[static_cast<std::size_t>(from)] + offset};
  }

  ActionLine parse_line(const Json& m) const {
    check_keys(m, "", {"name", "origin", "insertion", "outward", "control_points", "parts", "radius", "forces"});
    ActionLine line;
    std::tie(line.origin_joint, line.origin_rest) = attachment(m, "origin");
    std::tie(line.insertion_joint, line.insertion_rest) = attachment(m, "insertion");
    const glm::vec3 axis = line.insertion_rest - line.origin_rest;
    if (glm::length(axis) < 1e-3f) fail("insertion", "less than 1 mm from the origin at rest");
    if (!m.contains("outward")) fail("outward", "missing");
    const glm::vec3 outward = vec3(m["outward"], "outward");
    const glm::vec3 z = glm::normalize(axis);
    const glm::vec3 across = outward - glm::dot(outward, z) * z;
    if (glm::length(outward) < 1e-6f || glm::length(across) < 0.1f * glm::length(outward))
      fail("outward", "must point away from the action line (it is zero or nearly parallel to it)");
    line.outward_rest = glm::normalize(across);
    if (!m.contains("control_points") || !m["control_points"].is_number_integer())
      fail("control_points", "expected an integer");
    const auto points = m["control_points"].get<std::int64_t>();
    if (points < 2 || points > kMaxPointsPerLine) fail("control_points", "must lie in [2, 64]");
    line.point_count = static_cast<std::uint32_t>(points);
    if (!m.contains("parts") || !m["parts"].is_array() || m["parts"].empty())
      fail("parts", "expected a non-empty array of skin part names");
    for (const Json& p : m["parts"]) {
      if (!p.is_string() || p.get<std::string>().empty()) fail("parts", "expected part names");
      line.parts.push_back(p.get<std::string>());
    }
    if (!m.contains("radius")) fail("radius", "missing");
    line.radius = number(m["radius"], "radius");
    if (!(line.radius > 0.0f && line.radius <= 0.5f)) fail("radius", "must lie in (0, 0.5] m");
    if (!m.contains("forces") || !m["forces"].is_array() || m["forces"].size() != line.point_count)
      fail("forces", "expected one list of force vectors per control point (" + std::to_string(points) + ")");
    for (std::size_t k = 0; k < line.point_count; ++k) {
      const Json& list = m["forces"][k];
      const std::string f = "forces[" + std::to_string(k) + "]";
      if (!list.is_array()) fail(f, "expected a list of [dx, dy, dz, magnitude]");
      std::vector<ForceVector> vectors;
      for (std::size_t a = 0; a < list.size(); ++a) {
        const std::string fa = f + "[" + std::to_string(a) + "]";
        const Json& v = list[a];
        if (!v.is_array() || v.size() != 4) fail(fa, "expected [dx, dy, dz, magnitude]");
        const glm::vec3 d{number(v[0], fa), number(v[1], fa), number(v[2], fa)};
        const float magnitude = number(v[3], fa);
        if (glm::length(d) < 1e-6f) fail(fa, "zero direction");
        if (std::fabs(magnitude) > kMaxMagnitude) fail(fa, "magnitude beyond 0.5 m");
        vectors.push_back({glm::normalize(d), magnitude});
      }
      line.forces.push_back(std::move(vectors));
    }
    return line;
  }

  // l_knee <-> r_knee for joints, lThigh <-> rThigh for parts; other names are their own mirror.
  static std::string swap_side(const std::string& name, bool joint) {
    std::string out = name;
    const bool sided = joint ? name.size() > 2 && name[1] == '_' : name.size() > 1;
    if (sided && (name[0] == 'l' || name[0] == 'r')) out[0] = name[0] == 'l' ? 'r' : 'l';
    return out;
  }

  ActionLine mirrored(const Json& m, const MuscleSet& set) const {
    check_keys(m, "", {"name", "mirror_of"});
    if (!m["mirror_of"].is_string()) fail("mirror_of", "expected the name of an earlier muscle");
    const int source = set.find(m["mirror_of"].get<std::string>());
    if (source < 0) fail("mirror_of", "no earlier muscle '" + m["mirror_of"].get<std::string>() + "'");
    ActionLine line = set.lines[static_cast<std::size_t>(source)];
    const glm::vec3 flip(-1.0f, 1.0f, 1.0f);
    auto mirror_end = [&](std::int32_t& joint_index, glm::vec3& rest, const char* field) {
      const std::string name = swap_side(skeleton_.joint_names[static_cast<std::size_t>(joint_index)], true);
      joint_index = skeleton_.find_joint(name);
      if (joint_index < 0) fail(std::string("mirror_of.") + field, "no mirrored joint '" + name + "'");
      rest *= flip;
    };
    mirror_end(line.origin_joint, line.origin_rest, "origin");
    mirror_end(line.insertion_joint, line.insertion_rest, "insertion");
    line.outward_rest *= flip;
    for (std::string& part : line.parts) part = swap_side(part, false);
    for (auto& vectors : line.forces)
      for (ForceVector& f : vectors) f.direction.x = -f.direction.x;
    return line;
  }

  std::string_view source_;
  const Skeleton& skeleton_;
  std::string where_;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path + ": cannot open file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

MuscleSet parse_muscles(std::string_view json, std::string_view source, const Skeleton& skeleton) {
  return MuscleParser(source, skeleton).parse(json);
}

MuscleSet load_muscle_file(const std::string& path, const Skeleton& skeleton) {
  return parse_muscles(read_file(path), path, skeleton);
}

MuscleSet default_muscles(const Skeleton& skeleton) {
  const std::optional<std::string_view> text = embedded::find("data/muscles.json");
  if (!text) throw LoadError("data/muscles.json: not embedded in this build");
  return parse_muscles(*text, "data/muscles.json", skeleton);
}

MuscleGains parse_muscle_overrides(std::string_view json, std::string_view source, const MuscleSet& set) {
  const std::string src(source);
  Json root;
  try {
    root = Json::parse(json.begin(), json.end());
  } catch (const Json::exception& e) {
    throw LoadError(src + ": invalid JSON: " + e.what());
  }
  if (!root.is_object()) throw LoadError(src + ": expected a JSON object at the top level");
  auto gain = [&](const Json& j, const std::string& where) {
    if (!j.is_number()) throw LoadError(src + ": " + where + ": expected a number");
    const double g = j.get<double>();
    if (!std::isfinite(g) || g < 0.0 || g > 100.0) throw LoadError(src + ": " + where + ": gain must lie in [0, 100]");
    return static_cast<float>(g);
  };
  MuscleGains gains;
  gains.line.assign(set.lines.size(), 1.0f);
  for (const auto& [key, value] : root.items()) {
    if (key == "_doc") continue;
    if (key == "gain") {
      gains.global = gain(value, "gain");
    } else if (key == "muscles") {
      if (!value.is_object()) throw LoadError(src + ": muscles: expected an object of name: gain");
      for (const auto& [name, g] : value.items()) {
        const int m = set.find(name);
        if (m < 0) throw LoadError(src + ": muscles." + name + ": no such muscle in " + set.source);
        gains.line[static_cast<std::size_t>(m)] = gain(g, "muscles." + name);
      }
    } else {
      throw LoadError(src + ": " + key + ": unknown key");
    }
  }
  return gains;
}

MuscleGains load_muscle_overrides(const std::string& path, const MuscleSet& set) {
  return parse_muscle_overrides(read_file(path), path, set);
}

}  // namespace strata
