#pragma once
// Global navigation for a scenario: a Recast navigation mesh built from the scenario's walkable ground (its
// rectangle or its walkable OBJ) with the static obstacles cut out and eroded by the agent radius, and Detour
// queries over it (polygon path + string pulling into corners). Built once per scenario geometry and agent radius
// and cached on disk beside the other caches ($XDG_CACHE_HOME/strata/navmesh_<key>.bin, else ~/.cache/strata,
// keyed by a hash of the geometry, the build settings and a format version; a stale, truncated or corrupt file is
// rebuilt; STRATA_NO_NAV_CACHE=1 turns the cache off). Grounds over 512 cells a side are built as tiles on all
// cores. Recast/Detour come from Debian's librecast-dev and stay out of this header (pimpl), so consumers of
// the installed library need neither its headers nor its link line.
//
// A NavMesh is immutable once built and may be shared by any number of threads; queries run from several
// threads at once when each thread takes its own NavQuery (Detour's dtNavMeshQuery keeps per-query node pools,
// which is why a query object is not shared).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "components/scenario.h"

namespace strata {

struct NavBuildSettings {
  float agent_radius = 0.3f;   // erosion of the walkable area (m)
  float cell_size = 0.1f;      // Recast voxel size on the ground (m)
  float cell_height = 0.05f;
  float agent_height = 1.8f;
  float max_climb = 0.3f;
  float max_slope_deg = 45.0f;
  float max_edge_length = 12.0f;
  float max_simplification_error = 1.1f;
  // Cells per tile side. 0: automatic, one tile when the ground fits in 512 x 512 cells, else tiles of 256, built
  // in parallel (one heightfield for a 490 m ground at 0.1 m cells would hold 24 M cells at once, and Recast's
  // watershed slows down more than linearly with a tile's size).
  std::int32_t tile_size = 0;
};

struct NavBuildInfo {
  double build_ms = 0;   // Recast + Detour build time (0 when loaded from the cache)
  double load_ms = 0;
  bool from_cache = false;
  std::size_t polygons = 0;
  std::size_t bytes = 0;  // navigation mesh data
  std::string cache_file;  // empty when not cached
};

// The corners of a path, from the start (not included) to the goal or the walkable point nearest to it (the last
// corner). `complete` is false when the goal is unreachable and the path ends at the nearest reachable point.
struct NavPath {
  std::vector<glm::vec2> corners;
  bool complete = false;
};

class NavMesh;

// One thread's query object over a NavMesh.
class NavQuery {
 public:
  explicit NavQuery(const NavMesh& mesh);
  ~NavQuery();
  NavQuery(const NavQuery&) = delete;
  NavQuery& operator=(const NavQuery&) = delete;
  // Path on the ground from `from` to `to`; at most `max_corners` corners (the rest are found by the next
  // query). Start and goal off the mesh are snapped to the nearest walkable point within 3 m (the last corner is
  // then the snapped goal, and the path is complete); a goal further off gives a path towards the mesh point
  // nearest it with complete = false; no walkable point within 3 m of the start (or a non-finite input) gives an
  // empty path with complete = false. Never throws on geometry.
  NavPath find_path(glm::vec2 from, glm::vec2 to, std::size_t max_corners = 8);
  // The walkable point nearest `p` (within `search` metres), if any.
  std::optional<glm::vec2> nearest_walkable(glm::vec2 p, float search = 2.0f);
  // Whether the straight segment from a to b stays on the walkable mesh (a visibility test for skipping corners).
  // `a` must be on the mesh; a segment running along the mesh boundary (corner to corner of a path) counts as
  // walkable: the test allows 5 mm of sideways slack.
  bool walkable_line(glm::vec2 a, glm::vec2 b);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class NavMesh {
 public:
  // Builds (or loads from the cache, when `use_cache`) the mesh for `scenario`. Throws std::runtime_error naming
  // the scenario when the geometry gives no walkable polygon or Recast fails; std::invalid_argument for bad
  // settings.
  static std::shared_ptr<const NavMesh> build(const Scenario& scenario, const NavBuildSettings& settings,
                                              bool use_cache = true);
  ~NavMesh();
  const NavBuildInfo& info() const { return info_; }
  // The mesh's polygons as ground outlines (x, z), for drawing and tests.
  std::vector<std::vector<glm::vec2>> polygons() const;

 private:
  NavMesh();
  friend class NavQuery;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  NavBuildInfo info_;
};

}  // namespace strata
