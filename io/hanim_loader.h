#pragma once
// Loading H-Anim humanoids from XML: the X3D H-Anim encoding (HAnimHumanoid/HAnimJoint/HAnimSegment/HAnimSite,
// H-Anim 1.1 and 2019 names) and the paper-era simple XML (Humanoid/Joint/Segment/Site with limitx/y/z).
// The format is detected from the root element. Errors throw LoadError (io/load_error.h).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "components/animation_clip.h"
#include "components/rig.h"
#include "components/skeleton.h"
#include "io/load_error.h"

namespace strata {

enum class HumanoidFormat { X3D, PaperXml };

struct HumanoidAsset {
  Skeleton skeleton;
  std::vector<AnimationClip> clips;  // X3D interpolator animations routed to joints, one per TimeSensor
  HumanoidFormat format = HumanoidFormat::X3D;
};

// Loads a file; the format is detected from its root element (<X3D>/<HAnimHumanoid> or <Humanoid>).
HumanoidAsset load_humanoid_file(const std::filesystem::path& path);
// Loads from memory; `source_name` is used in error messages and Skeleton::source.
HumanoidAsset load_humanoid_text(std::string_view text, std::string_view source_name);
// The shipped default: the paper's 25-joint skeleton (data/default_skeleton.x3d, embedded in the library).
HumanoidAsset load_default_humanoid();

// The shared rig of a loaded humanoid: its skeleton and clips, named after the humanoid.
Rig to_rig(HumanoidAsset asset);

}  // namespace strata
