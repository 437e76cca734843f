#include "components/skeleton.h"

#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <utility>

namespace strata {
namespace {

// 2019 name -> 1.1 name. Only pairs where ISO 19774-1:2019 renamed the same anatomical joint. The 2019 finger and
// toe chains (carpometacarpal_*, tarsometatarsal_*, ...) are left alone: their one-to-one correspondence with
// 1.1's thumb1/index0/metatarsal is not something we could verify, and a wrong alias is worse than none.
constexpr std::array<std::pair<std::string_view, std::string_view>, 9> kRenamed2019 = {{
    {"humanoid_root", "HumanoidRoot"},
    {"l_talocrural", "l_ankle"},
    {"r_talocrural", "r_ankle"},
    {"l_radiocarpal", "l_wrist"},
    {"r_radiocarpal", "r_wrist"},
    {"l_talocalcaneonavicular", "l_subtalar"},
    {"r_talocalcaneonavicular", "r_subtalar"},
    {"l_transversetarsal", "l_midtarsal"},
    {"r_transversetarsal", "r_midtarsal"},
}};

// Stems (after the l_/r_ prefix) that only the 2019 hand and foot chains use.
constexpr std::array<std::string_view, 12> k2019Stems = {
    "carpometacarpal_",   "metacarpophalangeal_", "carpal_interphalangeal_", "carpal_proximal_interphalangeal_",
    "carpal_distal_interphalangeal_", "midcarpal_", "tarsometatarsal_", "metatarsophalangeal_",
    "tarsal_interphalangeal_", "tarsal_proximal_interphalangeal_", "tarsal_distal_interphalangeal_",
    "cuneonavicular_",
};

// H-Anim 1.1's joint names, the side prefix taken off the sided ones (ISO 19774 1.1, the LOA-4 list).
constexpr std::array<std::string_view, 19> kSidedStems11 = {
    "hip",      "knee",  "ankle", "subtalar", "midtarsal", "metatarsal", "sternoclavicular", "acromioclavicular",
    "shoulder", "elbow", "wrist", "thumb",    "index",     "middle",     "ring",             "pinky",
    "eyelid_joint", "eyeball_joint", "eyebrow_joint"};
constexpr std::array<std::string_view, 4> kUnsided11 = {"HumanoidRoot", "sacroiliac", "skullbase", "temporomandibular"};

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

}  // namespace

bool is_hanim_joint_name(std::string_view name) {
  if (is_hanim2019_name(name)) return true;
  for (std::string_view n : kUnsided11)
    if (name == n) return true;
  // The vertebrae: vl1..vl5, vt1..vt12, vc1..vc7.
  for (const auto& [prefix, count] : {std::pair<std::string_view, int>{"vl", 5}, {"vt", 12}, {"vc", 7}})
    if (name.starts_with(prefix) && all_digits(name.substr(2)) && name[2] != '0' && name.size() <= 4)
      return std::stoi(std::string(name.substr(2))) <= count;
  if (name.size() < 3 || !(name.starts_with("l_") || name.starts_with("r_"))) return false;
  const std::string_view stem = name.substr(2);
  for (std::string_view s : kSidedStems11) {
    if (!stem.starts_with(s)) continue;
    const std::string_view rest = stem.substr(s.size());
    if (rest.empty()) return s != "thumb" && s != "index" && s != "middle" && s != "ring" && s != "pinky";
    // Fingers carry a digit: thumb1..3, the others 0..3.
    if (rest.size() == 1 && (s == "thumb" ? (rest[0] >= '1' && rest[0] <= '3')
                                          : (s == "index" || s == "middle" || s == "ring" || s == "pinky") &&
                                                rest[0] >= '0' && rest[0] <= '3'))
      return true;
  }
  return false;
}

const char* to_string(JointNaming naming) {
  switch (naming) {
    case JointNaming::HAnim1_1: return "H-Anim 1.1";
    case JointNaming::HAnim2019: return "HAnim 2019";
    case JointNaming::Mixed: return "mixed";
  }
  return "unknown";
}

std::string_view canonical_joint_name(std::string_view name) {
  for (const auto& [from, to] : kRenamed2019)
    if (name == from) return to;
  return name;
}

bool is_hanim2019_name(std::string_view name) {
  if (canonical_joint_name(name) != name) return true;
  if (name.size() > 2 && (name.starts_with("l_") || name.starts_with("r_"))) {
    const std::string_view stem = name.substr(2);
    if (stem == "calcaneocuboid") return true;
    for (std::string_view s : k2019Stems)
      if (stem.starts_with(s)) return true;
  }
  return false;
}

std::int32_t Skeleton::find_joint(std::string_view name) const {
  for (std::size_t j = 0; j < joint_names.size(); ++j)
    if (joint_names[j] == name) return static_cast<std::int32_t>(j);
  for (std::size_t j = 0; j < source_joint_names.size(); ++j)
    if (source_joint_names[j] == name) return static_cast<std::int32_t>(j);
  // A 2019 name asked of a 1.1 skeleton (or the reverse through joint_names above) still finds the joint.
  const std::string_view canonical = canonical_joint_name(name);
  if (canonical != name)
    for (std::size_t j = 0; j < joint_names.size(); ++j)
      if (joint_names[j] == canonical) return static_cast<std::int32_t>(j);
  return -1;
}

std::int32_t Skeleton::find_site(std::string_view name) const {
  for (std::size_t s = 0; s < sites.size(); ++s)
    if (sites[s].name == name) return static_cast<std::int32_t>(s);
  return -1;
}

int Skeleton::depth(std::int32_t joint) const {
  if (joint < 0 || static_cast<std::size_t>(joint) >= parents.size()) return -1;
  int d = 0;
  // parents[j] < j bounds the walk even on a malformed skeleton: stop after joint_count() steps regardless.
  for (std::int32_t j = joint; parents[static_cast<std::size_t>(j)] >= 0 && d <= static_cast<int>(parents.size());
       j = parents[static_cast<std::size_t>(j)])
    ++d;
  return d;
}

RestStature rest_stature(const Skeleton& skeleton) {
  RestStature out;
  float low = std::numeric_limits<float>::max();
  float high = std::numeric_limits<float>::lowest();
  if (!skeleton.skin_points.empty()) {
    for (const glm::vec3& p : skeleton.skin_points) {
      low = std::min(low, p.y);
      high = std::max(high, p.y);
    }
    out.metres = high - low;
    out.source = "skin";
    return out;
  }
  for (const glm::vec3& c : skeleton.centers) {
    low = std::min(low, c.y);
    high = std::max(high, c.y);
  }
  // A site at exactly the origin is one written without a translation (X3D's default), not a landmark.
  for (const SkeletonSite& s : skeleton.sites)
    if (s.position != glm::vec3(0.0f)) low = std::min(low, s.position.y);
  if (skeleton.centers.empty()) return out;
  if (const std::int32_t tip = skeleton.find_site("skull_tip"); tip >= 0) {
    out.metres = skeleton.sites[static_cast<std::size_t>(tip)].position.y - low;
    out.source = "skull_tip";
  } else {
    out.metres = high + 0.13f - low;
  }
  return out;
}

}  // namespace strata
