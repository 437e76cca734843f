#pragma once
// Mesh: a rest-pose skin in humanoid space (metres, H-Anim axes), split into named parts, and its skin binding.
// Immutable rig data, built once by generators, importers and binders (rig/, io/), shared by every walker.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace strata {

struct Mesh {
  std::string name;
  std::vector<glm::vec3> positions;      // rest positions
  std::vector<glm::vec3> normals;        // unit, per vertex (may be empty until compute_normals)
  std::vector<glm::vec2> uvs;            // optional, per vertex; texture space with v up (OBJ's and OpenGL's)
  // Optional face-varying texture coordinates: one per triangle corner, in the order of `triangles`, so a UV seam
  // needs no split vertex (a split would change the vertex counts and open the surface for the binder and the
  // collapse). Importers with seams and the derived MakeHuman body fill these; `uvs` stays for seamless meshes.
  std::vector<glm::vec2> corner_uvs;
  std::vector<std::uint32_t> triangles;  // 3 indices per triangle, counter-clockwise seen from outside
  std::vector<std::uint16_t> part;       // per vertex: index into part_names
  std::vector<std::string> part_names;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size() / 3; }
};

// The paper's 53 skin parts (Poser naming): hip, abdomen, chest, neck, head, lEye, rEye, and per side (l/r)
// Collar, Shldr, ForeArm, Hand, Thigh, Shin, Foot, Toe, and Thumb1-3, Index1-3, Mid1-3, Ring1-3, Pinky1-3.
const std::vector<std::string>& paper_part_names();

// Up to four joint influences per vertex; weights sum to 1, unused slots have weight 0 and joint 0.
inline constexpr int kMaxInfluences = 4;
struct SkinBinding {
  std::vector<std::array<std::int16_t, kMaxInfluences>> joints;
  std::vector<std::array<float, kMaxInfluences>> weights;

  std::size_t vertex_count() const { return joints.size(); }
  // Influences with weight > 0 of vertex v.
  int influence_count(std::size_t v) const {
    int n = 0;
    for (float w : weights[v]) n += w > 0.0f;
    return n;
  }
};

// A mesh's per-corner texture coordinates (corner_uvs) as per-vertex values: one per distinct (vertex, uv) pair,
// in the order corners first use them, with each value's vertex and each corner's value. This is where a UV seam
// splits a vertex, for consumers whose attributes are per vertex (glTF) or per face-varying value (OpenSubdiv).
// Empty when the mesh has no corner uvs.
struct CornerUvValues {
  std::vector<glm::vec2> uvs;             // per value
  std::vector<std::uint32_t> vertex;      // per value: the mesh vertex it belongs to
  std::vector<std::uint32_t> of_corner;   // per corner (3 per triangle): its value
};
CornerUvValues corner_uv_values(const Mesh& mesh);

// The closed cut of some triangles by the plane through `o` across `axis`: its signed area (counter-clockwise seen
// from +axis, each cut segment oriented by its triangle's winding, so a concave outline sums right; a vertex on
// the plane counts as in front) and its area centroid, as an offset from o (meaningful when the area is positive).
// `starts` are triangle starts (indices into `triangles`, multiples of 3). For the section measures of skinning
// (reference/skin_metrics.h) and the MakeHuman fit's limb middles (rig/makehuman_body.cpp).
struct PlaneSection {
  double area = 0.0;
  glm::dvec3 centroid_offset{0.0};
};
PlaneSection plane_section(std::span<const glm::vec3> positions, std::span<const std::uint32_t> triangles,
                           std::span<const std::size_t> starts, const glm::dvec3& o, const glm::dvec3& axis);
PlaneSection plane_section(std::span<const glm::dvec3> positions, std::span<const std::uint32_t> triangles,
                           std::span<const std::size_t> starts, const glm::dvec3& o, const glm::dvec3& axis);

// Area-weighted vertex normals from the triangles (degenerate triangles contribute nothing; a vertex with no
// usable triangle gets +Y so no NaN leaves).
void compute_normals(Mesh& mesh);

// The cotangent Laplacian's edge weights, for the two weight solvers over the skin (rig/binding.cpp's bone heat
// and rig/harmonic_weights.cpp): per vertex, its neighbours u with w = sum over the edge's triangles of
// cot(opposite angle) / 2, clamped at 0 after summing (two obtuse opposite angles give a negative sum, which would
// break the maximum principle both solvers rely on), sorted by u so sweeps visit neighbours in a fixed order.
// Clamped edges stay in the list with weight 0 (they still say who is adjacent). Only vertices with rows[v] != 0
// get a list (all when `rows` is empty). `vertex_areas`, when given, receives each vertex's barycentric area (a
// third of every adjacent triangle's). Degenerate triangles contribute nothing.
using CotangentEdges = std::vector<std::vector<std::pair<std::uint32_t, double>>>;
CotangentEdges cotangent_edges(const Mesh& mesh, std::span<const std::uint8_t> rows = {},
                               std::vector<double>* vertex_areas = nullptr);


}  // namespace strata
