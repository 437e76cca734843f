// The skeleton pass's unit meshes and bone placement (see skeleton_geometry.h); moved verbatim from the former
// CrowdRenderer, so the bones and joints come out vertex-for-vertex as before.
#include "render/skeleton_geometry.h"

#include <array>
#include <cmath>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace strata {

namespace {

// The child end of a bone is this fraction of the parent end's radius: the taper shows the bone's direction.
constexpr float kTipRatio = 0.55f;
constexpr int kBoneSides = 8;
constexpr int kSphereStacks = 8;
constexpr int kSphereSlices = 12;  // 168 triangles

// A UnitMesh being built: vertices with normalised normals, triangles wound outwards.
struct TubeMesh : UnitMesh {
  std::uint16_t add(const glm::vec3& p, const glm::vec3& n) {
    vertices.push_back({p, glm::normalize(n)});
    return static_cast<std::uint16_t>(vertices.size() - 1);
  }
  // Emits the triangle counter-clockwise as seen from the side `outward` points to, so the generators need not
  // get every winding right by hand.
  void triangle(std::uint16_t a, std::uint16_t b, std::uint16_t c, const glm::vec3& outward) {
    const glm::vec3 n = glm::cross(vertices[b].position - vertices[a].position,
                                   vertices[c].position - vertices[a].position);
    if (glm::dot(n, outward) < 0.0f) std::swap(b, c);
    indices.insert(indices.end(), {a, b, c});
  }
};

bool is_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

// Tapered prism from radius 1 at y = 0 to kTipRatio at y = 1, capped at both ends. Side normals are smooth
// (per ring vertex, not per face) so the prism shades like a cone: a bone's basis may rotate about its axis from
// one frame to the next (see bone_transform) and a faceted prism would visibly flicker when it does.
UnitMesh make_bone_mesh() {
  TubeMesh mesh;
  const float slope = 1.0f - kTipRatio;  // outward normal of r(y) = 1 - slope * y is (cos, slope, sin)
  std::array<std::uint16_t, kBoneSides> bottom{}, top{};
  for (int k = 0; k < kBoneSides; ++k) {
    const float angle = 2.0f * 3.14159265f * static_cast<float>(k) / kBoneSides;
    const float c = std::cos(angle), s = std::sin(angle);
    bottom[k] = mesh.add({c, 0.0f, s}, {c, slope, s});
    top[k] = mesh.add({kTipRatio * c, 1.0f, kTipRatio * s}, {c, slope, s});
  }
  for (int k = 0; k < kBoneSides; ++k) {
    const int n = (k + 1) % kBoneSides;
    const glm::vec3 out = mesh.vertices[bottom[k]].position + mesh.vertices[bottom[n]].position;
    mesh.triangle(bottom[k], bottom[n], top[n], out);
    mesh.triangle(bottom[k], top[n], top[k], out);
  }
  // Caps get their own vertices: their normals are the axis, not the side normal.
  std::array<std::uint16_t, kBoneSides> cap_bottom{}, cap_top{};
  for (int k = 0; k < kBoneSides; ++k) {
    cap_bottom[k] = mesh.add(mesh.vertices[bottom[k]].position, {0.0f, -1.0f, 0.0f});
    cap_top[k] = mesh.add(mesh.vertices[top[k]].position, {0.0f, 1.0f, 0.0f});
  }
  for (int k = 1; k + 1 < kBoneSides; ++k) {
    mesh.triangle(cap_bottom[0], cap_bottom[k], cap_bottom[k + 1], {0.0f, -1.0f, 0.0f});
    mesh.triangle(cap_top[0], cap_top[k], cap_top[k + 1], {0.0f, 1.0f, 0.0f});
  }
  return mesh;
}

// Unit UV sphere with single pole vertices (no degenerate triangles) and smooth normals.
UnitMesh make_sphere_mesh() {
  TubeMesh mesh;
  const float pi = 3.14159265f;
  const std::uint16_t north = mesh.add({0.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.0f});
  std::vector<std::uint16_t> rings;  // (kSphereStacks - 1) rings of kSphereSlices vertices
  for (int i = 1; i < kSphereStacks; ++i) {
    const float phi = pi * static_cast<float>(i) / kSphereStacks;
    for (int j = 0; j < kSphereSlices; ++j) {
      const float theta = 2.0f * pi * static_cast<float>(j) / kSphereSlices;
      const glm::vec3 p{std::sin(phi) * std::cos(theta), std::cos(phi), std::sin(phi) * std::sin(theta)};
      rings.push_back(mesh.add(p, p));
    }
  }
  const std::uint16_t south = mesh.add({0.0f, -1.0f, 0.0f}, {0.0f, -1.0f, 0.0f});
  auto ring = [&](int i, int j) { return rings[static_cast<std::size_t>(i * kSphereSlices + j % kSphereSlices)]; };
  auto centroid = [&](std::uint16_t a, std::uint16_t b, std::uint16_t c) {
    return mesh.vertices[a].position + mesh.vertices[b].position + mesh.vertices[c].position;
  };
  for (int j = 0; j < kSphereSlices; ++j) {
    const auto a = ring(0, j), b = ring(0, j + 1);
    mesh.triangle(north, a, b, centroid(north, a, b));
    const auto c = ring(kSphereStacks - 2, j), d = ring(kSphereStacks - 2, j + 1);
    mesh.triangle(south, c, d, centroid(south, c, d));
  }
  for (int i = 0; i + 1 < kSphereStacks - 1; ++i) {
    for (int j = 0; j < kSphereSlices; ++j) {
      const auto a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j), d = ring(i + 1, j + 1);
      mesh.triangle(a, b, d, centroid(a, b, d));
      mesh.triangle(a, d, c, centroid(a, d, c));
    }
  }
  return mesh;
}

std::optional<glm::mat4> bone_transform(const glm::vec3& a, const glm::vec3& b, float radius) {
  if (!is_finite(a) || !is_finite(b)) return std::nullopt;
  const glm::vec3 along = b - a;
  const float length = glm::length(along);
  if (!(length > 1e-6f) || !std::isfinite(length)) return std::nullopt;
  const glm::vec3 d = along / length;
  // The helper is the world axis least aligned with the bone, so |cross(helper, d)| >= sqrt(2/3) and the basis
  // never degenerates. A fixed helper (say +Y) was rejected: it is singular exactly for upright bones, which are
  // most bones of a standing humanoid. The choice can flip between frames; the smooth-shaded mesh hides that.
  const glm::vec3 ad = glm::abs(d);
  glm::vec3 helper{0.0f, 0.0f, 1.0f};
  if (ad.x <= ad.y && ad.x <= ad.z)
    helper = {1.0f, 0.0f, 0.0f};
  else if (ad.y <= ad.z)
    helper = {0.0f, 1.0f, 0.0f};
  const glm::vec3 u = glm::normalize(glm::cross(helper, d));
  const glm::vec3 w = glm::cross(u, d);  // (u, d, w) is right-handed: det = u . (d x w) = 1
  glm::mat4 m{1.0f};
  m[0] = glm::vec4(radius * u, 0.0f);
  m[1] = glm::vec4(along, 0.0f);
  m[2] = glm::vec4(radius * w, 0.0f);
  m[3] = glm::vec4(a, 1.0f);
  return m;
}

}  // namespace strata
