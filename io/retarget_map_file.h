#pragma once
// The retarget map file (`--retarget-map FILE`): which BVH joint drives which H-Anim joint, for a capture whose
// joint names Strata does not recognise (motion/bvh_naming.h) and whose shape the topology fallback cannot read.
// Plain text, one row per line, the BVH joint's name then the H-Anim joint's; '#' starts a comment:
//
//   # BVH joint    H-Anim joint
//   Pelvis         HumanoidRoot
//   L_Thigh        l_hip
//   L_Calf         l_knee
//   L_Foot         l_ankle
//
// The H-Anim side is one of the joints retargeting drives (retargetable_hanim_joints(); 1.1 or 2019 spelling);
// HumanoidRoot and both legs' hip, knee and ankle are required, the rest optional. Bone directions (which child
// each row aims at) and the file's axes are worked out from the rows, so the file stays a list of names.
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace strata {

struct RetargetMapRow {
  std::string bvh;
  std::string hanim;  // as written (2019 names accepted)
  int line = 0;       // 1-based, for messages
};

struct RetargetMapFile {
  std::string source;
  std::vector<RetargetMapRow> rows;
};

// The H-Anim joints a retarget map may drive, in the 1.1 spelling.
std::span<const std::string_view> retargetable_hanim_joints();

// Parses the text. Throws LoadError "SOURCE:LINE: reason" (not two names, an H-Anim joint retargeting does not
// drive, a joint named twice, a required joint missing); nothing is returned half-read.
RetargetMapFile parse_retarget_map(std::string_view text, std::string_view source);
RetargetMapFile load_retarget_map_file(const std::string& path);

}  // namespace strata
