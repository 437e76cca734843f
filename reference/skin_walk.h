#pragma once
// The walk half of `strata report skin`, shared with tests/skin_walk_test.cpp so the test asserts exactly what
// the report prints: one walker of the default crowd setup walks for `seconds`, and every frame its skin at one
// body level is measured against the rest mesh (rig/skin_metrics.h), in humanoid space.
#include <cstddef>
#include <span>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/rig.h"
#include "components/skin_layout.h"

namespace strata {

struct WalkSkinMetrics {
  std::size_t frames = 0;
  std::size_t inverted_triangles = 0;  // worst frame
  int worst_frame = -1;                // first frame with that count (0-based), -1 when no triangle inverts
  double seam_gap_max_m = 0.0;         // over all frames
  std::size_t nan_count = 0;           // summed over all frames
};

// `rig` provides the skeleton (its body, if any, is replaced by `level` alone). Throws std::invalid_argument when
// the rig cannot walk (Crowd::walk_unavailable()).
// `mode` skins with the reference in that mode (centres: per vertex of `level`, for CentresOfRotation).
WalkSkinMetrics measure_walk_skin(const Rig& rig, const BodyLevel& level, float seconds, float fps,
                                  SkinningMode mode = SkinningMode::Linear, std::span<const glm::vec3> centres = {});

}  // namespace strata
