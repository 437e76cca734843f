#include "components/mesh.h"

#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "io/load_error.h"

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

void validate_mesh(const Mesh& mesh, std::string_view source) {
  const std::string where(source);
  const std::size_t n = mesh.positions.size();
  if (n == 0 || mesh.triangles.empty()) throw LoadError(where + ": mesh has no vertices or no faces");
  if (mesh.triangles.size() % 3 != 0)
    throw LoadError(where + ": triangle index list length " + std::to_string(mesh.triangles.size()) +
                    " is not a multiple of 3");
  for (std::size_t v = 0; v < n; ++v) {
    const glm::vec3& p = mesh.positions[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw LoadError(where + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (mesh.triangles[i] >= n)
      throw LoadError(where + ": triangle " + std::to_string(i / 3) + " uses vertex " +
                      std::to_string(mesh.triangles[i]) + " but there are only " + std::to_string(n));
  auto check_length = [&](std::size_t size, const char* what) {
    if (size != 0 && size != n)
      throw LoadError(where + ": " + what + " has " + std::to_string(size) + " entries for " + std::to_string(n) +
                      " vertices");
  };
  for (std::size_t v = 0; v < mesh.normals.size(); ++v) {
    const glm::vec3& nrm = mesh.normals[v];
    if (!std::isfinite(nrm.x) || !std::isfinite(nrm.y) || !std::isfinite(nrm.z))
      throw LoadError(where + ": vertex " + std::to_string(v) + " has a non-finite normal");
  }
  check_length(mesh.normals.size(), "normals");
  check_length(mesh.uvs.size(), "uvs");
  check_length(mesh.part.size(), "part ids");
  for (std::size_t v = 0; v < mesh.part.size(); ++v)
    if (mesh.part[v] >= mesh.part_names.size())
      throw LoadError(where + ": vertex " + std::to_string(v) + " has part " + std::to_string(mesh.part[v]) +
                      " but only " + std::to_string(mesh.part_names.size()) + " parts are named");
}

}  // namespace strata
