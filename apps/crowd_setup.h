#pragma once
// What `strata crowd` and `strata view` share: loading the rig they animate and choosing its clip.
#include <string>

#include "components/rig.h"

namespace strata::cli {

// Loads FILE (or the embedded default skeleton when empty) into a Rig. Throws LoadError.
Rig load_rig(const std::string& skeleton_path);
// Resolves --clip (a clip name or index; empty = the rig's first clip) to an index; -1 = rest pose.
// Throws std::invalid_argument naming the clip and listing the available ones when it does not exist.
int resolve_clip(const Rig& rig, const std::string& clip, bool rest);

}  // namespace strata::cli
