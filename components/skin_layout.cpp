#include "components/skin_layout.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <stdexcept>

#include "components/mesh.h"

namespace strata {

SkinLayout make_skin_layout(const BodyLevel& level, const MuscleBinding* muscles) {
  const Mesh& mesh = level.mesh;
  const SkinBinding& binding = level.binding;
  const std::size_t n = mesh.vertex_count();
  Mesh with_normals;
  const std::vector<glm::vec3>* normals = &mesh.normals;
  if (mesh.normals.size() != n) {
    with_normals = mesh;
    compute_normals(with_normals);
    normals = &with_normals.normals;
  }
  // Each vertex's influence set, joints sorted so {a, b} and {b, a} are one group.
  struct Influence {
    std::array<std::int16_t, kMaxInfluences> joints{};
    std::array<float, kMaxInfluences> weights{};
    std::uint32_t count = 0;
  };
  std::vector<Influence> inf(n);
  for (std::size_t v = 0; v < n; ++v) {
    std::array<std::pair<std::int16_t, float>, kMaxInfluences> pairs{};
    std::uint32_t c = 0;
    float sum = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k)
      if (binding.weights[v][k] > 0.0f) {
        pairs[c++] = {binding.joints[v][k], binding.weights[v][k]};
        sum += binding.weights[v][k];
      }
    if (c == 0) pairs[c++] = {0, sum = 1.0f};  // unbound: follow the root rather than vanish
    std::sort(pairs.begin(), pairs.begin() + c);
    for (std::uint32_t k = 0; k < c; ++k) {
      inf[v].joints[k] = pairs[k].first;
      inf[v].weights[k] = pairs[k].second / sum;
    }
    inf[v].count = c;
  }
  std::vector<std::uint32_t> slot(n, SkinLayout::kNoMuscle);
  if (muscles)
    for (std::uint32_t b = 0; b < muscles->size(); ++b)
      if (muscles->vertex[b] < n) slot[muscles->vertex[b]] = b;
  auto bound = [&](std::uint32_t v) { return slot[v] != SkinLayout::kNoMuscle; };
  // Order: by influence count, then joint set, then original index (stable, deterministic).
  SkinLayout layout;
  layout.vertex_count = static_cast<std::uint32_t>(n);
  layout.original.resize(n);
  std::iota(layout.original.begin(), layout.original.end(), 0u);
  std::stable_sort(layout.original.begin(), layout.original.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (inf[a].count != inf[b].count) return inf[a].count < inf[b].count;
    if (inf[a].joints != inf[b].joints) return inf[a].joints < inf[b].joints;
    return bound(a) < bound(b);
  });
  for (AlignedBuffer<float>* b : {&layout.px, &layout.py, &layout.pz, &layout.nx, &layout.ny, &layout.nz}) b->reset(n);
  for (AlignedBuffer<float>& w : layout.weight) w.reset(n);
  if (muscles) {
    for (auto& b : layout.muscle_point) b.reset(n);
    for (auto& b : layout.muscle_coefficient) b.reset(n);
    layout.muscle_slot.assign(n, SkinLayout::kNoMuscle);
  }
  std::vector<std::uint32_t> rank(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t v = layout.original[i];
    rank[v] = i;
    const Influence& f = inf[v];
    if (layout.groups.empty() || layout.groups.back().joints != f.joints || layout.groups.back().influences != f.count ||
        layout.groups.back().muscle != bound(v))
      layout.groups.push_back({f.joints, f.count, bound(v), i, 0});
    if (bound(v)) {
      layout.muscle_slot[i] = slot[v];
      for (int k = 0; k < kMusclePointsPerVertex; ++k) {
        layout.muscle_point[k][i] = static_cast<std::int32_t>(muscles->point[slot[v]][k]);
        layout.muscle_points = std::max(layout.muscle_points, muscles->point[slot[v]][k] + 1);
      }
    }
    ++layout.groups.back().count;
    layout.px[i] = mesh.positions[v].x;
    layout.py[i] = mesh.positions[v].y;
    layout.pz[i] = mesh.positions[v].z;
    layout.nx[i] = (*normals)[v].x;
    layout.ny[i] = (*normals)[v].y;
    layout.nz[i] = (*normals)[v].z;
    for (std::uint32_t k = 0; k < f.count; ++k) layout.weight[k][i] = f.weights[k];
  }
  layout.triangles.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) layout.triangles[t] = rank[mesh.triangles[t]];
  return layout;
}

void set_muscle_coefficients(SkinLayout& layout, std::span<const std::array<float, kMusclePointsPerVertex>> c) {
  for (std::size_t i = 0; i < layout.muscle_slot.size(); ++i) {
    const std::uint32_t b = layout.muscle_slot[i];
    if (b == SkinLayout::kNoMuscle) continue;
    if (b >= c.size()) throw std::invalid_argument("set_muscle_coefficients: fewer coefficients than bound vertices");
    for (int k = 0; k < kMusclePointsPerVertex; ++k) layout.muscle_coefficient[k][i] = c[b][k];
  }
}

void set_cor_centres(SkinLayout& layout, std::span<const glm::vec3> centres) {
  if (centres.size() != layout.vertex_count)
    throw std::invalid_argument("set_cor_centres: one centre per layout vertex expected");
  for (AlignedBuffer<float>* b : {&layout.cx, &layout.cy, &layout.cz}) b->reset(layout.vertex_count);
  for (std::uint32_t i = 0; i < layout.vertex_count; ++i) {
    const glm::vec3& c = centres[layout.original[i]];
    layout.cx[i] = c.x;
    layout.cy[i] = c.y;
    layout.cz[i] = c.z;
  }
}

const char* skinning_mode_name(SkinningMode mode) {
  switch (mode) {
    case SkinningMode::DualQuaternion: return "dqs";
    case SkinningMode::CentresOfRotation: return "cor";
    default: return "lbs";
  }
}

std::optional<SkinningMode> parse_skinning_mode(std::string_view name) {
  for (const SkinningMode m : kSkinningModes)
    if (name == skinning_mode_name(m)) return m;
  return std::nullopt;
}

}  // namespace strata
