#include "components/skeleton.h"

#include <array>
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

}  // namespace

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

}  // namespace strata
