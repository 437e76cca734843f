#include "io/hanim_loader.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_set>

#include "data/embedded.h"
#include "io/hanim_readers.h"

namespace strata {
namespace detail {

void finalize_joint_names(Skeleton& skeleton) {
  bool any_2019 = false;
  bool any_11_only = false;
  skeleton.joint_names.clear();
  skeleton.joint_names.reserve(skeleton.source_joint_names.size());
  std::unordered_set<std::string> taken(skeleton.source_joint_names.begin(), skeleton.source_joint_names.end());
  for (const std::string& source : skeleton.source_joint_names) {
    const std::string_view canonical = canonical_joint_name(source);
    if (is_hanim2019_name(source)) {
      any_2019 = true;
    } else if (canonical_joint_name(source) == source) {
      // A 1.1 name that 2019 renamed (HumanoidRoot, l_ankle, ...) marks the file as 1.1; shared names do not.
      for (const char* renamed : {"HumanoidRoot", "l_ankle", "r_ankle", "l_wrist", "r_wrist", "l_subtalar",
                                  "r_subtalar", "l_midtarsal", "r_midtarsal"})
        if (source == renamed) any_11_only = true;
    }
    if (canonical != source && taken.count(std::string(canonical)) != 0) {
      skeleton.warnings.push_back(skeleton.source + ": joint '" + source + "' keeps its 2019 name because '" +
                                  std::string(canonical) + "' is also in the file");
      skeleton.joint_names.push_back(source);
    } else {
      skeleton.joint_names.emplace_back(canonical);
      taken.insert(std::string(canonical));
    }
  }
  skeleton.naming = any_2019 ? (any_11_only ? JointNaming::Mixed : JointNaming::HAnim2019) : JointNaming::HAnim1_1;
}

void check_limits(const xml::Document& doc, pugi::xml_node node, const JointLimits& limits) {
  static constexpr const char* kAxis = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (limits.lower[a] > limits.upper[a]) {
      std::ostringstream msg;
      msg << "limit about " << kAxis[a] << " has lower " << limits.lower[a] << " > upper " << limits.upper[a];
      doc.fail(node, msg.str());
    }
  }
}

}  // namespace detail

HumanoidAsset load_humanoid_text(std::string_view text, std::string_view source_name) {
  const xml::Document doc(text, source_name);
  const pugi::xml_node root = doc.root();
  const std::string_view tag = root.name();
  HumanoidAsset asset;
  if (tag == "X3D" || tag == "HAnimHumanoid") {
    asset = detail::read_x3d_humanoid(doc);
  } else if (tag == "Humanoid") {
    asset = detail::read_paper_humanoid(doc);
  } else {
    doc.fail(root, "unknown root element: expected <X3D>, <HAnimHumanoid> or <Humanoid>");
  }
  return asset;
}

HumanoidAsset load_humanoid_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path.string() + ": cannot open file: " + std::strerror(errno));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw LoadError(path.string() + ": read error: " + std::strerror(errno));
  return load_humanoid_text(text, path.string());
}

HumanoidAsset load_default_humanoid() {
  static constexpr std::string_view kName = "data/default_skeleton.x3d";
  const std::optional<std::string_view> text = embedded::find(kName);
  if (!text) throw LoadError(std::string("<embedded>/") + std::string(kName) + ": not compiled into the library");
  return load_humanoid_text(*text, std::string("<embedded>/") + std::string(kName));
}

Rig to_rig(HumanoidAsset asset) {
  Rig rig;
  rig.name = asset.skeleton.name.empty() ? std::string("humanoid") : asset.skeleton.name;
  rig.skeleton = std::move(asset.skeleton);
  rig.clips = std::move(asset.clips);
  return rig;
}

}  // namespace strata
