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

struct CorCentres;  // rig/cor_centres.h
// Centres of rotation per level (index 0..2) and for the cage (index 3), computed on first use by
// body_cor_centres() (rig/cor_centres.h): only a crowd skinned with SkinningMode::CentresOfRotation pays for
// them. A copy starts empty, like SubdivSurfaceCache, so an edited binding never serves stale centres.
class CorCentreCache {
 public:
  CorCentreCache() = default;
  CorCentreCache(const CorCentreCache&) {}
  CorCentreCache& operator=(const CorCentreCache&) {
    std::lock_guard lock(mutex_);
    centres_ = {};
    return *this;
  }
  template <class Build>
  std::shared_ptr<const CorCentres> get(std::size_t slot, Build&& build) const {
    if (slot >= centres_.size()) throw std::invalid_argument("centres of rotation: no such level");
    std::lock_guard lock(mutex_);
    std::shared_ptr<const CorCentres>& c = centres_[slot];
    if (!c) c = build();
    return c;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::array<std::shared_ptr<const CorCentres>, 4> centres_{};
};

struct Body {
  std::vector<BodyLevel> levels;
  // The low-resolution subdivision cage, bound like the levels; absent for imported bodies. Kept apart from
  // `levels` so level numbers 0..2 keep their meaning for reports and tests.
  std::optional<BodyLevel> cage = std::nullopt;
  SubdivSurfaceCache subdiv{};
  CorCentreCache cor{};
};

}  // namespace strata
