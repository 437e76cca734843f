#include "nav/navmesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <thread>

#include <DetourAlloc.h>
#include <DetourNavMesh.h>
#include <DetourNavMeshBuilder.h>
#include <DetourNavMeshQuery.h>
#include <Recast.h>

#include "components/fnv_hasher.h"
#include "io/atomic_file.h"
#include "io/obj.h"

namespace strata {
namespace {

// Bumped whenever the build below or the file layout changes, so an old cache file never matches a new key.
constexpr std::uint32_t kFormatVersion = 1;
constexpr char kMagic[8] = {'S', 'T', 'R', 'A', 'N', 'A', 'V', '\0'};
constexpr std::uint16_t kWalkableFlag = 1;  // every polygon Recast keeps is plain walkable ground
constexpr int kMaxPathPolys = 4096;
constexpr int kQueryNodes = 8192;
// tile_size 0 builds one tile while the ground fits in this many cells per side; above it, tiles of
// kAutoTileCells, because a single heightfield grows with the ground's area (a 490 m ground at 0.1 m is 24 M
// cells at once) and Recast's watershed slows down faster than the area grows. Measured on 2 shared cores: the
// circle's 400 tiles took 31 s one after the other and 4.9 s on two threads (the first figure under a
// concurrent build); crossing's 720 x 720 cells took 0.86 s as one tile and 0.12 s as 9 tiles.
constexpr int kSingleTileMaxCells = 512;
constexpr int kAutoTileCells = 256;
constexpr float kSnapDistance = 3.0f;     // m: how far find_path snaps a start or goal onto the mesh
constexpr float kSideTolerance = 0.005f;  // m: walkable_line's sideways slack (see there)

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// --- Input geometry ----------------------------------------------------------------------------------------

struct InputGeometry {
  std::vector<float> verts;          // x, y, z
  std::vector<int> tris;             // 3 indices each
  std::vector<unsigned char> areas;  // per triangle
  float bmin[3] = {0, 0, 0}, bmax[3] = {0, 0, 0};
  // Obstacle interiors, as convex pieces (triangles) marked unwalkable after voxelisation.
  std::vector<std::array<glm::vec2, 3>> obstacle_triangles;
  std::vector<glm::vec2> ground_outline;  // empty for an OBJ ground
  std::vector<glm::vec3> obj_positions;   // hashed into the cache key
  std::vector<std::uint32_t> obj_triangles;
};

int add_vertex(InputGeometry& g, float x, float y, float z) {
  g.verts.insert(g.verts.end(), {x, y, z});
  return static_cast<int>(g.verts.size() / 3 - 1);
}

double cross2(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Ear clipping of a simple polygon. The scenario loader guarantees simple polygons; ear clipping handles the
// concave ones (an L-shaped kiosk) that Recast's rcMarkConvexPolyArea cannot take whole. Rejected: a convex
// decomposition (Hertel-Mehlhorn) gives fewer pieces, but the pieces only mark voxels once per build, so the
// triangle count does not matter. A polygon that is not simple after all degrades to a fan of what is left.
std::vector<std::array<glm::vec2, 3>> triangulate(std::vector<glm::vec2> p) {
  std::vector<std::array<glm::vec2, 3>> out;
  double area = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    area +=
        static_cast<double>(p[i].x) * p[(i + 1) % p.size()].y - static_cast<double>(p[(i + 1) % p.size()].x) * p[i].y;
  if (area < 0.0) std::reverse(p.begin(), p.end());
  while (p.size() > 3) {
    bool clipped = false;
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n && !clipped; ++i) {
      const glm::dvec2 a(p[(i + n - 1) % n]), b(p[i]), c(p[(i + 1) % n]);
      if (cross2(a, b, c) <= 0.0) continue;  // reflex or flat corner: not an ear
      bool empty = true;
      for (std::size_t k = 0; k < n && empty; ++k) {
        if (k == i || k == (i + 1) % n || k == (i + n - 1) % n) continue;
        const glm::dvec2 q(p[k]);
        empty = !(cross2(a, b, q) >= 0.0 && cross2(b, c, q) >= 0.0 && cross2(c, a, q) >= 0.0);
      }
      if (!empty) continue;
      out.push_back({p[(i + n - 1) % n], p[i], p[(i + 1) % n]});
      p.erase(p.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) break;
  }
  for (std::size_t i = 1; i + 1 < p.size(); ++i) out.push_back({p[0], p[i], p[i + 1]});
  return out;
}

InputGeometry input_geometry(const Scenario& scenario, const NavBuildSettings& s) {
  InputGeometry g;
  float ymin = 0.0f, ymax = 0.0f;
  if (scenario.walkable_obj.empty()) {
    // The ground rectangle as two triangles, wound so their normals point up (+Y) for Recast's slope test.
    const glm::vec2 lo = scenario.ground_min, hi = scenario.ground_max;
    const int a = add_vertex(g, lo.x, 0, lo.y), b = add_vertex(g, hi.x, 0, lo.y), c = add_vertex(g, hi.x, 0, hi.y),
              d = add_vertex(g, lo.x, 0, hi.y);
    g.tris = {a, c, b, a, d, c};
    g.areas = {RC_WALKABLE_AREA, RC_WALKABLE_AREA};
    g.ground_outline = {lo, {hi.x, lo.y}, hi, {lo.x, hi.y}};
  } else {
    const Mesh mesh = load_obj_file(scenario.walkable_obj);
    if (mesh.positions.empty() || mesh.triangles.empty())
      throw std::runtime_error(scenario.walkable_obj + ": the walkable mesh has no triangles");
    ymin = ymax = mesh.positions[0].y;
    for (const glm::vec3& v : mesh.positions) {
      add_vertex(g, v.x, v.y, v.z);
      ymin = std::min(ymin, v.y);
      ymax = std::max(ymax, v.y);
    }
    for (const std::uint32_t i : mesh.triangles) g.tris.push_back(static_cast<int>(i));
    g.areas.assign(mesh.triangles.size() / 3, 0);
    rcContext ctx(false);
    rcMarkWalkableTriangles(&ctx, s.max_slope_deg, g.verts.data(), static_cast<int>(g.verts.size() / 3), g.tris.data(),
                            static_cast<int>(g.areas.size()), g.areas.data());
    g.obj_positions = mesh.positions;
    g.obj_triangles = mesh.triangles;
  }
  // Obstacles: vertical walls along every edge, from below the lowest ground to above head height, rasterised as
  // unwalkable. Recast rasterises conservatively (any voxel a triangle touches), so even a wall thinner than a
  // cell closes; the interior is marked from the triangles after voxelisation (mark_obstacles). Rejected: a low
  // roof over each obstacle that the walkable-height filter removes (works on a flat ground only, not on an OBJ
  // ground whose height varies), and rcMarkConvexPolyArea alone (it samples cell centres and lets a thin wall
  // fall between them).
  const float y_lo = ymin - 1.0f, y_hi = ymax + s.agent_height + 1.0f;
  for (const ScenarioPolygon& poly : scenario.obstacles) {
    const std::size_t n = poly.points.size();
    if (n < 3) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec2 a = poly.points[i], b = poly.points[(i + 1) % n];
      const int a0 = add_vertex(g, a.x, y_lo, a.y), b0 = add_vertex(g, b.x, y_lo, b.y);
      const int a1 = add_vertex(g, a.x, y_hi, a.y), b1 = add_vertex(g, b.x, y_hi, b.y);
      g.tris.insert(g.tris.end(), {a0, b0, b1, a0, b1, a1});
      g.areas.insert(g.areas.end(), {RC_NULL_AREA, RC_NULL_AREA});
    }
    const auto pieces = triangulate(poly.points);
    g.obstacle_triangles.insert(g.obstacle_triangles.end(), pieces.begin(), pieces.end());
  }
  rcCalcBounds(g.verts.data(), static_cast<int>(g.verts.size() / 3), g.bmin, g.bmax);
  // Room above and below for the spans (a flat ground without obstacles would otherwise have no height at all).
  g.bmin[1] = std::min(g.bmin[1], y_lo);
  g.bmax[1] = std::max(g.bmax[1], y_hi);
  // The ground defines the navigable extent; obstacles reaching past it do not widen it.
  if (scenario.walkable_obj.empty()) {
    g.bmin[0] = scenario.ground_min.x, g.bmin[2] = scenario.ground_min.y;
    g.bmax[0] = scenario.ground_max.x, g.bmax[2] = scenario.ground_max.y;
  }
  return g;
}

// --- Recast build --------------------------------------------------------------------------------------------

struct RecastPtrs {
  rcHeightfield* solid = nullptr;
  rcCompactHeightfield* chf = nullptr;
  rcContourSet* cset = nullptr;
  rcPolyMesh* pmesh = nullptr;
  rcPolyMeshDetail* dmesh = nullptr;
  ~RecastPtrs() {
    rcFreeHeightField(solid);
    rcFreeCompactHeightfield(chf);
    rcFreeContourSet(cset);
    rcFreePolyMesh(pmesh);
    rcFreePolyMeshDetail(dmesh);
  }
};

struct TileData {
  int tx = 0, ty = 0;
  std::vector<unsigned char> bytes;
};

struct Layout {
  int tile_cells = 0;  // cells per tile side (without the border)
  int tiles_x = 1, tiles_y = 1;
  float tile_world = 0.0f;
};

// Whole-cell counts from metres: a radius of exactly 3 cells must erode 3 cells, not 4 through float error.
int cells_up(float metres, float cell) { return static_cast<int>(std::ceil(metres / cell - 1e-4f)); }
int cells_down(float metres, float cell) { return static_cast<int>(std::floor(metres / cell + 1e-4f)); }

// One tile: voxelise the input in its bounds (plus a border, so the erosion sees across the seam), filter,
// mark and erode, regions, contours, polygons, detail, Detour tile data. Empty bytes when nothing walkable.
std::vector<unsigned char> build_tile(const InputGeometry& g, const NavBuildSettings& s, const Layout& layout, int tx,
                                      int ty, const std::string& name) {
  rcConfig cfg{};
  cfg.cs = s.cell_size;
  cfg.ch = s.cell_height;
  cfg.walkableSlopeAngle = s.max_slope_deg;
  cfg.walkableHeight = cells_up(s.agent_height, s.cell_height);
  cfg.walkableClimb = cells_down(s.max_climb, s.cell_height);
  cfg.walkableRadius = cells_up(s.agent_radius, s.cell_size);
  cfg.maxEdgeLen = static_cast<int>(s.max_edge_length / s.cell_size);
  cfg.maxSimplificationError = s.max_simplification_error;
  cfg.minRegionArea = 8 * 8;  // islands under 0.64 m^2 (at 0.1 m cells) are dropped: nobody stands there
  cfg.mergeRegionArea = 20 * 20;
  cfg.maxVertsPerPoly = 6;
  cfg.detailSampleDist = 6.0f * s.cell_size;
  cfg.detailSampleMaxError = s.cell_height;
  cfg.tileSize = layout.tile_cells;
  cfg.borderSize = cfg.walkableRadius + 3;
  const float tile_bmin[3] = {g.bmin[0] + tx * layout.tile_world, g.bmin[1], g.bmin[2] + ty * layout.tile_world};
  const float tile_bmax[3] = {std::min(g.bmax[0], tile_bmin[0] + layout.tile_world), g.bmax[1],
                              std::min(g.bmax[2], tile_bmin[2] + layout.tile_world)};
  rcVcopy(cfg.bmin, tile_bmin);
  rcVcopy(cfg.bmax, tile_bmax);
  cfg.bmin[0] -= cfg.borderSize * cfg.cs;
  cfg.bmin[2] -= cfg.borderSize * cfg.cs;
  cfg.bmax[0] += cfg.borderSize * cfg.cs;
  cfg.bmax[2] += cfg.borderSize * cfg.cs;
  rcCalcGridSize(cfg.bmin, cfg.bmax, cfg.cs, &cfg.width, &cfg.height);

  auto fail = [&](const char* step) -> std::runtime_error {
    return std::runtime_error(name + ": Recast failed at " + step + " (tile " + std::to_string(tx) + ", " +
                              std::to_string(ty) + ")");
  };
  rcContext ctx(false);
  RecastPtrs r;
  r.solid = rcAllocHeightfield();
  if (!r.solid || !rcCreateHeightfield(&ctx, *r.solid, cfg.width, cfg.height, cfg.bmin, cfg.bmax, cfg.cs, cfg.ch))
    throw fail("the heightfield");
  if (!rcRasterizeTriangles(&ctx, g.verts.data(), static_cast<int>(g.verts.size() / 3), g.tris.data(), g.areas.data(),
                            static_cast<int>(g.areas.size()), *r.solid, cfg.walkableClimb))
    throw fail("rasterisation");
  rcFilterLowHangingWalkableObstacles(&ctx, cfg.walkableClimb, *r.solid);
  rcFilterLedgeSpans(&ctx, cfg.walkableHeight, cfg.walkableClimb, *r.solid);
  rcFilterWalkableLowHeightSpans(&ctx, cfg.walkableHeight, *r.solid);
  r.chf = rcAllocCompactHeightfield();
  if (!r.chf || !rcBuildCompactHeightfield(&ctx, cfg.walkableHeight, cfg.walkableClimb, *r.solid, *r.chf))
    throw fail("the compact heightfield");
  rcFreeHeightField(r.solid);
  r.solid = nullptr;
  // Obstacle interiors: unwalkable at every height, before erosion so the erosion also pushes away from them.
  for (const auto& t : g.obstacle_triangles) {
    const float v[9] = {t[0].x, 0, t[0].y, t[1].x, 0, t[1].y, t[2].x, 0, t[2].y};
    rcMarkConvexPolyArea(&ctx, v, 3, g.bmin[1] - 1.0f, g.bmax[1] + 1.0f, RC_NULL_AREA, *r.chf);
  }
  if (!rcErodeWalkableArea(&ctx, cfg.walkableRadius, *r.chf)) throw fail("erosion");
  // Watershed regions: the best polygons for open areas with obstacles (monotone partitioning makes long thin
  // polygons that lengthen paths; layers suit overlapping storeys, which a crowd ground rarely has).
  if (!rcBuildDistanceField(&ctx, *r.chf)) throw fail("the distance field");
  if (!rcBuildRegions(&ctx, *r.chf, cfg.borderSize, cfg.minRegionArea, cfg.mergeRegionArea)) throw fail("regions");
  r.cset = rcAllocContourSet();
  if (!r.cset || !rcBuildContours(&ctx, *r.chf, cfg.maxSimplificationError, cfg.maxEdgeLen, *r.cset))
    throw fail("contours");
  if (r.cset->nconts == 0) return {};
  r.pmesh = rcAllocPolyMesh();
  if (!r.pmesh || !rcBuildPolyMesh(&ctx, *r.cset, cfg.maxVertsPerPoly, *r.pmesh)) throw fail("the polygon mesh");
  r.dmesh = rcAllocPolyMeshDetail();
  if (!r.dmesh ||
      !rcBuildPolyMeshDetail(&ctx, *r.pmesh, *r.chf, cfg.detailSampleDist, cfg.detailSampleMaxError, *r.dmesh))
    throw fail("the detail mesh");
  if (r.pmesh->npolys == 0) return {};
  if (r.pmesh->nverts >= 0xffff)
    throw fail("the polygon mesh (over 65535 vertices in a tile: use a smaller tile_size)");
  for (int i = 0; i < r.pmesh->npolys; ++i)
    r.pmesh->flags[i] = r.pmesh->areas[i] == RC_WALKABLE_AREA ? kWalkableFlag : 0;

  dtNavMeshCreateParams p{};
  p.verts = r.pmesh->verts;
  p.vertCount = r.pmesh->nverts;
  p.polys = r.pmesh->polys;
  p.polyAreas = r.pmesh->areas;
  p.polyFlags = r.pmesh->flags;
  p.polyCount = r.pmesh->npolys;
  p.nvp = r.pmesh->nvp;
  p.detailMeshes = r.dmesh->meshes;
  p.detailVerts = r.dmesh->verts;
  p.detailVertsCount = r.dmesh->nverts;
  p.detailTris = r.dmesh->tris;
  p.detailTriCount = r.dmesh->ntris;
  p.walkableHeight = s.agent_height;
  p.walkableRadius = s.agent_radius;
  p.walkableClimb = s.max_climb;
  p.tileX = tx;
  p.tileY = ty;
  rcVcopy(p.bmin, r.pmesh->bmin);
  rcVcopy(p.bmax, r.pmesh->bmax);
  p.cs = cfg.cs;
  p.ch = cfg.ch;
  p.buildBvTree = true;
  unsigned char* data = nullptr;
  int size = 0;
  if (!dtCreateNavMeshData(&p, &data, &size)) throw fail("the Detour tile data");
  std::vector<unsigned char> bytes(data, data + size);
  dtFree(data);
  return bytes;
}

// --- The cache ---------------------------------------------------------------------------------------------

// $XDG_CACHE_HOME/strata, else ~/.cache/strata, as the body cache (rig/body_cache.h) does. rig/ is not visible
// from nav/ (cmake/layers.txt), so this is a three-line twin rather than a move of body_cache_directory into
// io/, which would touch the rig's callers for no gain. STRATA_NO_NAV_CACHE=1 turns it off.
std::optional<std::filesystem::path> nav_cache_directory() {
  const char* off = std::getenv("STRATA_NO_NAV_CACHE");
  if (off && *off && std::string(off) != "0") return std::nullopt;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "strata";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "strata";
  return std::nullopt;
}

std::uint64_t cache_key(const InputGeometry& g, const Scenario& scenario, const NavBuildSettings& s,
                        const Layout& layout) {
  FnvHasher h;
  h.value(kFormatVersion);
  for (const float f : {s.agent_radius, s.cell_size, s.cell_height, s.agent_height, s.max_climb, s.max_slope_deg,
                        s.max_edge_length, s.max_simplification_error})
    h.value(f);
  h.value(layout.tile_cells);
  h.value(scenario.ground_min);
  h.value(scenario.ground_max);
  h.value(scenario.obstacles.size());
  for (const ScenarioPolygon& p : scenario.obstacles) h.vector(p.points);
  h.vector(g.obj_positions);
  h.vector(g.obj_triangles);
  return h.h;
}

struct MeshFile {
  dtNavMeshParams params{};
  std::vector<TileData> tiles;
};

std::uint64_t payload_hash(const MeshFile& f) {
  FnvHasher h;
  h.value(f.params);
  for (const TileData& t : f.tiles) {
    h.value(t.tx);
    h.value(t.ty);
    h.vector(t.bytes);
  }
  return h.h;
}

void save_cache(const std::filesystem::path& file, std::uint64_t key, const MeshFile& f) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return;
  std::string out(kMagic, sizeof kMagic);
  auto put = [&out](const auto& v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(kFormatVersion);
  put(key);
  put(f.params);
  put(static_cast<std::uint32_t>(f.tiles.size()));
  for (const TileData& t : f.tiles) {
    put(t.tx);
    put(t.ty);
    put(static_cast<std::uint32_t>(t.bytes.size()));
    out.append(reinterpret_cast<const char*>(t.bytes.data()), t.bytes.size());
  }
  put(payload_hash(f));
  // The cache is an optimisation: a failed write (read-only home, full disk) only means the next run builds.
  try {
    write_file_atomically(file, out);
  } catch (const std::exception&) {
  }
}

// The stored mesh, or nullopt for a missing, stale (other key or version), truncated or corrupt file: every
// length is checked against what is left and the payload against its hash, so a damaged file is rebuilt, never
// handed to Detour (which trusts its tile data's offsets).
std::optional<MeshFile> load_cache(const std::filesystem::path& file, std::uint64_t key) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::size_t at = 0;
  auto get = [&](auto& v) {
    if (bytes.size() - at < sizeof v) return false;
    std::memcpy(&v, bytes.data() + at, sizeof v);
    at += sizeof v;
    return true;
  };
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return std::nullopt;
  at = sizeof kMagic;
  std::uint32_t version = 0, count = 0;
  std::uint64_t stored_key = 0, stored_hash = 0;
  MeshFile f;
  if (!get(version) || version != kFormatVersion || !get(stored_key) || stored_key != key || !get(f.params) ||
      !get(count) || count > 1u << 20)
    return std::nullopt;
  for (std::uint32_t i = 0; i < count; ++i) {
    TileData t;
    std::uint32_t size = 0;
    if (!get(t.tx) || !get(t.ty) || !get(size) || bytes.size() - at < size || size < sizeof(dtMeshHeader))
      return std::nullopt;
    t.bytes.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at),
                   bytes.begin() + static_cast<std::ptrdiff_t>(at + size));
    at += size;
    f.tiles.push_back(std::move(t));
  }
  if (!get(stored_hash) || stored_hash != payload_hash(f) || at != bytes.size()) return std::nullopt;
  return f;
}

}  // namespace

// Outside the anonymous namespace: NavMesh::Impl (declared in the header) holds one, and a member of an
// internal-linkage type in a class with external linkage draws -Wsubobject-linkage once this file is compiled
// inside a unity batch.
struct DtNavMeshDeleter {
  void operator()(dtNavMesh* m) const { dtFreeNavMesh(m); }
};
using DtNavMeshPtr = std::unique_ptr<dtNavMesh, DtNavMeshDeleter>;

namespace {

// A Detour mesh over copies of the tiles (Detour frees them with the mesh); nullptr when Detour refuses any.
DtNavMeshPtr make_detour(const MeshFile& f) {
  DtNavMeshPtr mesh(dtAllocNavMesh());
  if (!mesh || dtStatusFailed(mesh->init(&f.params))) return nullptr;
  for (const TileData& t : f.tiles) {
    auto* data = static_cast<unsigned char*>(dtAlloc(static_cast<int>(t.bytes.size()), DT_ALLOC_PERM));
    if (!data) return nullptr;
    std::memcpy(data, t.bytes.data(), t.bytes.size());
    if (dtStatusFailed(mesh->addTile(data, static_cast<int>(t.bytes.size()), DT_TILE_FREE_DATA, 0, nullptr))) {
      dtFree(data);
      return nullptr;
    }
  }
  return mesh;
}

unsigned next_pow2(unsigned v) {
  unsigned p = 1;
  while (p < v) p <<= 1;
  return p;
}

unsigned ilog2(unsigned v) {
  unsigned r = 0;
  while (v >>= 1) ++r;
  return r;
}

void check_settings(const NavBuildSettings& s) {
  auto positive = [](float v, float hi) { return std::isfinite(v) && v > 0.0f && v <= hi; };
  if (!positive(s.agent_radius, 10.0f))
    throw std::invalid_argument("NavBuildSettings: agent_radius must lie in (0, 10]");
  if (!positive(s.cell_size, 10.0f)) throw std::invalid_argument("NavBuildSettings: cell_size must lie in (0, 10]");
  if (!positive(s.cell_height, 10.0f)) throw std::invalid_argument("NavBuildSettings: cell_height must lie in (0, 10]");
  if (!positive(s.agent_height, 10.0f))
    throw std::invalid_argument("NavBuildSettings: agent_height must lie in (0, 10]");
  if (!(std::isfinite(s.max_climb) && s.max_climb >= 0.0f && s.max_climb < s.agent_height))
    throw std::invalid_argument("NavBuildSettings: max_climb must lie in [0, agent_height)");
  if (!(std::isfinite(s.max_slope_deg) && s.max_slope_deg >= 0.0f && s.max_slope_deg < 90.0f))
    throw std::invalid_argument("NavBuildSettings: max_slope_deg must lie in [0, 90)");
  if (!positive(s.max_edge_length, 1000.0f))
    throw std::invalid_argument("NavBuildSettings: max_edge_length must lie in (0, 1000]");
  if (!positive(s.max_simplification_error, 100.0f))
    throw std::invalid_argument("NavBuildSettings: max_simplification_error must lie in (0, 100]");
  if (s.tile_size < 0 || (s.tile_size > 0 && s.tile_size < 16) || s.tile_size > 4096)
    throw std::invalid_argument("NavBuildSettings: tile_size must be 0 (automatic) or lie in [16, 4096]");
}

}  // namespace

// --- NavMesh -----------------------------------------------------------------------------------------------

struct NavMesh::Impl {
  DtNavMeshPtr mesh;
  float y_center = 0.0f, y_extent = 1.0f;  // queries are 2-D: every level within this vertical reach is searched
};

NavMesh::NavMesh() : impl_(std::make_unique<Impl>()) {}
NavMesh::~NavMesh() = default;

std::shared_ptr<const NavMesh> NavMesh::build(const Scenario& scenario, const NavBuildSettings& settings,
                                              bool use_cache) {
  check_settings(settings);
  const std::string name = scenario.name.empty() ? scenario.source : scenario.name;
  const auto t0 = std::chrono::steady_clock::now();
  const InputGeometry g = input_geometry(scenario, settings);

  int gw = 0, gh = 0;
  rcCalcGridSize(g.bmin, g.bmax, settings.cell_size, &gw, &gh);
  if (gw <= 0 || gh <= 0) throw std::runtime_error(name + ": the ground is empty");
  if (static_cast<double>(gw) * gh > 4e8)
    throw std::runtime_error(name + ": the ground is over 400 M cells at cell_size " +
                             std::to_string(settings.cell_size));
  Layout layout;
  layout.tile_cells = settings.tile_size > 0                    ? settings.tile_size
                      : std::max(gw, gh) <= kSingleTileMaxCells ? std::max(gw, gh)
                                                                : kAutoTileCells;
  layout.tile_world = static_cast<float>(layout.tile_cells) * settings.cell_size;
  layout.tiles_x = (gw + layout.tile_cells - 1) / layout.tile_cells;
  layout.tiles_y = (gh + layout.tile_cells - 1) / layout.tile_cells;
  const int tile_count = layout.tiles_x * layout.tiles_y;
  const unsigned tile_bits = ilog2(next_pow2(static_cast<unsigned>(tile_count)));
  if (tile_bits > 14) throw std::runtime_error(name + ": more than 16384 tiles: use a larger tile_size or cell_size");

  auto mesh = std::shared_ptr<NavMesh>(new NavMesh());
  mesh->impl_->y_center = 0.5f * (g.bmin[1] + g.bmax[1]);
  mesh->impl_->y_extent = 0.5f * (g.bmax[1] - g.bmin[1]) + settings.agent_height;

  const std::uint64_t key = cache_key(g, scenario, settings, layout);
  std::optional<std::filesystem::path> file;
  if (use_cache) {
    if (const auto dir = nav_cache_directory()) {
      char hex[17];
      std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
      file = *dir / ("navmesh_" + std::string(hex) + ".bin");
    }
  }
  NavBuildInfo& info = mesh->info_;
  if (file) {
    const auto t1 = std::chrono::steady_clock::now();
    if (std::optional<MeshFile> cached = load_cache(*file, key)) {
      if (DtNavMeshPtr dt = make_detour(*cached)) {
        mesh->impl_->mesh = std::move(dt);
        info.from_cache = true;
        info.load_ms = ms_since(t1);
        info.cache_file = file->string();
        for (const TileData& t : cached->tiles) {
          info.bytes += t.bytes.size();
          info.polygons += reinterpret_cast<const dtMeshHeader*>(t.bytes.data())->polyCount;
        }
        return mesh;
      }
    }
  }

  MeshFile built;
  built.params.orig[0] = g.bmin[0];
  built.params.orig[1] = g.bmin[1];
  built.params.orig[2] = g.bmin[2];
  built.params.tileWidth = layout.tile_world;
  built.params.tileHeight = layout.tile_world;
  built.params.maxTiles = 1 << tile_bits;
  built.params.maxPolys = 1 << (22 - tile_bits);
  // Tiles are independent: built on all cores (std::thread, not the engine's TBB, which nav/ does not link;
  // one build per scenario does not need a scheduler). Each result lands in its own slot, so the file and the
  // mesh are the same whatever the thread count.
  std::vector<std::vector<unsigned char>> results(static_cast<std::size_t>(tile_count));
  std::vector<std::exception_ptr> errors(results.size());
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int i = next++; i < tile_count; i = next++) {
      try {
        results[static_cast<std::size_t>(i)] =
            build_tile(g, settings, layout, i % layout.tiles_x, i / layout.tiles_x, name);
      } catch (...) {
        errors[static_cast<std::size_t>(i)] = std::current_exception();
      }
    }
  };
  const int threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(tile_count, 64));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  for (int i = 0; i < tile_count; ++i) {
    std::vector<unsigned char>& bytes = results[static_cast<std::size_t>(i)];
    if (bytes.empty()) continue;
    if (reinterpret_cast<const dtMeshHeader*>(bytes.data())->polyCount > built.params.maxPolys)
      throw std::runtime_error(name +
                               ": a tile has more polygons than its reference bits hold: use a smaller tile_size");
    info.polygons += reinterpret_cast<const dtMeshHeader*>(bytes.data())->polyCount;
    info.bytes += bytes.size();
    built.tiles.push_back({i % layout.tiles_x, i / layout.tiles_x, std::move(bytes)});
  }
  if (built.tiles.empty())
    throw std::runtime_error(name +
                             ": no walkable polygon (is the ground covered by obstacles, or narrower than "
                             "two agent radii?)");
  mesh->impl_->mesh = make_detour(built);
  if (!mesh->impl_->mesh) throw std::runtime_error(name + ": Detour refused the navigation mesh");
  info.build_ms = ms_since(t0);
  if (file) {
    save_cache(*file, key, built);
    info.cache_file = file->string();
  }
  return mesh;
}

std::vector<std::vector<glm::vec2>> NavMesh::polygons() const {
  std::vector<std::vector<glm::vec2>> out;
  const dtNavMesh& mesh = *impl_->mesh;
  for (int i = 0; i < mesh.getMaxTiles(); ++i) {
    const dtMeshTile* tile = mesh.getTile(i);
    if (!tile || !tile->header) continue;
    for (int p = 0; p < tile->header->polyCount; ++p) {
      const dtPoly& poly = tile->polys[p];
      if (poly.getType() != DT_POLYTYPE_GROUND) continue;
      std::vector<glm::vec2> outline;
      for (int v = 0; v < poly.vertCount; ++v) {
        const float* q = &tile->verts[poly.verts[v] * 3];
        outline.emplace_back(q[0], q[2]);
      }
      // Detour winds its polygons clockwise in (x, z) read as (x, y); returned counter-clockwise like the
      // scenario's obstacles (components/scenario.h).
      double area = 0.0;
      for (std::size_t k = 0; k < outline.size(); ++k)
        area += static_cast<double>(outline[k].x) * outline[(k + 1) % outline.size()].y -
                static_cast<double>(outline[(k + 1) % outline.size()].x) * outline[k].y;
      if (area < 0.0) std::reverse(outline.begin(), outline.end());
      out.push_back(std::move(outline));
    }
  }
  return out;
}

// --- NavQuery ----------------------------------------------------------------------------------------------

struct NavQuery::Impl {
  const NavMesh::Impl* mesh = nullptr;
  dtNavMeshQuery* query = nullptr;
  dtQueryFilter filter;
  std::vector<dtPolyRef> path = std::vector<dtPolyRef>(kMaxPathPolys);
  std::vector<float> straight;
  std::vector<dtPolyRef> straight_refs;
  std::vector<unsigned char> straight_flags;
  ~Impl() { dtFreeNavMeshQuery(query); }

  // Whether the straight segment from a (on the mesh, within a millimetre) to b crosses no mesh boundary.
  bool ray_clear(glm::vec2 a, glm::vec2 b) {
    float start[3];
    const dtPolyRef ref = nearest(a, 1e-3f, start);
    if (!ref) return false;
    const float end[3] = {b.x, start[1], b.y};
    float t = 0.0f, normal[3];
    int visited = 0;
    if (dtStatusFailed(query->raycast(ref, start, end, &filter, &t, normal, path.data(), &visited, kMaxPathPolys)))
      return false;
    // t is FLT_MAX when the ray reached the end without crossing a wall. A full corridor buffer is inconclusive.
    return t > 1.0f && visited < kMaxPathPolys;
  }

  // The polygon nearest p within `reach` metres horizontally, and the point on it.
  dtPolyRef nearest(glm::vec2 p, float reach, float* on) const {
    const float center[3] = {p.x, mesh->y_center, p.y};
    const float extents[3] = {reach, mesh->y_extent, reach};
    dtPolyRef ref = 0;
    if (dtStatusFailed(query->findNearestPoly(center, extents, &filter, &ref, on)) || ref == 0) return 0;
    // The search box is square; keep the promise of a distance.
    const float dx = on[0] - p.x, dz = on[2] - p.y;
    return dx * dx + dz * dz <= reach * reach * 1.0001f ? ref : 0;
  }
};

NavQuery::NavQuery(const NavMesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->mesh = mesh.impl_.get();
  impl_->query = dtAllocNavMeshQuery();
  if (!impl_->query || dtStatusFailed(impl_->query->init(mesh.impl_->mesh.get(), kQueryNodes)))
    throw std::runtime_error("NavQuery: Detour could not allocate its query");
  impl_->filter.setIncludeFlags(kWalkableFlag);
  impl_->filter.setExcludeFlags(0);
}

NavQuery::~NavQuery() = default;

NavPath NavQuery::find_path(glm::vec2 from, glm::vec2 to, std::size_t max_corners) {
  NavPath out;
  Impl& q = *impl_;
  if (!std::isfinite(from.x) || !std::isfinite(from.y) || !std::isfinite(to.x) || !std::isfinite(to.y)) return out;
  float start[3], goal[3];
  const dtPolyRef start_ref = q.nearest(from, kSnapDistance, start);
  if (!start_ref) return out;
  dtPolyRef goal_ref = q.nearest(to, kSnapDistance, goal);
  bool goal_reachable = goal_ref != 0;
  if (!goal_ref) {
    // A goal far off the mesh: head for the mesh point nearest to it, and say the goal is not reached. The
    // search box grows instead of spanning the whole mesh at once, so a near miss stays cheap.
    for (float reach = 4.0f * kSnapDistance; !goal_ref && reach < 1e5f; reach *= 4.0f)
      goal_ref = q.nearest(to, reach, goal);
    if (!goal_ref) return out;
  }
  // In sight: the straight line, without A*. Besides being cheaper on open ground, this avoids the bends A*
  // over large polygons leaves in a corridor (its cost runs through edge midpoints, so the corridor it picks need
  // not contain the straight line: a circle path from (100, 30) to (-100, -30) came back with a 3 m detour).
  if (goal_reachable && q.ray_clear({start[0], start[2]}, {goal[0], goal[2]})) {
    out.corners.emplace_back(goal[0], goal[2]);
    out.complete = true;
    return out;
  }
  int count = 0;
  const dtStatus status =
      q.query->findPath(start_ref, goal_ref, start, goal, &q.filter, q.path.data(), &count, kMaxPathPolys);
  if (dtStatusFailed(status) || count == 0) return out;
  float end[3] = {goal[0], goal[1], goal[2]};
  const bool partial =
      dtStatusDetail(status, DT_PARTIAL_RESULT) || q.path[static_cast<std::size_t>(count - 1)] != goal_ref;
  if (partial) {
    // The path stops at the reachable polygon nearest to the goal: end at its point nearest to the goal.
    if (dtStatusFailed(q.query->closestPointOnPoly(q.path[static_cast<std::size_t>(count - 1)], goal, end, nullptr)))
      return out;
  }
  // Detour's string pulling keeps a corner wherever the straight line passes exactly through a polygon vertex
  // (tile seams on open ground do this: the circle's diagonal paths came back with 4 collinear corners). Those
  // are dropped below, so more points are asked for than corners returned; a path with more real corners than
  // that is simply cut, as max_corners allows.
  const std::size_t wanted = std::min<std::size_t>(std::max<std::size_t>(max_corners, 1), 1 << 16);
  const int max_points = static_cast<int>(2 * wanted + 8);
  q.straight.resize(static_cast<std::size_t>(max_points) * 3);
  q.straight_refs.resize(static_cast<std::size_t>(max_points));
  q.straight_flags.resize(static_cast<std::size_t>(max_points));
  int points = 0;
  if (dtStatusFailed(q.query->findStraightPath(start, end, q.path.data(), count, q.straight.data(),
                                               q.straight_flags.data(), q.straight_refs.data(), &points, max_points)))
    return out;
  // The first point is the (snapped) start; the corners follow it. A corner within 1 mm of the line from the
  // last kept point to the next one, and between them, is not a turn.
  glm::vec2 prev(q.straight[0], q.straight[2]);
  for (int i = 1; i < points && out.corners.size() < wanted; ++i) {
    const glm::vec2 c(q.straight[i * 3], q.straight[i * 3 + 2]);
    if (i + 1 < points) {
      const glm::vec2 next(q.straight[(i + 1) * 3], q.straight[(i + 1) * 3 + 2]);
      const glm::vec2 d = next - prev, e = c - prev;
      const float len = std::sqrt(d.x * d.x + d.y * d.y);
      const float along = len > 0.0f ? (d.x * e.x + d.y * e.y) / len : -1.0f;
      if (len > 0.0f && std::fabs(d.x * e.y - d.y * e.x) / len < 1e-3f && along > 0.0f && along < len) continue;
    }
    out.corners.push_back(c);
    prev = c;
  }
  // The same bends further along: a corner is dropped when the point after it is in sight of the one before
  // (one greedy pass, a ray cast per corner; the start and the kept corners are on the mesh).
  if (out.corners.size() >= 2) {
    std::vector<glm::vec2> kept;
    glm::vec2 from(start[0], start[2]);
    for (std::size_t i = 0; i < out.corners.size(); ++i) {
      if (i + 1 < out.corners.size() && q.ray_clear(from, out.corners[i + 1])) continue;
      kept.push_back(out.corners[i]);
      from = out.corners[i];
    }
    out.corners = std::move(kept);
  }
  if (out.corners.empty()) out.corners.emplace_back(end[0], end[2]);
  out.complete = goal_reachable && !partial;
  return out;
}

std::optional<glm::vec2> NavQuery::nearest_walkable(glm::vec2 p, float search) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(search) || search < 0.0f) return std::nullopt;
  float on[3];
  if (!impl_->nearest(p, std::max(search, 1e-3f), on)) return std::nullopt;
  return glm::vec2(on[0], on[2]);
}

bool NavQuery::walkable_line(glm::vec2 a, glm::vec2 b) {
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) return false;
  if (impl_->ray_clear(a, b)) return true;
  // A path's corners lie on the mesh boundary (string pulling wraps them round the eroded obstacles), and a ray
  // from one to the next runs along a boundary edge, which Detour reports as a hit. The segment also counts as
  // walkable when a copy shifted sideways by kSideTolerance on either side is clear. Rejected: shrinking the
  // segment at its ends, which does not help a segment lying along an edge for its whole length.
  const glm::vec2 d = b - a;
  const float len = std::sqrt(d.x * d.x + d.y * d.y);
  if (len <= 0.0f) return false;
  const glm::vec2 side = glm::vec2(-d.y, d.x) * (kSideTolerance / len);
  return impl_->ray_clear(a + side, b + side) || impl_->ray_clear(a - side, b - side);
}

}  // namespace strata
