#include "apps/crowd_setup.h"

#include <charconv>
#include <stdexcept>

#include "io/hanim_loader.h"
#include "systems/animation_sample.h"

namespace strata::cli {

Rig load_rig(const std::string& skeleton_path) {
  HumanoidAsset asset = skeleton_path.empty() ? load_default_humanoid() : load_humanoid_file(skeleton_path);
  Rig rig;
  rig.name = asset.skeleton.name.empty() ? std::string("humanoid") : asset.skeleton.name;
  rig.skeleton = std::move(asset.skeleton);
  rig.clips = std::move(asset.clips);
  return rig;
}

int resolve_clip(const Rig& rig, const std::string& clip, bool rest) {
  if (rest || rig.clips.empty()) {
    if (!rest && !clip.empty() && clip != "all")
      throw std::invalid_argument("no clip '" + clip + "' in " + rig.skeleton.source + " (it has no animation)");
    return kRestPose;
  }
  if (clip.empty() || clip == "all") return kAllClips;
  for (std::size_t i = 0; i < rig.clips.size(); ++i)
    if (rig.clips[i].name == clip) return static_cast<int>(i);
  int index = -1;
  auto [end, ec] = std::from_chars(clip.data(), clip.data() + clip.size(), index);
  if (ec == std::errc() && end == clip.data() + clip.size() && index >= 0 &&
      static_cast<std::size_t>(index) < rig.clips.size())
    return index;
  std::string available;
  for (const AnimationClip& c : rig.clips) available += (available.empty() ? "" : ", ") + c.name;
  throw std::invalid_argument("no clip '" + clip + "' in " + rig.skeleton.source +
                              " (available: " + (available.empty() ? "none" : available) + ")");
}

}  // namespace strata::cli
