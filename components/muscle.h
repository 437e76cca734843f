#pragma once
// The muscle layer's immutable rig data (the paper, section 4): each muscle is an action line, a polyline of
// control points whose first point (origin) and last point (insertion) ride on joints and whose inner points are
// interpolated linearly between them every frame. Each control point carries force vectors in the muscle's local
// frame; the force grows as the point's segment shortens and relaxes as it lengthens, and bound skin vertices
// move along their normals accordingly.
//
// Local frame of a control point (right-handed): z runs along the action line from origin to insertion, y is the
// muscle's outward direction (the side its belly bulges to, e.g. anterior for the biceps) made perpendicular to
// z, and x = y cross z. At rest the outward direction is the file's `outward`; per frame it turns with the
// origin joint.
//
// Force model (systems/muscle.h): a control point's length l is the mean of its adjacent segments' lengths and
// L that length at rest; its force factor is
//     f = L / max(l, min_length_ratio * L) - 1
// so f = 0 exactly at rest, f > 0 (grows like 1/l) when the muscle shortens, f < 0 when it lengthens, and a
// zero-length segment clamps to 1 / min_length_ratio - 1 instead of dividing by zero. A bound vertex moves along
// its skinned normal by  d = scale * sum_i c_i f_i  over its three nearest control points (rig/muscle_binding.h
// derives c_i from the force vectors' magnitudes and the binding weights).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace strata {

struct ForceVector {
  glm::vec3 direction{0.0f, 1.0f, 0.0f};  // unit, in the control point's local frame
  float magnitude = 0.0f;                 // metres of skin displacement per unit force factor
};

struct ActionLine {
  std::string name;                      // e.g. "l_biceps"
  std::int32_t origin_joint = -1;        // skeleton joint indices the ends ride on
  std::int32_t insertion_joint = -1;
  glm::vec3 origin_rest{0.0f};           // rest (humanoid) space: joint centre + the file's offset
  glm::vec3 insertion_rest{0.0f};
  glm::vec3 outward_rest{0.0f, 0.0f, 1.0f};  // unit, perpendicular to the rest line
  std::uint32_t first_point = 0;         // index of this line's first control point in the set
  std::uint32_t point_count = 0;         // >= 2 (origin, inner points, insertion)
  std::vector<std::vector<ForceVector>> forces;  // per control point
  std::vector<std::string> parts;        // skin parts whose vertices may bind to this line
  float radius = 0.08f;                  // binding reach from the rest line (m); the effect fades to 0 there
};

// Upper bound on a set's control points (the skinning kernel keeps one walker's force factors on its stack).
inline constexpr std::uint32_t kMaxMusclePoints = 2048;

struct MuscleSet {
  std::string source;  // file it came from, for messages
  std::vector<ActionLine> lines;
  std::uint32_t point_count = 0;     // control points over all lines
  float min_length_ratio = 0.5f;     // l is clamped to at least this fraction of L (see above)
  std::vector<float> rest_length;    // per control point: L (computed by systems/muscle.h at load)

  // Index of the line called `name`, or -1.
  int find(const std::string& name) const {
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (lines[i].name == name) return static_cast<int>(i);
    return -1;
  }
};

// Control point k of a line with `count` points sits at origin + (k / (count - 1)) * (insertion - origin).
inline glm::vec3 action_line_point(const glm::vec3& origin, const glm::vec3& insertion, std::uint32_t k,
                                   std::uint32_t count) {
  const float t = static_cast<float>(k) / static_cast<float>(count - 1);
  return origin + t * (insertion - origin);
}

// Each control point's length l (the mean of its adjacent segments' lengths; an end point has one). The muscle
// system and the loader (for the rest lengths L) both call this one function, so the rest pose reproduces L bit
// for bit and f = L / l - 1 is exactly 0 there.
inline void action_line_point_lengths(const glm::vec3& origin, const glm::vec3& insertion, std::uint32_t count,
                                      float* lengths) {
  float previous = 0.0f;
  glm::vec3 a = action_line_point(origin, insertion, 0, count);
  for (std::uint32_t k = 0; k + 1 < count; ++k) {
    const glm::vec3 b = action_line_point(origin, insertion, k + 1, count);
    const float segment = glm::length(b - a);
    lengths[k] = k == 0 ? segment : 0.5f * (previous + segment);
    previous = segment;
    a = b;
  }
  lengths[count - 1] = previous;
}

// Muscle binding of one body level (rig/muscle_binding.h): each bound vertex is attached to one action line and
// its nearest three control points (fewer when the line has fewer), with inverse-distance weights summing to 1,
// and each control point's weight spread over its force vectors inversely to the angle between the force vector
// and the direction from the control point to the vertex.
inline constexpr int kMusclePointsPerVertex = 3;
struct MuscleBinding {
  std::vector<std::uint32_t> vertex;  // mesh vertex index, ascending
  std::vector<std::uint16_t> line;    // action line per bound vertex
  std::vector<std::array<std::uint32_t, kMusclePointsPerVertex>> point;  // control points (set-wide index)
  std::vector<std::array<float, kMusclePointsPerVertex>> weight;         // inverse distance, sums to 1
  // Beyond the paper: (1 - (r / radius)^2)^2 of the vertex's rest distance r from the line, so the bulge fades
  // to zero at the edge of the muscle's reach instead of stepping there (a visible crease on the skin).
  std::vector<float> falloff;
  // Force-vector shares: for bound vertex b and slot i, the shares of control point point[b][i]'s force vectors
  // start at share[share_first[b][i]] (as many as that point has force vectors; each group sums to 1).
  std::vector<std::array<std::uint32_t, kMusclePointsPerVertex>> share_first;
  std::vector<float> share;

  std::size_t size() const { return vertex.size(); }
};

// Run-time force gains: the displacement of muscle m is scaled by global * line[m].
struct MuscleGains {
  float global = 1.0f;
  std::vector<float> line;  // per action line of the set; empty = all 1

  float of(std::size_t m) const { return global * (m < line.size() ? line[m] : 1.0f); }
};

// The muscle layer of a rig: the set and its binding to every body level (index = body level) and to the cage.
struct MuscleRig {
  MuscleSet set;
  std::vector<MuscleBinding> levels;
  std::optional<MuscleBinding> cage;  // the body's subdivision cage, when it has one
};

}  // namespace strata
