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

struct Body {
  std::vector<BodyLevel> levels;
  // The low-resolution subdivision cage, bound like the levels; absent for imported bodies. Kept apart from
  // `levels` so level numbers 0..2 keep their meaning for reports and tests.
  std::optional<BodyLevel> cage = std::nullopt;
  SubdivSurfaceCache subdiv{};
};

// Body level numbers, as CrowdScene::set_body_level, `--level` and the reports use them: 0..levels-1 are the
// meshes (0 finest), -1 is no body, and the cage refined k times (k = 1..3, "S1".."S3") is kSubdivLevelBase + k,
// i.e. 11, 12, 13. Plain ints rather than an enum so the existing 0/1/2/-1 call sites keep working.
inline constexpr int kSubdivLevelBase = 10;
inline constexpr int kMaxSubdivDepth = 3;
constexpr bool is_subdiv_level(int level) {
  return level > kSubdivLevelBase && level <= kSubdivLevelBase + kMaxSubdivDepth;
}
constexpr int subdiv_level(int depth) { return kSubdivLevelBase + depth; }
constexpr int subdiv_depth(int level) { return is_subdiv_level(level) ? level - kSubdivLevelBase : 0; }
// Each walker at its own mesh level, chosen per frame by its projected size (systems/lod.h): `--level auto`.
inline constexpr int kAutoBodyLevel = 20;
// "0", "1", "2", "-1", "S1".."S3", "auto".
inline std::string body_level_name(int level) {
  if (level == kAutoBodyLevel) return "auto";
  if (!is_subdiv_level(level)) return std::to_string(level);
  std::string name = "S";  // appended rather than "S" + std::string, which trips GCC 12's -Wrestrict false positive
  name += std::to_string(subdiv_depth(level));
  return name;
}

}  // namespace strata
