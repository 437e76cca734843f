#include "io/retarget_map_file.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "components/skeleton.h"
#include "io/load_error.h"

namespace strata {
namespace {

constexpr std::array<std::string_view, 21> kRetargetable = {
    "HumanoidRoot", "vl5",    "vt6",     "vc4",        "skullbase",          "l_sternoclavicular", "l_shoulder",
    "l_elbow",      "l_wrist", "l_hip",  "l_knee",     "l_ankle",            "l_midtarsal",        "r_sternoclavicular",
    "r_shoulder",   "r_elbow", "r_wrist", "r_hip",     "r_knee",             "r_ankle",            "r_midtarsal"};

}  // namespace

std::span<const std::string_view> retargetable_hanim_joints() { return kRetargetable; }

RetargetMapFile parse_retarget_map(std::string_view text, std::string_view source) {
  RetargetMapFile out;
  out.source = std::string(source);
  const auto known = retargetable_hanim_joints();
  std::istringstream in{std::string(text)};
  std::string line;
  int number = 0;
  auto fail = [&](int at, const std::string& why) -> void {
    throw LoadError(out.source + ":" + std::to_string(at) + ": " + why);
  };
  while (std::getline(in, line)) {
    ++number;
    if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream fields(line);
    std::vector<std::string> words;
    for (std::string w; fields >> w;) words.push_back(w);
    if (words.empty()) continue;
    if (words.size() != 2)
      fail(number, "expected 'BVH_JOINT H-ANIM_JOINT', got " + std::to_string(words.size()) + " words");
    RetargetMapRow row{words[0], words[1], number};
    const std::string_view canonical = canonical_joint_name(row.hanim);
    if (std::find(known.begin(), known.end(), canonical) == known.end()) {
      std::string list;
      for (const std::string_view k : known) {
        if (!list.empty()) list += ' ';
        list += k;
      }
      fail(number, "'" + row.hanim + "' is not a joint retargeting drives (one of: " + list + ")");
    }
    for (const RetargetMapRow& earlier : out.rows) {
      if (earlier.bvh == row.bvh)
        fail(number, "BVH joint '" + row.bvh + "' is mapped twice (first at line " + std::to_string(earlier.line) + ")");
      if (canonical_joint_name(earlier.hanim) == canonical)
        fail(number, "H-Anim joint '" + row.hanim + "' is mapped twice (first at line " +
                         std::to_string(earlier.line) + ")");
    }
    out.rows.push_back(std::move(row));
  }
  std::string missing;
  for (const char* need : {"HumanoidRoot", "l_hip", "l_knee", "l_ankle", "r_hip", "r_knee", "r_ankle"})
    if (std::none_of(out.rows.begin(), out.rows.end(),
                     [&](const RetargetMapRow& r) { return canonical_joint_name(r.hanim) == need; }))
      missing += std::string(missing.empty() ? "" : ", ") + need;
  if (!missing.empty())
    throw LoadError(out.source + ":" + std::to_string(number) + ": the map leaves out " + missing +
                    " (the root and both legs are needed to place the walker and lock its feet)");
  return out;
}

RetargetMapFile load_retarget_map_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path + ": cannot open file: " + std::strerror(errno));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw LoadError(path + ": read error: " + std::strerror(errno));
  return parse_retarget_map(text, path);
}

}  // namespace strata
