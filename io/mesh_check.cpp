#include "io/mesh_check.h"

#include <cmath>
#include <string>

#include "io/load_error.h"

namespace strata {

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
  if (!mesh.corner_uvs.empty() && mesh.corner_uvs.size() != mesh.triangles.size())
    throw LoadError(where + ": corner uvs has " + std::to_string(mesh.corner_uvs.size()) + " entries for " +
                    std::to_string(mesh.triangles.size()) + " triangle corners");
  for (std::size_t c = 0; c < mesh.corner_uvs.size(); ++c)
    if (!std::isfinite(mesh.corner_uvs[c].x) || !std::isfinite(mesh.corner_uvs[c].y))
      throw LoadError(where + ": triangle " + std::to_string(c / 3) + " has a non-finite texture coordinate");
  check_length(mesh.part.size(), "part ids");
  for (std::size_t v = 0; v < mesh.part.size(); ++v)
    if (mesh.part[v] >= mesh.part_names.size())
      throw LoadError(where + ": vertex " + std::to_string(v) + " has part " + std::to_string(mesh.part[v]) +
                      " but only " + std::to_string(mesh.part_names.size()) + " parts are named");
}

}  // namespace strata
