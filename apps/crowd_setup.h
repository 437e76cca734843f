#pragma once
// What `strata crowd` and `strata view` share: loading the rig they animate and choosing its clip.
#include <string>

#include "components/rig.h"

namespace strata::cli {

// Loads FILE (or the embedded default skeleton when empty) into a Rig. Throws LoadError.
Rig load_rig(const std::string& skeleton_path);
// Resolves --clip to a walker clip selector: a clip name or index, "all" (every clip at once, as an X3D browser
// plays a scene's TimeSensors together; the default when the rig has clips), or kRestPose when `rest` is set
// or the rig has no clips.
// Throws std::invalid_argument naming the clip and listing the available ones when it does not exist.
int resolve_clip(const Rig& rig, const std::string& clip, bool rest);

}  // namespace strata::cli
