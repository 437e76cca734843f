#pragma once
// Private to io/: the two format readers behind io/hanim_loader.h and the pieces they share.
#include <string>

#include "io/hanim_loader.h"
#include "io/xml_util.h"

namespace strata::detail {

// Reads the <X3D> (or bare <HAnimHumanoid>) document. Throws LoadError.
HumanoidAsset read_x3d_humanoid(const xml::Document& doc);
// Reads the paper-era <Humanoid> document. Throws LoadError.
HumanoidAsset read_paper_humanoid(const xml::Document& doc);

// Fills joint_names (internal 1.1 vocabulary) and naming from source_joint_names. A name whose 1.1 alias is
// already taken by another joint of the same file keeps its source spelling (and gets a warning), so internal
// names stay unique.
void finalize_joint_names(Skeleton& skeleton);

// Rejects "lower > upper" on any axis of a limit read from a file. skeleton.h reserves lower > upper for "this axis
// is unlimited", but a file that writes limitx="2 -1" meant a range and swapped it by mistake; silently turning
// that into "no limit" would hide the error, so both readers fail instead.
void check_limits(const xml::Document& doc, pugi::xml_node node, const JointLimits& limits);

}  // namespace strata::detail
