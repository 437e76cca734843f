#pragma once
// Muscle system (frame script step 4, after FK, before skinning): for every walker and action line, places the
// origin and insertion on their joints (skinning matrices S = F A^-1 applied to the rest attachment points),
// interpolates the inner control points, and writes each point's position, local frame, length and force factor
// into the walker's muscle columns (components/walker.h). The force model is in components/muscle.h:
//     f = L / max(l, min_length_ratio * L) - 1      (0 at rest, > 0 shortened, < 0 lengthened, never inf/NaN)
// The skinning kernel turns the factors into a displacement along each bound vertex's skinned normal.
//
//   reads:  muscle set (lines, attachments, rest lengths), skinning (joints*12)
//   writes: muscle_point (P*3), muscle_frame (P*6), muscle_length (P), muscle_force (P)   (P = set.point_count)
//
// Walkers run in parallel (oneTBB) and each writes only its own lane, so the output is the same for any thread
// count. Control points are few (60 for the default set), so the loop is per walker, scalar; vectorising across
// walkers was not worth its complexity at about 4 % of the skinning step's cost (0.69 ms against 19.2 ms for 1,000 walkers; docs/skin.md).
#include "components/muscle.h"
#include "ecs/column_view.h"
#include "systems/job.h"

namespace strata {

struct MuscleJob {
  const MuscleSet* set = nullptr;        // lines (joints, rest attachment points, control point ranges)
  ColumnView<const float> skinning;      // S(j) per joint, 3x4 column-major (component j*12 + k)
  ColumnView<float> point;               // P*3: control point positions, humanoid space
  ColumnView<float> frame;               // P*6: local frame axes y (outward) then z (along the line)
  ColumnView<float> length;              // P: the point's length l (mean of its adjacent segments)
  ColumnView<float> force;               // P: force factor f = L / max(l, ratio L) - 1

  // Set given with P >= 2 control points and one rest length each; every line's points within P, at most 64
  // per line, joints inside the skinning view; all views with the same rows and their widths; outputs
  // overlapping neither each other nor the input.
  bool validate() const;
  // Every walker (oneTBB chunks; each writes only its own lane).
  bool run() const;
  // Walker `walker` only (tests and tools); false when invalid or out of range.
  bool run_walker(std::size_t walker) const;
};

// The job over every walker of `walkers` (a walker table made with set.point_count muscle points).
MuscleJob make_muscle_job(const MuscleSet& set, SoaTable& walkers);

}  // namespace strata
