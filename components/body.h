#pragma once
// Body: the skin of a rig at one or more resolution levels, each a rest mesh with its skin binding. Immutable
// rig data shared by every walker of the rig (components/rig.h); level 0 is the finest.
#include <array>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "components/detail_level.h"
#include "components/mesh.h"

namespace strata {

struct BodyLevel {
  Mesh mesh;
  SkinBinding binding;
};

struct SubdivSurface;  // rig/subdiv_topology.h

// The cage's refined surfaces (one per subdivision level), built on first use by body_subdiv_surface()
// (rig/subdiv_topology.h) and then shared by every scene and walker of the rig. Built lazily rather than at bind
// time: level 3 costs a few hundred ms to set up, which every process that never draws a subdivided body would
// otherwise pay. A copy starts empty, so a copied Body whose cage is then edited never serves stale surfaces.
class SubdivSurfaceCache {
 public:
  SubdivSurfaceCache() = default;
  SubdivSurfaceCache(const SubdivSurfaceCache&) {}
  SubdivSurfaceCache& operator=(const SubdivSurfaceCache&) {
    std::lock_guard lock(mutex_);
    surfaces_ = {};
    return *this;
  }
  // The surface of subdivision level `depth` (1..3), built by `build()` on the first request. Thread-safe.
  template <class Build>
  std::shared_ptr<const SubdivSurface> get(int depth, Build&& build) const {
    if (depth < 1 || depth > static_cast<int>(surfaces_.size()))
      throw std::invalid_argument("subdivision level must be 1..3, got " + std::to_string(depth));
    std::lock_guard lock(mutex_);
    std::shared_ptr<const SubdivSurface>& s = surfaces_[static_cast<std::size_t>(depth - 1)];
    if (!s) s = build();
    return s;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::array<std::shared_ptr<const SubdivSurface>, 3> surfaces_{};
};

// Data derived from one level's rest mesh and binding (index 0..2 the levels, 3 the cage), computed on first use
// by the function that owns it and then shared by every scene and walker of the rig; a copy starts empty, like
// SubdivSurfaceCache, so an edited binding or mesh never serves stale results.
template <class T>
class PerLevelCache {
 public:
  PerLevelCache() = default;
  PerLevelCache(const PerLevelCache&) {}
  PerLevelCache& operator=(const PerLevelCache&) {
    std::lock_guard lock(mutex_);
    items_ = {};
    return *this;
  }
  template <class Build>
  std::shared_ptr<const T> get(std::size_t slot, Build&& build) const {
    if (slot >= items_.size()) throw std::invalid_argument("body cache: no such level");
    std::lock_guard lock(mutex_);
    std::shared_ptr<const T>& c = items_[slot];
    if (!c) c = build();
    return c;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::array<std::shared_ptr<const T>, 4> items_{};
};

// Centres of rotation (rig/cor_centres.h body_cor_centres): only a crowd skinned with
// SkinningMode::CentresOfRotation pays for them.
struct CorCentres;
using CorCentreCache = PerLevelCache<CorCentres>;
// Ambient occlusion per vertex (rig/vertex_occlusion.h body_vertex_occlusion): only the shaded renderer
// (RenderQuality::High) pays for it.
struct VertexOcclusion;
using VertexOcclusionCache = PerLevelCache<VertexOcclusion>;

struct Body;
// Level `level` of `body` (0..2), or its cage for -1; null when it has no such level. The PerLevelCache slot of the
// same level (3 for the cage) is per_level_slot(level).
const BodyLevel* body_level_or_cage(const Body& body, int level);
inline std::size_t per_level_slot(int level) { return level < 0 ? 3 : static_cast<std::size_t>(level); }

struct Body {
  std::vector<BodyLevel> levels;
  // The low-resolution subdivision cage, bound like the levels; absent for imported bodies. Kept apart from
  // `levels` so level numbers 0..2 keep their meaning for reports and tests.
  std::optional<BodyLevel> cage = std::nullopt;
  SubdivSurfaceCache subdiv{};
  CorCentreCache cor{};
  VertexOcclusionCache occlusion{};
};

inline const BodyLevel* body_level_or_cage(const Body& body, int level) {
  if (level < 0) return body.cage ? &*body.cage : nullptr;
  if (static_cast<std::size_t>(level) < body.levels.size() && level < 3) return &body.levels[static_cast<std::size_t>(level)];
  return nullptr;
}

}  // namespace strata
