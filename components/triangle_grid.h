#pragma once
// Nearest-point queries against a triangle soup: a uniform grid of cells, each listing the triangles whose bounding
// box touches it; a query searches growing shells of cells around its own (clamped into the grid) until no
// unsearched cell can hold anything closer. Shared by the UV transfer onto the body's levels (rig/uv_transfer.h)
// and the measurement of one surface's distance from another (reference/surface_distance.h).
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

namespace strata {

// The point of triangle (a, b, c) closest to p, as barycentric weights of a, b, c: the Voronoi regions of the
// vertices, then of the edges, then the face (Ericson, Real-Time Collision Detection, 5.1.5). A degenerate
// triangle whose face region has no area answers its first corner.
glm::dvec3 closest_barycentric(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

class TriangleGrid {
 public:
  // `triangles` index `positions`, 3 per triangle; `cell` is the cell size (m). Throws std::invalid_argument for no
  // positions, an index out of range or a cell that is not positive.
  TriangleGrid(std::span<const glm::vec3> positions, std::span<const std::uint32_t> triangles, float cell);

  struct Hit {
    std::uint32_t triangle = 0;                   // index of the triangle (its corners at 3 * triangle)
    glm::dvec3 barycentric{1.0, 0.0, 0.0};        // of the nearest point
    double distance = std::numeric_limits<double>::infinity();
  };
  // The nearest point of any triangle to q; ties go to the lower triangle index, so the answer does not depend on
  // the order cells are searched in. A non-finite q, or a grid without triangles, answers the default Hit.
  Hit nearest(const glm::dvec3& q) const;

 private:
  glm::ivec3 cell_of(const glm::dvec3& v) const;
  std::size_t index(int x, int y, int z) const;

  std::vector<glm::dvec3> p_;
  std::vector<std::uint32_t> tri_;
  double cell_;
  glm::dvec3 lo_{0.0}, hi_{0.0};
  int dims_[3] = {1, 1, 1};
  std::vector<std::uint32_t> start_, items_;
};

}  // namespace strata
