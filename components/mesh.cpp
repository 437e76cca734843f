#include "components/mesh.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>


namespace strata {

const std::vector<std::string>& paper_part_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = {"hip", "abdomen", "chest", "neck", "head", "lEye", "rEye"};
    for (const char* side : {"l", "r"}) {
      for (const char* part : {"Collar", "Shldr", "ForeArm", "Hand", "Thigh", "Shin", "Foot", "Toe"})
        n.push_back(std::string(side) + part);
      for (const char* finger : {"Thumb", "Index", "Mid", "Ring", "Pinky"})
        for (int k = 1; k <= 3; ++k) n.push_back(std::string(side) + finger + std::to_string(k));
    }
    return n;
  }();
  return names;
}

namespace {

template <class Position>
PlaneSection plane_section_of(std::span<const Position> p, std::span<const std::uint32_t> triangles,
                              std::span<const std::size_t> starts, const glm::dvec3& o, const glm::dvec3& axis) {
  PlaneSection out;
  glm::dvec3 moment(0.0);
  for (const std::size_t t : starts) {
    const glm::dvec3 v[3] = {glm::dvec3(p[triangles[t]]), glm::dvec3(p[triangles[t + 1]]), glm::dvec3(p[triangles[t + 2]])};
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = glm::dot(v[k] - o, axis);
    glm::dvec3 q[2];
    int found = 0;
    for (int k = 0; k < 3 && found < 2; ++k) {
      const int l = (k + 1) % 3;
      if ((d[k] < 0.0) == (d[l] < 0.0)) continue;  // this edge does not cross
      q[found++] = v[k] + (d[k] / (d[k] - d[l])) * (v[l] - v[k]);
    }
    if (found < 2) continue;
    // Counter-clockwise seen from +axis: the cut's outward normal, cross(segment, axis), agrees with the triangle's.
    const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
    if (glm::dot(glm::cross(q[1] - q[0], axis), n) < 0.0) std::swap(q[0], q[1]);
    // The segment and o make a (signed) triangle of the section; its centroid is (q0 + q1 - 2 o) / 3 from o.
    const double a = 0.5 * glm::dot(axis, glm::cross(q[0] - o, q[1] - o));
    out.area += a;
    moment += a * ((q[0] - o) + (q[1] - o)) / 3.0;
  }
  if (out.area > 0.0) out.centroid_offset = moment / out.area;
  return out;
}

}  // namespace

PlaneSection plane_section(std::span<const glm::vec3> positions, std::span<const std::uint32_t> triangles,
                           std::span<const std::size_t> starts, const glm::dvec3& o, const glm::dvec3& axis) {
  return plane_section_of(positions, triangles, starts, o, axis);
}
PlaneSection plane_section(std::span<const glm::dvec3> positions, std::span<const std::uint32_t> triangles,
                           std::span<const std::size_t> starts, const glm::dvec3& o, const glm::dvec3& axis) {
  return plane_section_of(positions, triangles, starts, o, axis);
}

CornerUvValues corner_uv_values(const Mesh& mesh) {
  CornerUvValues out;
  if (mesh.corner_uvs.size() != mesh.triangles.size() || mesh.triangles.empty()) return out;
  std::vector<std::vector<std::uint32_t>> of_vertex(mesh.vertex_count());  // per vertex, its values so far
  out.of_corner.reserve(mesh.triangles.size());
  for (std::size_t c = 0; c < mesh.triangles.size(); ++c) {
    const std::uint32_t v = mesh.triangles[c];
    const glm::vec2 uv = mesh.corner_uvs[c];
    std::vector<std::uint32_t>& mine = of_vertex.at(v);
    const auto it = std::find_if(mine.begin(), mine.end(), [&](std::uint32_t i) { return out.uvs[i] == uv; });
    if (it != mine.end()) {
      out.of_corner.push_back(*it);
      continue;
    }
    out.of_corner.push_back(static_cast<std::uint32_t>(out.uvs.size()));
    mine.push_back(out.of_corner.back());
    out.uvs.push_back(uv);
    out.vertex.push_back(v);
  }
  return out;
}

void compute_normals(Mesh& mesh) {
  mesh.normals.assign(mesh.positions.size(), glm::vec3(0.0f));
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::uint32_t a = mesh.triangles[t], b = mesh.triangles[t + 1], c = mesh.triangles[t + 2];
    // The cross product's length is twice the area: summing it weights each face by its area for free.
    const glm::vec3 n = glm::cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
    if (!std::isfinite(n.x + n.y + n.z)) continue;
    mesh.normals[a] += n;
    mesh.normals[b] += n;
    mesh.normals[c] += n;
  }
  for (glm::vec3& n : mesh.normals) {
    const float len = glm::length(n);
    n = len > 1e-20f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

CotangentEdges cotangent_edges(const Mesh& mesh, std::span<const std::uint8_t> rows,
                               std::vector<double>* vertex_areas) {
  const std::size_t n = mesh.vertex_count();
  const bool all_rows = rows.empty();
  CotangentEdges out(n);
  if (vertex_areas) vertex_areas->assign(n, 0.0);
  auto add = [&](std::uint32_t a, std::uint32_t b, double w) {
    if (!all_rows && !rows[a]) return;
    for (auto& [c, cw] : out[a])
      if (c == b) {
        cw += w;
        return;
      }
    out[a].emplace_back(b, w);
  };
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::uint32_t idx[3] = {mesh.triangles[t], mesh.triangles[t + 1], mesh.triangles[t + 2]};
    if (!vertex_areas && !all_rows && !rows[idx[0]] && !rows[idx[1]] && !rows[idx[2]]) continue;
    const glm::dvec3 q[3] = {glm::dvec3(mesh.positions[idx[0]]), glm::dvec3(mesh.positions[idx[1]]),
                             glm::dvec3(mesh.positions[idx[2]])};
    const double twice_area = glm::length(glm::cross(q[1] - q[0], q[2] - q[0]));
    if (!(twice_area > 1e-20)) continue;
    for (int k = 0; k < 3; ++k) {
      if (vertex_areas) (*vertex_areas)[idx[k]] += twice_area / 6.0;
      // The angle at corner k faces the edge (k+1, k+2): cot = dot / |cross|, and |cross| is twice the area.
      const glm::dvec3 e1 = q[(k + 1) % 3] - q[k], e2 = q[(k + 2) % 3] - q[k];
      const double half_cot = 0.5 * glm::dot(e1, e2) / twice_area;
      add(idx[(k + 1) % 3], idx[(k + 2) % 3], half_cot);
      add(idx[(k + 2) % 3], idx[(k + 1) % 3], half_cot);
    }
  }
  for (auto& list : out) {
    for (auto& [u, w] : list) w = std::max(w, 0.0);
    std::sort(list.begin(), list.end());
  }
  return out;
}

}  // namespace strata
