#include "systems/avoidance.h"

// Measured (bench/avoidance_bench.cpp, Release, GCC 12, a jittered grid of ~1 agent per 2 m^2 walking to random
// goals, 6 box obstacles, default parameters: 12 neighbours within 4 m, horizons 2 s / 0.6 s) on the 2-core AMD
// EPYC development machine (nproc 2), which another engineer's build kept at a load of 2 to 4.7 throughout; best
// of repeated runs (wall time per step), taken in the quietest minute (load 2.05):
//   10,000 agents, two threads: 5.33 ms with the second pass (the default), 4.83 ms without it (issue 16's target
//                  is 5 ms); most runs under load read 9-12 ms, the build holding the second core.
//   10,000 agents, one thread: 9.6 ms.      1,000 agents: two threads 0.44 ms, one thread 0.96 ms.
// Where the time goes (perf, callgrind): about 70 % of an agent's ~0.9 us is the neighbour search, the rest the
// half-planes and the linear program. Since then the search takes each cell's distance as a row's plus a
// column's, computed once per agent (2026-11-27, an idle VM, 5 repetitions each, builds alternated twice):
// 10,000 agents, two threads, 5.18-5.25 -> 4.57-4.71 ms (mean), the same velocities bit for bit. Rejected, same
// machine and method: the kept neighbours as a max-heap (the farthest on top, replaced and sifted down in log k
// moves, sorted at the end) instead of keep_nearest's sorted list: 5.72-5.80 against 4.69-4.77 ms. perf names the
// list's shift the search's hottest instruction, but with 12 kept most candidates exit at the first comparison.
// 2026-11-28: 10,000 agents, two threads, halves 4.51 -> 4.04 ms and the crowds' settings 7.00 -> 5.85 ms (old and
// new built alike, alternated; docs/crowds.md) with the list filled unsorted then sorted once, one admission test
// per candidate, and the second pass reading the first's neighbour lists; then the pair rules over gathered
// neighbours, branch-free (NeighbourBatch): the crowds' settings 5.72 ms, halves 4.24 ms against 7.37 / 4.82 for
// the day's starting code in the same runs; then the search's cells visited nearest-first by quadrant (-2.6 %);
// then the search by rows of cells, distances 16 at a time into a bit mask (crowds' settings -3 to -4 %), a
// sorting network for the full list (-4 %), the runs four at a time with SSE2 (-4 %) and the second pass reading
// the first's preferred velocities (-3 %): against the day's start, alternated before the last step, 5.43 -> 4.60
// ms at the crowds' settings and 3.97 -> 3.27 ms with halves; the same velocities bit for bit throughout.

// The half-plane form used throughout: a constraint is {v : dot(v - point, normal) >= 0} with |normal| = 1, the
// permitted side being where the normal points. The paper and RVO2 describe a line by a point and a direction
// with the permitted side on the left; a normal is the same information (direction = (normal.y, -normal.x)) and
// makes "how far is v on the wrong side" a single dot product, which the 3-D fallback needs for every line.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/common.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {
namespace {

using glm::vec2;

float dot2(vec2 a, vec2 b) { return a.x * b.x + a.y * b.y; }
float det2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }
float length_squared(vec2 a) { return dot2(a, a); }

// The fallback weighs a neighbour's half-plane by 1 / max(gap, this) (m; gap = centre distance minus the radii):
// a violation of v m/s against a neighbour g metres away closes the gap in about g / v seconds, so minimising the
// largest weighted violation maximises the shortest time to contact rather than treating a neighbour 3 m away
// like one touching. Measured on a 128-agent circle: it does not remove the centre jam's overlaps (see the test),
// but it moves the remaining violation onto the far neighbours where it is harmless for longer.
constexpr float kMinWeightGap = 0.01f;

// Below this squared length a vector has no usable direction (1e-6 m/s or m).
constexpr float kTinySquared = 1e-12f;
// Two half-plane boundaries closer to parallel than this (|sin| of the angle) are treated as parallel.
constexpr float kParallel = 1e-6f;

// a / |a|, or `fallback` when a is too short to have a direction.
vec2 direction_or(vec2 a, vec2 fallback) {
  const float l2 = length_squared(a);
  if (!(l2 > kTinySquared)) return fallback;
  const float inv = 1.0f / std::sqrt(l2);
  return {a.x * inv, a.y * inv};
}

struct HalfPlane {
  vec2 point;
  vec2 normal;          // unit; permitted where dot(v - point, normal) >= 0
  float weight;  // how much a violation of it counts in the fallback (solve_minimax); a neighbour's plane gets
                 // it only there (agent_plane_weight). No default member initialiser: it would make the
                 // per-agent arrays of 96 planes be filled on every call.
};

float violation(const HalfPlane& h, vec2 v) { return -dot2(v - h.point, h.normal); }

// ---- The linear programs --------------------------------------------------------------------------------------
// Incremental 2-D LP (Seidel's idea without the shuffle: the order is fixed, so the result is deterministic):
// the optimum is kept while it satisfies each new half-plane; when it does not, the new optimum lies on that
// half-plane's boundary and is found by a 1-D LP along it against the half-planes before it and the speed disc.

// On the boundary of planes[index]: the point that best meets the goal among those satisfying planes[0..index)
// and |v| <= max_speed. Goal: nearest to `target`, or farthest along `target` when `direction_mode`. False when
// that set is empty (result untouched).
bool solve_on_boundary(const HalfPlane* planes, std::size_t index, float max_speed, vec2 target,
                       bool direction_mode, vec2& result) {
  const HalfPlane& h = planes[index];
  const vec2 along(h.normal.y, -h.normal.x);  // unit direction of the boundary line
  // |point + t along|^2 <= max_speed^2
  const float b = dot2(h.point, along);
  const float disc = b * b + max_speed * max_speed - length_squared(h.point);
  if (disc < 0.0f) return false;
  const float root = std::sqrt(disc);
  float t_low = -b - root, t_high = -b + root;
  for (std::size_t j = 0; j < index; ++j) {
    const HalfPlane& other = planes[j];
    // dot(point + t along - other.point, other.normal) >= 0  <=>  t * denom >= numer
    const float denom = dot2(along, other.normal);
    const float numer = dot2(other.point - h.point, other.normal);
    if (std::fabs(denom) <= kParallel) {
      if (numer > 0.0f) return false;  // this boundary lies wholly on the forbidden side of `other`
      continue;
    }
    const float t = numer / denom;
    if (denom > 0.0f) t_low = std::max(t_low, t);
    else t_high = std::min(t_high, t);
    if (t_low > t_high) return false;
  }
  float t;
  if (direction_mode) t = dot2(target, along) > 0.0f ? t_high : t_low;
  else t = std::clamp(dot2(target - h.point, along), t_low, t_high);
  result = h.point + t * along;
  return true;
}

// Returns the number of planes satisfied in order: count on success; otherwise the index of the first half-plane
// that could not be met together with those before it (result is then the optimum for planes[0..index)).
std::size_t solve_2d(const HalfPlane* planes, std::size_t count, float max_speed, vec2 target, bool direction_mode,
                     vec2& result) {
  if (direction_mode) {
    result = target * max_speed;  // target is a unit direction here
  } else if (length_squared(target) > max_speed * max_speed) {
    result = direction_or(target, vec2(0.0f)) * max_speed;
  } else {
    result = target;
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (violation(planes[i], result) > 0.0f) {
      const vec2 before = result;
      if (!solve_on_boundary(planes, i, max_speed, target, direction_mode, result)) {
        result = before;
        return i;
      }
    }
  }
  return count;
}

// The fallback when the half-planes leave no velocity (the paper's 3-D LP, section 5.2 there): planes[0..hard)
// stay hard; among the rest, minimise the largest violation. Walking the soft planes in order from `first_failed`,
// each one violated by more than the current worst becomes the plane to improve: the velocity is pushed as far as
// possible into it while no earlier soft plane becomes worse than it (the bisector of the two boundaries) and the
// hard ones hold. `projected` is scratch of the same capacity as planes.
void solve_minimax(const HalfPlane* planes, std::size_t count, std::size_t hard, std::size_t first_failed,
                   float max_speed, HalfPlane* projected, vec2& result) {
  float worst = 0.0f;
  for (std::size_t i = std::max(first_failed, hard); i < count; ++i) {
    const float violated_by = planes[i].weight * violation(planes[i], result);
    if (!(violated_by > worst)) continue;
    std::size_t n = 0;
    for (std::size_t j = 0; j < hard; ++j) projected[n++] = planes[j];
    const vec2 wi = planes[i].weight * planes[i].normal;
    for (std::size_t j = hard; j < i; ++j) {
      // Where plane j is (weighted) violated no more than plane i:
      //   dot(v, wj nj - wi ni) >= wj dot(pj, nj) - wi dot(pi, ni).
      const vec2 wj = planes[j].weight * planes[j].normal;
      const vec2 m = wj - wi;
      const float m2 = length_squared(m);
      const float scale = kParallel * (planes[i].weight + planes[j].weight);
      // m ~ 0: the difference of the two weighted violations is a constant, already <= 0 here (i is the worse).
      if (m2 <= scale * scale) continue;
      const float m_length = std::sqrt(m2);
      const vec2 unit = m / m_length;
      const float offset = (dot2(planes[j].point, wj) - dot2(planes[i].point, wi)) / m_length;
      projected[n++] = HalfPlane{unit * offset, unit, 1.0f};
    }
    const vec2 before = result;
    if (solve_2d(projected, n, max_speed, planes[i].normal, true, result) < n) {
      // Only rounding can get here (the velocity before satisfied all of them); keep it rather than a half-step.
      result = before;
    }
    worst = planes[i].weight * violation(planes[i], result);
  }
}

// ---- Neighbour selection ---------------------------------------------------------------------------------------
// The k nearest by (squared distance, index): a total order, so the kept set and its order (which the LP's
// result depends on through rounding) are the same whatever order candidates arrive in: grid or brute force,
// any chunking.
//
// The pair is packed into one 64-bit key, the distance's bits above the index: a non-negative float's bit pattern
// orders like its value, so one integer comparison is the lexicographic one (comparing the float and then the
// index compiles to a NaN-aware branch pair; callgrind: 2.5 % fewer instructions for the job, 2 % fewer
// mispredicted branches). Squared distances here are never negative or NaN: validate() sees to that.
struct Nearest {
  std::uint64_t key;
  Nearest() = default;  // uninitialised: the lists are filled before they are read
  Nearest(float squared_distance, std::uint32_t index)
      : key(static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(squared_distance)) << 32 | index) {}
  float d2() const { return std::bit_cast<float>(static_cast<std::uint32_t>(key >> 32)); }
  std::uint32_t index() const { return static_cast<std::uint32_t>(key); }
};

bool closer(const Nearest& a, const Nearest& b) { return a.key < b.key; }

// Inserts into the sorted list items[0..count) of capacity `capacity`, dropping the last when full. One loop that
// finds the place and shifts as it goes (two loops, find then shift, mispredicted their exits twice as often).
// Forced inline: it runs for every candidate of the neighbour search, and as a call it was a quarter of the job.
[[gnu::always_inline]] inline void keep_nearest(Nearest* items, std::uint32_t& count, std::uint32_t capacity,
                                                Nearest candidate) {
  if (count == capacity && !closer(candidate, items[count - 1])) return;
  std::uint32_t k = count < capacity ? count : capacity - 1;
  while (k > 0 && closer(candidate, items[k - 1])) {
    items[k] = items[k - 1];
    --k;
  }
  items[k] = candidate;
  if (count < capacity) ++count;
}

// Sorts items[0..count) by key, ascending. Twelve (the default max_neighbors, the list's usual size when it
// fills) through a sorting network, branch-free: 39 compare-exchanges in 9 layers (the smallest known for 12,
// checked below). std::sort's insertion sort of 12 random keys mispredicted its inner loop's exit at nearly every
// key: perf put a fifth of the neighbour search there. 10,000 agents, two threads, alternated builds, medians of
// 6 (2026-11-28): the crowds' settings 5.43 -> 5.20 ms, the paper's halves 4.42 -> 4.09 ms, the same velocities
// bit for bit.
inline constexpr std::array<std::array<std::uint8_t, 2>, 39> kSortTwelve{{
    {0, 8}, {1, 7}, {2, 6}, {3, 11}, {4, 10}, {5, 9},  {0, 1}, {2, 5}, {3, 4}, {6, 9}, {7, 8}, {10, 11}, {0, 2},
    {1, 6}, {5, 10}, {9, 11}, {0, 3}, {1, 2}, {4, 6}, {5, 7}, {8, 11}, {9, 10}, {1, 4}, {3, 5}, {6, 8}, {7, 10},
    {1, 3}, {2, 5}, {6, 9}, {8, 10}, {2, 3}, {4, 5}, {6, 7}, {8, 9}, {4, 6}, {5, 7}, {3, 4}, {5, 6}, {7, 8}}};

// The 0-1 principle: a comparator network that sorts every sequence of zeros and ones sorts every sequence.
// Checked when compiling, so a mistyped comparator cannot build: all 4,096 inputs at once, one bit per input
// (wire[i][w] bit b: input 64 w + b has a one on wire i), a compare-exchange being AND (the min) and OR (the max).
// Rejected: each input in turn, which passed GCC's constexpr limit but exceeded clang's (1,048,576 steps).
constexpr bool sorts_every_zero_one_input() {
  constexpr std::uint64_t kLowBits[6] = {0xAAAAAAAAAAAAAAAAull, 0xCCCCCCCCCCCCCCCCull, 0xF0F0F0F0F0F0F0F0ull,
                                         0xFF00FF00FF00FF00ull, 0xFFFF0000FFFF0000ull, 0xFFFFFFFF00000000ull};
  std::array<std::array<std::uint64_t, 64>, 12> wire{};
  for (std::uint32_t i = 0; i < 12; ++i)
    for (std::uint32_t w = 0; w < 64; ++w)
      wire[i][w] = i < 6 ? kLowBits[i] : (((w >> (i - 6)) & 1u) != 0 ? ~0ull : 0ull);
  for (const auto& c : kSortTwelve)
    for (std::uint32_t w = 0; w < 64; ++w) {
      const std::uint64_t a = wire[c[0]][w], b = wire[c[1]][w];
      wire[c[0]][w] = a & b;
      wire[c[1]][w] = a | b;
    }
  for (std::uint32_t i = 1; i < 12; ++i)
    for (std::uint32_t w = 0; w < 64; ++w)
      if ((wire[i - 1][w] & ~wire[i][w]) != 0) return false;  // a one above a zero: unsorted
  return true;
}
static_assert(sorts_every_zero_one_input(), "kSortTwelve is not a sorting network");

void sort_nearest(Nearest* items, std::uint32_t count) {
  if (count == 12) {
    std::uint64_t k[12];
    for (int i = 0; i < 12; ++i) k[i] = items[i].key;
    for (const auto& [a, b] : kSortTwelve) {
      const std::uint64_t lo = k[a] < k[b] ? k[a] : k[b], hi = k[a] < k[b] ? k[b] : k[a];
      k[a] = lo;
      k[b] = hi;
    }
    for (int i = 0; i < 12; ++i) items[i].key = k[i];
    return;
  }
  std::sort(items, items + count, closer);
}

// The same for obstacle edges, which arrive once per grid cell they cross: an exact duplicate is dropped.
void keep_nearest_unique(Nearest* items, std::uint32_t& count, std::uint32_t capacity, Nearest candidate) {
  for (std::uint32_t k = 0; k < count; ++k)
    if (items[k].key == candidate.key) return;
  keep_nearest(items, count, capacity, candidate);
}

// The closest point of an edge to p, exactly an endpoint when clamped, so the two edges meeting at a corner give
// bit-identical distances there. where: 0 at a, 1 between, 2 at b.
vec2 closest_on_edge(const ObstacleSet::Edge& e, vec2 p, int& where) {
  const float t = dot2(p - e.a, e.direction);
  if (t <= 0.0f) {
    where = 0;
    return e.a;
  }
  if (t >= e.length) {
    where = 2;
    return e.b;
  }
  where = 1;
  return e.a + t * e.direction;
}

// Signed distance of p from the edge's line: > 0 on the free (right) side.
float free_side(const ObstacleSet::Edge& e, vec2 p) { return det2(p - e.a, e.direction); }

vec2 outward_normal(const ObstacleSet::Edge& e) { return {e.direction.y, -e.direction.x}; }

// ---- One agent -------------------------------------------------------------------------------------------------
struct Agents {
  const AvoidanceJob& job;
  vec2 position(std::uint32_t i) const { return {job.px[i], job.pz[i]}; }
  vec2 velocity(std::uint32_t i) const { return {job.vx[i], job.vz[i]}; }
};

constexpr std::size_t kMaxPlanes = kAvoidanceMaxNeighbors + kAvoidanceMaxObstacleEdges + 1;  // + the tether

// A deterministic unit direction from a hash of a number (splitmix64's finaliser).
vec2 hashed_direction(std::uint64_t key) {
  key ^= key >> 33;
  key *= 0xff51afd7ed558ccdULL;
  key ^= key >> 33;
  key *= 0xc4ceb9fe1a85ec53ULL;
  key ^= key >> 33;
  const float angle = static_cast<float>(key & 0xffffu) * (6.28318530718f / 65536.0f);
  return {std::cos(angle), std::sin(angle)};
}

// The direction `self` leaves `other` in when the two are at the same spot moving alike (opposite for the other
// one). Each agent gets its own hashed heading d and leaves along d_self - d_other: then moving along d_self makes
// progress against every coincident neighbour at once (dot(d_self, d_self - d_k) = 1 - cos >= 0), so a pile of
// agents dropped on one point fans out. Rejected: one hashed direction per pair, which for a pile of several can
// put zero velocity at the fallback's optimum, and the pile never comes apart.
vec2 separation_direction(std::uint32_t self, std::uint32_t other) {
  const vec2 d = hashed_direction(self) - hashed_direction(other);
  if (length_squared(d) > 1e-6f) return d / std::sqrt(length_squared(d));
  const std::uint32_t lo = std::min(self, other), hi = std::max(self, other);
  const vec2 pair = hashed_direction((static_cast<std::uint64_t>(lo) << 32) ^ hi ^ 0x9e3779b97f4a7c15ULL);
  return self == lo ? -pair : pair;
}

// What agent i's pair computations read of its neighbours, gathered once per agent (SoA, in the neighbours'
// order): the right of way and the passing side run branch-free over these in loops the compiler vectorises. As
// per-pair functions with early exits they were a fifth of the job at the crowds' settings (perf and a cycle
// count per agent on the benchmark's crowd: whether two agents go the same way or meet head-on is a coin toss
// in a mixed crowd, and so were the branches). Every value is computed as the per-pair code did, in the same
// order, and selected: the same bits.
struct NeighbourBatch {
  std::uint32_t count = 0;
  std::array<float, kAvoidanceMaxNeighbors> rel_x, rel_z;    // p_j - p_i
  std::array<float, kAvoidanceMaxNeighbors> wish_x, wish_z;  // j's preferred velocity
  std::array<float, kAvoidanceMaxNeighbors> vel_x, vel_z;    // j's current velocity
  std::array<float, kAvoidanceMaxNeighbors> radii;           // r_i + r_j
  std::array<std::uint8_t, kAvoidanceMaxNeighbors> held;     // j holds still this step (AvoidanceJob::holds)
};

void gather_neighbours(const AvoidanceJob& job, std::uint32_t i, const Nearest* neighbours, std::uint32_t count,
                       NeighbourBatch& b) {
  b.count = count;
  const bool any_holds = !job.holds.empty();
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::uint32_t j = neighbours[k].index();
    b.rel_x[k] = job.px[j] - job.px[i];
    b.rel_z[k] = job.pz[j] - job.pz[i];
    b.wish_x[k] = job.pref_vx[j];
    b.wish_z[k] = job.pref_vz[j];
    b.vel_x[k] = job.vx[j];
    b.vel_z[k] = job.vz[j];
    b.radii[k] = job.radius[i] + job.radius[j];
    b.held[k] = any_holds && job.holds[j] != 0 ? 1 : 0;
  }
}

// How much more than half of the avoidance between i and each neighbour j agent i takes
// (AvoidanceParameters::right_of_way), into shift[0..count): positive when j is ahead of it on their common way, 0
// unless both prefer to move within 60 deg of each other. Exactly the negation of j's (pj - pi and pi - pj,
// pref_i + pref_j in either order, round alike), so the two shares add up to 1 (to the rounding of 0.5 + s).
// Rejected, over four bottleneck seeds: the heading test at 90 deg (89 % in after 240 s on average against 94 %),
// and the shift gated on both moving slower than they want (91.5 %, and 2 of 4 crossing runs left an agent short of
// its goal).
void right_of_way_shifts(const AvoidanceJob& job, std::uint32_t i, const NeighbourBatch& b, float* shift) {
  const float aix = job.pref_vx[i], aiz = job.pref_vz[i];
  const float vix = job.vx[i], viz = job.vz[i];
  const float li = aix * aix + aiz * aiz;
  constexpr float kMinPreferred2 = 1e-4f;  // (1 cm/s)^2: an agent that wants to stand has no way to lead on
  constexpr float kCosSameWay2 = 0.5f * 0.5f;  // 60 deg
  const float row = job.params.right_of_way, fade = job.params.right_of_way_back_fade;
  const bool lead_on = li > kMinPreferred2;
  for (std::uint32_t k = 0; k < b.count; ++k) {
    const float ajx = b.wish_x[k], ajz = b.wish_z[k];
    const float lj = ajx * ajx + ajz * ajz;
    // Within 60 deg: along > 0 and along^2 > cos^2 li lj (no square root).
    const float along = aix * ajx + aiz * ajz;
    const bool same_way = lead_on & (lj > kMinPreferred2) & (along > 0.0f) & (along * along > kCosSameWay2 * li * lj);
    const float way_x = aix + ajx, way_z = aiz + ajz;
    const float along_way = b.rel_x[k] * way_x + b.rel_z[k] * way_z;
    const float radii = b.radii[k];
    const float way2 = way_x * way_x + way_z * way_z;
    const float way_length = std::sqrt(way2);  // > 0 where it is used: the two are within 60 deg
    // The one ahead moving back along the way loses its right of way (right_of_way_back_fade). Both agents of the
    // pair compute the same leader (along_way only changes sign between them, and `way` is the same sum), from the
    // same velocity, so their shifts stay each other's negation.
    const bool j_leads = along_way > 0.0f;
    const float vjx = b.vel_x[k], vjz = b.vel_z[k];  // loaded either way: a load in one arm only blocks the select
    const float back = -((j_leads ? vjx : vix) * way_x + (j_leads ? vjz : viz) * way_z);
    const bool fading = (fade > 0.0f) & (along_way != 0.0f) & (back > 0.0f);
    const float faded = row * std::max(0.0f, 1.0f - (back / way_length) / fade);
    const float lead = fading ? faded : row;
    // Most neighbours are more than the radii's sum ahead or behind: the clamp gives exactly +-1 there.
    const bool beyond = along_way * along_way > 1.001f * way2 * radii * radii;
    const float ahead = std::clamp(along_way / (way_length * radii), -1.0f, 1.0f);
    const float value = beyond ? (j_leads ? lead : -lead) : lead * ahead;
    shift[k] = same_way ? value : 0.0f;
  }
}

// Agent i's half-plane against neighbour j (the paper's ORCA_{i|j}): u is the smallest change of the relative
// velocity that leaves the truncated velocity obstacle, n its outward normal there; i takes half of u.
// The first pass's answers, for the second pass over the agents the first left without a permitted velocity.
struct FirstPass {
  const float* vx;
  const float* vz;
  const std::uint8_t* infeasible;
  // The first pass's preferred velocities (after the passing side) of the agents it left infeasible; null: the
  // second pass computes them again (the same values).
  const float* preferred_x = nullptr;
  const float* preferred_z = nullptr;
};

// `first` null: the ordinary ORCA half-plane from the current velocities, each side taking half. Otherwise (the
// second pass): from both agents' first-pass velocities; a neighbour whose first pass succeeded keeps its answer,
// so this agent takes the whole of the avoidance against it; one that failed too recomputes, so the half again.
// `right_of_way_shift` is this pair's from right_of_way_shifts, added to the half in the first pass.
// 1 / time_horizon and 1 / dt, divided once per agent rather than per pair.
struct Inverses {
  float tau, dt;
  explicit Inverses(const AvoidanceParameters& p) : tau(1.0f / p.time_horizon), dt(1.0f / p.dt) {}
};

// The velocities the first pass's half-planes are set about: each agent's back_off_velocity (the current velocity
// when back_off_limit is off).
struct PlaneVelocities {
  const float* x;
  const float* z;
};

// Every agent's back_off_velocity into x[0..n), z[0..n): the job (into its scratch) and the twin read the same.
void fill_back_off_velocities(const AvoidanceJob& job, float* x, float* z) {
  for (std::size_t i = 0; i < job.vx.size(); ++i) {
    const vec2 v = back_off_velocity({job.vx[i], job.vz[i]}, {job.pref_vx[i], job.pref_vz[i]}, job.params.back_off_limit);
    x[i] = v.x;
    z[i] = v.y;
  }
}

HalfPlane agent_plane(const AvoidanceJob& job, std::uint32_t i, std::uint32_t j, const FirstPass* first,
                      const PlaneVelocities& plane_v, const Inverses& inverse, float right_of_way_shift) {
  const AvoidanceParameters& prm = job.params;
  const vec2 pi(job.px[i], job.pz[i]), pj(job.px[j], job.pz[j]);
  const vec2 vi = first ? vec2(first->vx[i], first->vz[i]) : vec2(plane_v.x[i], plane_v.z[i]);
  vec2 vj = first ? vec2(first->vx[j], first->vz[j]) : vec2(plane_v.x[j], plane_v.z[j]);
  float share = first && first->infeasible[j] == 0 ? 1.0f : 0.5f;
  // A neighbour holding still this step takes no part: this agent avoids it wholly, where it stands. Counted on for
  // half, it stayed put while this one moved as if it would not (the crossing: agents held still 19,359 agent-steps
  // with an avoidance velocity over 5 cm/s, and in one run 3 pairs came 1.7 cm inside their radii).
  if (!job.holds.empty() && job.holds[j] != 0) {
    vj = vec2(0.0f);
    share = 1.0f;
  } else if (!first && prm.right_of_way > 0.0f) {
    share += right_of_way_shift;
  }
  const vec2 rel_p = pj - pi;
  const vec2 rel_v = vi - vj;
  const float dist2 = length_squared(rel_p);
  const float r = job.radius[i] + job.radius[j];
  const float r2 = r * r;
  vec2 u, n;
  if (dist2 > r2) {
    // Apart: VO is the cone from the origin tangent to the disc (rel_p / tau, r / tau), cut off at that disc.
    const float inv_tau = inverse.tau;
    const vec2 w = rel_v - rel_p * inv_tau;  // from the cut-off disc's centre
    const float w2 = length_squared(w);
    const float w_dot_p = dot2(w, rel_p);
    if (w_dot_p < 0.0f && w_dot_p * w_dot_p > r2 * w2 && w2 > kTinySquared) {
      // Nearest boundary point on the cut-off arc.
      const float w_length = std::sqrt(w2);
      n = w / w_length;
      u = (r * inv_tau - w_length) * n;
    } else {
      // Nearest boundary point on a leg: the tangent from the origin on rel_v's side of the axis.
      const float leg = std::sqrt(dist2 - r2);
      vec2 d;
      if (det2(rel_p, w) > 0.0f) {
        d = vec2(rel_p.x * leg - rel_p.y * r, rel_p.x * r + rel_p.y * leg) / dist2;  // axis turned left by asin(r/|p|)
        n = vec2(-d.y, d.x);
      } else {
        d = vec2(rel_p.x * leg + rel_p.y * r, -rel_p.x * r + rel_p.y * leg) / dist2;  // turned right
        n = vec2(d.y, -d.x);
      }
      u = dot2(rel_v, d) * d - rel_v;
    }
  } else {
    // Overlapping (the paper's collision case): the obstacle is the disc (rel_p / dt, r / dt), so the pair is
    // pushed apart within one step.
    const float inv_dt = inverse.dt;
    const vec2 w = rel_v - rel_p * inv_dt;
    const float w2 = length_squared(w);
    if (w2 > kTinySquared) {
      const float w_length = std::sqrt(w2);
      n = w / w_length;
      u = (r * inv_dt - w_length) * n;
    } else {
      // Moving exactly at the disc's centre (or coincident and moving alike): leave away from the neighbour.
      n = dist2 > kTinySquared ? -rel_p / std::sqrt(dist2) : separation_direction(i, j);
      u = r * inv_dt * n;
    }
  }
  // The weight only matters in the fallback, which most agents never reach: agent_plane_weight fills it in there
  // (a square root and a division per pair saved in a feasible solve).
  return HalfPlane{vi + share * u, n, 0.0f};
}

// The fallback's weight of agent i's half-plane against neighbour j (kMinWeightGap).
float agent_plane_weight(const AvoidanceJob& job, std::uint32_t i, std::uint32_t j) {
  const vec2 rel_p(job.px[j] - job.px[i], job.pz[j] - job.pz[i]);
  const float gap = std::sqrt(length_squared(rel_p)) - (job.radius[i] + job.radius[j]);
  return 1.0f / std::max(gap, kMinWeightGap);
}

// Collects agent i's obstacle half-planes into planes[0..); returns how many. Edges within reach (obstacle
// horizon times max speed, plus the radius) are taken nearest first. For an agent outside every polygon, each
// edge facing it gives the half-plane of the truncated velocity obstacle of that edge (the segment grown by the
// radius, seen over obstacle_time_horizon) tangent at its point nearest the zero velocity (the paper's choice of
// optimisation velocity for static obstacles, so standing still is always allowed):
// dot(v, toward) <= gap / horizon, `toward` pointing at the edge's nearest point. Edges facing
// away are skipped: reaching one means crossing a facing edge first (or, at a corner, the facing edge that shares
// the corner), whose half-plane already forbids it. Rejected: RVO2-style legs from each vertex, which let agents
// graze corners more tightly but need the neighbouring edges' geometry to stay consistent; the nearest-point
// half-plane is conservative, simpler to keep robust for collinear and concave outlines, and exact along a face.
//
// An agent whose centre is inside a polygon (decided at its nearest boundary point: between corners by the edge's
// side; at a corner by both edges' sides, convex corners needing both, reflex ones either) gets one half-plane:
// leave through that nearest point at up to its max speed, the other edges ignored (they would contradict it).
// An agent outside but overlapping an edge must move away by the overlap within one step, again capped at its max
// speed so the half-plane alone stays feasible.
template <class ForEachEdge>
std::size_t obstacle_planes(const AvoidanceJob& job, std::uint32_t i, const ForEachEdge& for_each_edge,
                            HalfPlane* planes) {
  const ObstacleSet* set = job.obstacles;
  if (set == nullptr || set->empty()) return 0;
  const auto& edges = set->edges();
  const vec2 p(job.px[i], job.pz[i]);
  const float r = job.radius[i];
  const float max_speed = job.max_speed[i];
  const float reach = job.params.obstacle_time_horizon * max_speed + r;
  const float reach2 = reach * reach;

  std::array<Nearest, kAvoidanceMaxObstacleEdges> facing;
  std::uint32_t facing_count = 0;
  Nearest nearest{std::numeric_limits<float>::infinity(), std::numeric_limits<std::uint32_t>::max()};
  for_each_edge([&](std::uint32_t e) {
    int where;
    const vec2 q = closest_on_edge(edges[e], p, where);
    const float d2 = length_squared(q - p);
    if (!(d2 < reach2)) return;
    const Nearest candidate{d2, e};
    if (closer(candidate, nearest)) nearest = candidate;
    if (free_side(edges[e], p) >= 0.0f)
      keep_nearest_unique(facing.data(), facing_count, kAvoidanceMaxObstacleEdges, candidate);
  });
  if (nearest.index() == std::numeric_limits<std::uint32_t>::max()) return 0;

  // Inside?
  const ObstacleSet::Edge& ne = edges[nearest.index()];
  int where;
  const vec2 q = closest_on_edge(ne, p, where);
  bool inside;
  if (where == 1) {
    inside = free_side(ne, p) < 0.0f;
  } else {
    const ObstacleSet::Edge& in = where == 0 ? edges[ne.prev] : ne;
    const ObstacleSet::Edge& out = where == 0 ? ne : edges[ne.next];
    const bool behind_in = free_side(in, p) < 0.0f, behind_out = free_side(out, p) < 0.0f;
    inside = out.convex_at_a ? (behind_in && behind_out) : (behind_in || behind_out);
  }
  if (inside) {
    const float d = std::sqrt(nearest.d2());
    const vec2 exit = direction_or(q - p, outward_normal(ne));
    const float need = std::min((d + r) / job.params.dt, max_speed);
    planes[0] = HalfPlane{exit * need, exit, 1.0f / kMinWeightGap};
    return 1;
  }

  const float inv_tau = 1.0f / job.params.obstacle_time_horizon;
  const float inv_dt = 1.0f / job.params.dt;
  for (std::uint32_t k = 0; k < facing_count; ++k) {
    const ObstacleSet::Edge& e = edges[facing[k].index()];
    int w;
    const vec2 qe = closest_on_edge(e, p, w);
    const float d = std::sqrt(facing[k].d2());
    const vec2 toward = direction_or(qe - p, -outward_normal(e));
    // dot(v, toward) <= limit, as {v : dot(v - toward * limit, -toward) >= 0}
    const float limit = d >= r ? (d - r) * inv_tau : std::max((d - r) * inv_dt, -max_speed);
    // Weighted like a neighbour at the same gap, for when the obstacle planes alone leave nothing and join the
    // fallback as soft ones.
    planes[k] = HalfPlane{toward * limit, -toward, 1.0f / std::max(d - r, kMinWeightGap)};
  }
  return facing_count;
}

// {v : dot(v, u) <= limit} for a unit u.
HalfPlane at_most_along(vec2 u, float limit) { return HalfPlane{u * limit, -u, 1.0f}; }

// Agent i's tether (AvoidanceJob::tether_dx): with e the agent's offset from its tether point and r = |e|,
// |e + v dt| <= reach is kept by dot(v, e / r) <= (reach - r) / dt, the disc's tangent at the point of e's
// direction (a step across it lengthens e by (v dt)^2 / 2r at most: 0.3 cm at 1.4 m/s, 30 fps, r 0.2 m, which the
// tether's user leaves room for). False when there is none or it cannot bind this step.
// Rejected beside it: caps on the speed across and against the preferred velocity (where the body faced), so a
// body goes no faster sideways or backwards than it steps: at 0.4-0.6 m/s the crossing's and the plaza's slides
// over 2 cm came 2-3 times as often as with agents facing where they go (systems/agent_move.h facing_direction).
bool tether_plane(const AvoidanceJob& job, std::uint32_t i, HalfPlane& out) {
  if (job.tether_reach.empty() || !(job.tether_reach[i] > 0.0f)) return false;
  const vec2 e(-job.tether_dx[i], -job.tether_dz[i]);
  const float r2 = length_squared(e);
  if (r2 < kTinySquared) return false;
  const float r = std::sqrt(r2);
  const float max_speed = job.max_speed[i];
  const float limit = std::max((job.tether_reach[i] - r) / job.params.dt, -max_speed);
  if (limit >= max_speed) return false;  // no velocity the agent may take reaches the tether's edge
  out = at_most_along(e / r, limit);
  return true;
}

// AvoidanceParameters::make_way for held agent i: the unit direction off the way of the nearest walking
// neighbour blocked against it, or 0. Reads the neighbours' current and preferred velocities only (this step's
// inputs), so it is the same in the parallel job, the scalar twin and across processes.
vec2 make_way_direction(const AvoidanceJob& job, std::uint32_t i, const Nearest* neighbours, std::uint32_t count) {
  constexpr float kPressGap = 0.15f;        // m between the bodies
  constexpr float kMinWish2 = 0.3f * 0.3f;  // (m/s)^2: a neighbour that wants to walk
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::uint32_t j = neighbours[k].index();
    if (!job.holds.empty() && job.holds[j] != 0) continue;
    const vec2 d(job.px[i] - job.px[j], job.pz[i] - job.pz[j]);
    const float reach = job.radius[i] + job.radius[j] + kPressGap;
    const float dist2 = length_squared(d);
    if (!(dist2 < reach * reach)) continue;
    const vec2 wish(job.pref_vx[j], job.pref_vz[j]);
    const float wish2 = length_squared(wish);
    if (!(wish2 > kMinWish2)) continue;
    const vec2 v(job.vx[j], job.vz[j]);
    if (!(length_squared(v) < 0.25f * wish2)) continue;  // moving at half its wish or more: not blocked
    const float toward = dot2(wish, d);                  // within 60 deg: toward > 0, toward^2 > 0.25 wish2 dist2
    if (!(toward > 0.0f && toward * toward > 0.25f * wish2 * dist2)) continue;
    const float wish_length = std::sqrt(wish2);
    const vec2 across(-wish.y / wish_length, wish.x / wish_length);
    const float side = dot2(d, across);
    // Straight ahead of it (within a millimetre): a side by index, the same whatever the thread count.
    const float sign = std::abs(side) > 1e-3f ? (side > 0.0f ? 1.0f : -1.0f) : (i < j ? 1.0f : -1.0f);
    return sign * across;
  }
  return vec2(0.0f);
}

// AvoidanceParameters::passing_angle: agent i's preferred velocity turned towards its passing side by the largest
// share of the angle that any head-on neighbour on a collision course calls for. Reads this step's
// inputs only (positions, preferred velocities), so it is the same in the parallel job, the scalar twin and across
// processes.
vec2 passing_preferred(const AvoidanceJob& job, std::uint32_t i, const NeighbourBatch& b) {
  const AvoidanceParameters& prm = job.params;
  const vec2 preferred(job.pref_vx[i], job.pref_vz[i]);
  const float pref2 = length_squared(preferred);
  constexpr float kMinWish2 = 0.1f * 0.1f;  // (m/s)^2: an agent that barely wants to move keeps to no side
  if (prm.passing_angle == 0.0f || !(pref2 > kMinWish2)) return preferred;
  const float pref_length = std::sqrt(pref2);
  const vec2 way = preferred / pref_length;
  const vec2 right(-way.y, way.x);  // the agent's right with y up (way x up)
  const float side = prm.passing_angle > 0.0f ? 1.0f : -1.0f;
  // Each neighbour's share computed in full and selected (see NeighbourBatch), the largest taken after.
  std::array<float, kAvoidanceMaxNeighbors> shares;
  for (std::uint32_t k = 0; k < b.count; ++k) {
    const float wx = b.wish_x[k], wz = b.wish_z[k];
    const float wish2 = wx * wx + wz * wz;
    const float facing = wx * way.x + wz * way.y;  // head-on: over 120 deg apart, cos < -0.5 (no square root)
    const float rx = b.rel_x[k], rz = b.rel_z[k];
    const float along = rx * way.x + rz * way.y;
    const float r = b.radii[k];
    // On a collision course: less than the radii's sum plus the margin across its way, on either side. (Turning
    // only where the other is not already on the passing side, so as never to turn towards it, kept the 500-agent
    // circle's jam less of a roundabout: 143 agents stuck on average over three seeds against 127; 1,000: 282
    // against 132-133.) A standing neighbour is avoided where it is: no side to agree on.
    // Bitwise on ints, not &&: every test evaluated, no branch (clang warns on & between bools).
    const int head_on = int(wish2 > kMinWish2) & int(facing < 0.0f) & int(facing * facing > 0.25f * wish2) &
                        int(along > 0.0f) & int(std::abs(rx * right.x + rz * right.y) < r + prm.passing_margin) &
                        int(b.held[k] == 0);
    // Full with passing_full_gap or less between the bodies along its way, none at neighbor_distance.
    const float fade = prm.neighbor_distance - r - prm.passing_full_gap;
    const float full = fade > 0.0f ? std::clamp((prm.neighbor_distance - along) / fade, 0.0f, 1.0f) : 1.0f;
    shares[k] = head_on != 0 ? full : 0.0f;
  }
  float share = 0.0f;
  for (std::uint32_t k = 0; k < b.count; ++k) share = std::max(share, shares[k]);
  if (share == 0.0f) return preferred;
  const float angle = std::abs(prm.passing_angle) * share;
  return pref_length * (std::cos(angle) * way + side * std::sin(angle) * right);
}

// Agent i's new velocity from its chosen neighbours (sorted) and obstacle edges.
template <class ForEachEdge>
vec2 solve_agent(const AvoidanceJob& job, std::uint32_t i, const Nearest* neighbours, std::uint32_t neighbour_count,
                 const ForEachEdge& for_each_edge, const FirstPass* first, const PlaneVelocities& plane_v,
                 bool& infeasible,
                 vec2* preferred_out = nullptr) {
  if (!job.holds.empty() && job.holds[i] != 0) {  // it stays where it is: its neighbours avoid it wholly
    infeasible = false;
    return job.params.make_way ? make_way_direction(job, i, neighbours, neighbour_count) : vec2(0.0f);
  }
  std::array<HalfPlane, kMaxPlanes> planes;
  std::array<HalfPlane, kMaxPlanes> projected;
  const std::size_t hard = obstacle_planes(job, i, for_each_edge, planes.data());
  std::size_t count = hard;
  const Inverses inverse(job.params);
  // The pair rules (right of way, passing side) read the neighbours gathered; the paper's halves need neither.
  const bool right_of_way = !first && job.params.right_of_way > 0.0f;
  const bool preferred_kept = first != nullptr && first->preferred_x != nullptr;
  NeighbourBatch batch;
  if (right_of_way || (job.params.passing_angle != 0.0f && !preferred_kept))
    gather_neighbours(job, i, neighbours, neighbour_count, batch);
  std::array<float, kAvoidanceMaxNeighbors> shift;
  if (right_of_way) right_of_way_shifts(job, i, batch, shift.data());
  for (std::uint32_t k = 0; k < neighbour_count; ++k)
    planes[count++] =
        agent_plane(job, i, neighbours[k].index(), first, plane_v, inverse, right_of_way ? shift[k] : 0.0f);

  const float max_speed = job.max_speed[i];
  const vec2 preferred = preferred_kept ? vec2(first->preferred_x[i], first->preferred_z[i])
                                        : passing_preferred(job, i, batch);
  if (preferred_out != nullptr) *preferred_out = preferred;
  vec2 result;
  const std::size_t failed = solve_2d(planes.data(), count, max_speed, preferred, false, result);
  infeasible = failed < count;
  // The tether, when the half-planes leave a velocity within it: the one nearest the preferred among those. The
  // half-planes' permitted set is unchanged, so is the guarantee avoidance gives every neighbour (each takes its
  // half of every avoidance); the tether only picks another velocity within it, and is let go for this step where
  // none is within it. Rejected: the tether as a hard plane like an obstacle's: in the crossing's jams tethered
  // agents could not give way and 345 pairs overlapped, by up to 49 cm.
  HalfPlane tether;
  if (!infeasible && tether_plane(job, i, tether) && violation(tether, result) > 0.0f) {
    planes[count] = tether;
    vec2 trial;
    if (solve_2d(planes.data(), count + 1, max_speed, preferred, false, trial) == count + 1) result = trial;
  }
  if (failed < count) {
    for (std::uint32_t k = 0; k < neighbour_count; ++k)
      planes[hard + k].weight = agent_plane_weight(job, i, neighbours[k].index());
    // Obstacles stay hard unless they alone leave nothing (the agent wedged in a corner it overlaps).
    const std::size_t keep_hard = failed < hard ? 0 : hard;
    solve_minimax(planes.data(), count, keep_hard, failed, max_speed, projected.data(), result);
    // The minimax optimum is often not unique (an agent squeezed between two neighbours may slide anywhere along
    // the squeeze), and the fallback's direction-mode LP then returns an arbitrary extreme of that set, at full
    // speed. So: relax every soft plane by the worst weighted violation found (plus a hair for rounding) and take
    // the velocity of that set nearest the preferred one, the ORCA objective again.
    float worst = 0.0f;
    for (std::size_t k = keep_hard; k < count; ++k)
      worst = std::max(worst, planes[k].weight * violation(planes[k], result));
    const float slack = worst * 1.001f + 1e-6f;
    for (std::size_t k = 0; k < count; ++k) {
      projected[k] = planes[k];
      if (k >= keep_hard) projected[k].point -= projected[k].normal * (slack / planes[k].weight);
    }
    vec2 relaxed;
    if (solve_2d(projected.data(), count, max_speed, preferred, false, relaxed) == count) result = relaxed;
  }
  // Belt and braces: the LPs keep |result| <= max_speed up to rounding; never hand out a NaN or an overshoot.
  if (!(std::isfinite(result.x) && std::isfinite(result.y))) return vec2(0.0f);
  // In double: a float square of a 1e-29 m/s rounding residue underflows to 0 and would slip past max_speed 0.
  const double l2 = static_cast<double>(result.x) * result.x + static_cast<double>(result.y) * result.y;
  if (l2 > static_cast<double>(max_speed) * max_speed) {
    const double scale = static_cast<double>(max_speed) / std::sqrt(l2);
    result = vec2(static_cast<float>(result.x * scale), static_cast<float>(result.y * scale));
  }
  return result;
}

// ---- The grid --------------------------------------------------------------------------------------------------
// Candidates the search takes at a time from a row's run (a mask of 16 bits; 32 measured no different).
inline constexpr std::uint32_t kSearchRun = 16;
static_assert(kSearchRun % 4 == 0 && kSearchRun <= 32, "whole SSE2 vectors, and a mask that fits 32 bits");

struct GridShape {
  double origin_x = 0.0, origin_z = 0.0, cell = 1.0;
  std::uint32_t cols = 1, rows = 1;
  std::uint32_t cell_of(float x, float z) const {
    const double fx = std::floor((static_cast<double>(x) - origin_x) / cell);
    const double fz = std::floor((static_cast<double>(z) - origin_z) / cell);
    const auto cx = static_cast<std::uint32_t>(std::clamp(fx, 0.0, static_cast<double>(cols - 1)));
    const auto cz = static_cast<std::uint32_t>(std::clamp(fz, 0.0, static_cast<double>(rows - 1)));
    return cz * cols + cx;
  }
};

// Cells half the neighbour distance wide, so a 5 x 5 block holds every neighbour in range (half-width cells let
// the search skip more of that area than a 3 x 3 block of full-width ones: ~10 % faster at 10,000 agents);
// widened when the crowd is spread so far that the grid would have many more cells than agents (bounding memory
// and the prefix sum).
GridShape grid_shape(const AvoidanceJob& job, std::size_t n) {
  double min_x = job.px[0], max_x = job.px[0], min_z = job.pz[0], max_z = job.pz[0];
  for (std::size_t i = 1; i < n; ++i) {
    min_x = std::min(min_x, static_cast<double>(job.px[i]));
    max_x = std::max(max_x, static_cast<double>(job.px[i]));
    min_z = std::min(min_z, static_cast<double>(job.pz[i]));
    max_z = std::max(max_z, static_cast<double>(job.pz[i]));
  }
  const double side_limit = std::clamp(std::ceil(std::sqrt(2.0 * static_cast<double>(n))), 16.0, 2048.0);
  GridShape g;
  g.origin_x = min_x;
  g.origin_z = min_z;
  g.cell = std::max({0.5 * static_cast<double>(job.params.neighbor_distance), (max_x - min_x) / (side_limit - 1.0),
                     (max_z - min_z) / (side_limit - 1.0)});
  g.cols = static_cast<std::uint32_t>(std::floor((max_x - min_x) / g.cell)) + 1;
  g.rows = static_cast<std::uint32_t>(std::floor((max_z - min_z) / g.cell)) + 1;
  return g;
}

bool finite_within(float v, float bound) { return std::isfinite(v) && std::fabs(v) <= bound; }

bool validate_job(const AvoidanceJob& job, bool need_scratch) {
  if (need_scratch && job.scratch == nullptr) return false;
  const AvoidanceParameters& p = job.params;
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!positive(p.time_horizon) || !positive(p.obstacle_time_horizon) || !positive(p.neighbor_distance) ||
      !positive(p.dt))
    return false;
  if (p.neighbor_distance > 2.0f * kAvoidanceMaxCoordinate) return false;
  if (p.max_neighbors == 0 || p.max_neighbors > kAvoidanceMaxNeighbors) return false;
  if (!(p.right_of_way >= 0.0f && p.right_of_way <= 0.5f)) return false;  // NaN too
  if (!(p.right_of_way_back_fade >= 0.0f && std::isfinite(p.right_of_way_back_fade))) return false;
  if (!std::isfinite(p.back_off_limit)) return false;  // negative is off
  // A turn past a right angle would walk away from the goal; NaN or a negative margin or gap never compares true.
  if (!(std::abs(p.passing_angle) <= 1.5707964f) || !(p.passing_margin >= 0.0f && std::isfinite(p.passing_margin)) ||
      !(p.passing_full_gap >= 0.0f && std::isfinite(p.passing_full_gap)))
    return false;
  const std::size_t n = job.px.size();
  for (std::size_t size : {job.pz.size(), job.vx.size(), job.vz.size(), job.pref_vx.size(), job.pref_vz.size(),
                           job.radius.size(), job.max_speed.size(), job.new_vx.size(), job.new_vz.size()})
    if (size != n) return false;
  if (n > std::numeric_limits<std::uint32_t>::max() / 2) return false;
  if (n == 0) return true;
  // Outputs must not overlap any input or each other (run() reads every agent's inputs while writing).
  auto overlaps = [n](const float* a, const float* b) { return a < b + n && b < a + n; };
  const float* outs[] = {job.new_vx.data(), job.new_vz.data()};
  const float* ins[] = {job.px.data(), job.pz.data(), job.vx.data(), job.vz.data(), job.pref_vx.data(),
                        job.pref_vz.data(), job.radius.data(), job.max_speed.data()};
  if (overlaps(outs[0], outs[1])) return false;
  for (const float* o : outs)
    for (const float* in : ins)
      if (overlaps(o, in)) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite_within(job.px[i], kAvoidanceMaxCoordinate) || !finite_within(job.pz[i], kAvoidanceMaxCoordinate))
      return false;
    if (!finite_within(job.vx[i], kAvoidanceMaxSpeed) || !finite_within(job.vz[i], kAvoidanceMaxSpeed) ||
        !finite_within(job.pref_vx[i], kAvoidanceMaxSpeed) || !finite_within(job.pref_vz[i], kAvoidanceMaxSpeed))
      return false;
    if (!(job.radius[i] > 0.0f && job.radius[i] <= kAvoidanceMaxRadius)) return false;
    if (!(job.max_speed[i] >= 0.0f && job.max_speed[i] <= kAvoidanceMaxSpeed)) return false;
  }
  if (!job.holds.empty() && job.holds.size() != n) return false;
  if (!job.tether_reach.empty() || !job.tether_dx.empty() || !job.tether_dz.empty()) {
    if (job.tether_reach.size() != n || job.tether_dx.size() != n || job.tether_dz.size() != n) return false;
    for (const float* in : {job.tether_dx.data(), job.tether_dz.data(), job.tether_reach.data()})
      for (const float* o : outs)
        if (overlaps(o, in)) return false;
    for (std::size_t i = 0; i < n; ++i)
      if (!finite_within(job.tether_dx[i], kAvoidanceMaxCoordinate) ||
          !finite_within(job.tether_dz[i], kAvoidanceMaxCoordinate) ||
          !finite_within(job.tether_reach[i], kAvoidanceMaxCoordinate))
        return false;
  }
  return true;
}

}  // namespace

// ---- ObstacleSet -----------------------------------------------------------------------------------------------
ObstacleSet::ObstacleSet(const std::vector<std::vector<glm::vec2>>& polygons, float cell_size) {
  if (!(std::isfinite(cell_size) && cell_size > 0.0f))
    throw std::invalid_argument("ObstacleSet: cell size must be finite and positive");
  vec2 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const auto& polygon : polygons) {
    std::vector<vec2> points;
    points.reserve(polygon.size());
    for (const vec2& p : polygon) {
      if (!finite_within(p.x, kAvoidanceMaxCoordinate) || !finite_within(p.y, kAvoidanceMaxCoordinate))
        throw std::invalid_argument("ObstacleSet: non-finite or out-of-range polygon coordinate");
      if (points.empty() || points.back() != p) points.push_back(p);
    }
    while (points.size() > 1 && points.back() == points.front()) points.pop_back();
    if (points.size() < 3) throw std::invalid_argument("ObstacleSet: a polygon needs at least 3 distinct points");
    double area2 = 0.0;  // shoelace in double: a long thin polygon's float sum can come out with the wrong sign
    for (std::size_t k = 0; k < points.size(); ++k) {
      const vec2 a = points[k], b = points[(k + 1) % points.size()];
      area2 += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
    }
    if (area2 < 0.0) std::reverse(points.begin(), points.end());
    const auto first = static_cast<std::uint32_t>(edges_.size());
    const auto m = static_cast<std::uint32_t>(points.size());
    for (std::uint32_t k = 0; k < m; ++k) {
      Edge e;
      e.a = points[k];
      e.b = points[(k + 1) % m];
      const vec2 d = e.b - e.a;
      e.length = std::sqrt(length_squared(d));
      e.direction = d / e.length;  // length > 0: consecutive points differ
      e.prev = first + (k + m - 1) % m;
      e.next = first + (k + 1) % m;
      edges_.push_back(e);
      lo = glm::min(lo, e.a);
      hi = glm::max(hi, e.a);
    }
    for (std::uint32_t k = 0; k < m; ++k) {
      Edge& e = edges_[first + k];
      e.convex_at_a = det2(edges_[e.prev].direction, e.direction) >= 0.0f;
    }
  }
  if (edges_.empty()) return;
  // A grid no larger than 1024 x 1024 cells: a huge outline gets coarser cells rather than a huge table.
  const float extent = std::max(hi.x - lo.x, hi.y - lo.y);
  cell_ = std::max(cell_size, extent / 1023.0f);
  origin_ = lo;
  cols_ = static_cast<std::uint32_t>((hi.x - lo.x) / cell_) + 1;
  rows_ = static_cast<std::uint32_t>((hi.y - lo.y) / cell_) + 1;
  cols_ = std::min(cols_, 1024u);
  rows_ = std::min(rows_, 1024u);
  cell_start_.assign(static_cast<std::size_t>(cols_) * rows_ + 1, 0);
  // Two passes over each edge's bounding box of cells: count, then fill (CSR).
  auto for_cells = [&](const Edge& e, auto&& f) {
    std::uint32_t x0, x1, z0, z1;
    const vec2 c = 0.5f * (e.a + e.b);
    const vec2 half = 0.5f * glm::abs(e.b - e.a);
    // cell_span takes a square: use the larger half-extent (conservative).
    // (padded by a thousandth of a cell, so rounding cannot drop an edge from a cell its end only touches)
    if (!cell_span(c, std::max(half.x, half.y) + 1e-3f * cell_, x0, x1, z0, z1)) return;
    for (std::uint32_t z = z0; z <= z1; ++z)
      for (std::uint32_t x = x0; x <= x1; ++x) f(static_cast<std::size_t>(z) * cols_ + x);
  };
  for (const Edge& e : edges_) for_cells(e, [&](std::size_t cell) { ++cell_start_[cell + 1]; });
  for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  cell_edges_.resize(cell_start_.back());
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::uint32_t k = 0; k < edges_.size(); ++k)
    for_cells(edges_[k], [&](std::size_t cell) { cell_edges_[fill[cell]++] = k; });
}

bool ObstacleSet::cell_span(glm::vec2 p, float reach, std::uint32_t& x0, std::uint32_t& x1, std::uint32_t& z0,
                            std::uint32_t& z1) const {
  const double inv = 1.0 / static_cast<double>(cell_);
  const double ax = (static_cast<double>(p.x) - reach - origin_.x) * inv;
  const double bx = (static_cast<double>(p.x) + reach - origin_.x) * inv;
  const double az = (static_cast<double>(p.y) - reach - origin_.y) * inv;
  const double bz = (static_cast<double>(p.y) + reach - origin_.y) * inv;
  if (bx < 0.0 || bz < 0.0 || ax >= cols_ || az >= rows_) return false;
  x0 = static_cast<std::uint32_t>(std::max(0.0, std::floor(ax)));
  z0 = static_cast<std::uint32_t>(std::max(0.0, std::floor(az)));
  x1 = static_cast<std::uint32_t>(std::min(static_cast<double>(cols_ - 1), std::floor(bx)));
  z1 = static_cast<std::uint32_t>(std::min(static_cast<double>(rows_ - 1), std::floor(bz)));
  return true;
}

void ObstacleSet::edges_near(glm::vec2 p, float reach, std::vector<std::uint32_t>& out) const {
  const std::size_t start = out.size();
  for_each_edge_near(p, reach, [&](std::uint32_t e) { out.push_back(e); });
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(start), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(start), out.end()), out.end());
}

// ---- The job ---------------------------------------------------------------------------------------------------
bool AvoidanceJob::validate() const { return validate_job(*this, true); }

bool AvoidanceJob::run() const {
  if (!validate()) return false;
  const std::size_t n = px.size();
  if (n == 0) return true;
  AvoidanceScratch& s = *scratch;

  // Counting sort of the agents into the grid: stable, so a cell lists its agents by ascending index (not needed
  // for the result, which the (distance, index) order fixes, but it keeps the scan order reproducible).
  const GridShape g = grid_shape(*this, n);
  const std::size_t cells = static_cast<std::size_t>(g.cols) * g.rows;
  s.cell_start.assign(cells + 1, 0);
  if (s.agent_cell.size() < n) {
    s.agent_cell.resize(n);
    s.cell_agents.resize(n);
    s.infeasible.resize(n);
    s.first_vx.resize(n);
    s.first_vz.resize(n);
    s.kept_count.resize(n);
    s.kept_preferred_x.resize(n);
    s.kept_preferred_z.resize(n);
    s.plane_vx.resize(n);
    s.plane_vz.resize(n);
  }
  if (s.kept_neighbors.size() < n * params.max_neighbors) s.kept_neighbors.resize(n * params.max_neighbors);
  // Padded by a run's width: the search reads whole runs of four past a row's last candidate (masked off).
  if (s.sorted_x.size() < n + kSearchRun) {
    s.sorted_x.resize(n + kSearchRun);
    s.sorted_z.resize(n + kSearchRun);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c = g.cell_of(px[i], pz[i]);
    s.agent_cell[i] = c;
    ++s.cell_start[c + 1];
  }
  // Off (the paper's), the half-planes read the current velocities themselves.
  PlaneVelocities plane_v{vx.data(), vz.data()};
  if (params.back_off_limit >= 0.0f) {
    fill_back_off_velocities(*this, s.plane_vx.data(), s.plane_vz.data());
    plane_v = {s.plane_vx.data(), s.plane_vz.data()};
  }
  for (std::size_t c = 1; c <= cells; ++c) s.cell_start[c] += s.cell_start[c - 1];
  // Fill from the back: cell_start[c + 1] (cell c's end) counts down to cell c's begin, so descending i lands in
  // descending slots (ascending index within a cell) without a cursor array; one shift then restores the offsets.
  for (std::size_t i = n; i-- > 0;) {
    const std::uint32_t slot = --s.cell_start[s.agent_cell[i] + 1];
    s.cell_agents[slot] = static_cast<std::uint32_t>(i);
    s.sorted_x[slot] = px[i];
    s.sorted_z[slot] = pz[i];
  }
  for (std::size_t c = 0; c < cells; ++c) s.cell_start[c] = s.cell_start[c + 1];
  s.cell_start[cells] = static_cast<std::uint32_t>(n);

  const float reach2 = params.neighbor_distance * params.neighbor_distance;
  const std::uint32_t capacity = params.max_neighbors;
  // The block of cells that can hold a neighbour in range: (2 block + 1)^2 around the agent's.
  const int block = g.cell >= params.neighbor_distance ? 1 : 2;
  // Agent i's nearest neighbours within reach into nearest[0..), sorted by (squared distance, index); returns how
  // many. The block's rows nearest first, each row's cells skipped when even their nearest point is farther than
  // the current k-th neighbour: once the list is full the search shrinks to it. Only candidates that could not
  // enter the list are skipped (the margin covers rounding), so the kept set is the brute-force one.
  const float below_reach = std::nextafter(reach2, 0.0f);  // d2 < reach2 <=> d2 <= below_reach
  auto search = [&](std::uint32_t i, float x, float z, Nearest* nearest) {
    const std::uint32_t c = s.agent_cell[i];
    const std::uint32_t cx = c % g.cols, cz = c / g.cols;
    // The squared distance from the agent to each column and each row of cells the block spans (the distance
    // to a cell is then one sum): 2 x (2 block + 1) terms instead of two per cell.
    std::array<double, 5> ex2, ez2;
    for (int d = -block; d <= block; ++d) {
      const double x0 = g.origin_x + static_cast<double>(static_cast<std::int64_t>(cx) + d) * g.cell;
      const double z0 = g.origin_z + static_cast<double>(static_cast<std::int64_t>(cz) + d) * g.cell;
      // Nested two-argument max (maxsd), not std::max({...}): the initializer-list form became a loop whose
      // branch was a fifth of the job's mispredictions (callgrind).
      const double ex = std::max(0.0, std::max(x0 - x, x - (x0 + g.cell)));
      const double ez = std::max(0.0, std::max(z0 - z, z - (z0 + g.cell)));
      ex2[static_cast<std::size_t>(d + block)] = ex * ex;
      ez2[static_cast<std::size_t>(d + block)] = ez * ez;
    }
    // One comparison per candidate: `admit` is the largest squared distance that could still enter the list,
    // below_reach or, once the list is full, its last distance if smaller (an equal distance may still win on its
    // index; keep_nearest decides). The list is filled unsorted and sorted once when full: a sorted insert per
    // candidate mispredicted where its shift ended nearly every time (perf: a tenth of the job), and the range
    // test followed by the list's doubled the mispredictions of one.
    std::uint32_t count = 0;
    float admit = below_reach;
    // A cell is skipped when even its nearest point is beyond `cull`: the reach, then the list's last distance once
    // it is full, with a margin for rounding (updated with the list, not recomputed per cell).
    const auto cull_at = [](float d2) { return static_cast<double>(d2) * (1.0 + 1e-4) + 1e-6; };
    double cull = cull_at(reach2);
    const double in_z = static_cast<double>(z) - (g.origin_z + static_cast<double>(cz) * g.cell);
    const int near_side = in_z > 0.5 * g.cell ? 1 : -1;
    // Row by row, the agent's own first, then the nearer neighbouring row (by the rows' distances): a row's cells
    // in the block are contiguous in cell order, so its candidates are one run of sorted_x/z, trimmed at both ends
    // to the columns not culled when the row starts. Their distances are computed 16 at a time (vectorised) and
    // compared with `admit` into a bit mask; only the set bits are visited, each checked again against the list
    // as it shrinks. Measured against cells visited one by one, nearest first in one of four orders by the
    // agent's quadrant, with a branch per candidate (10,000 agents, two threads, both built with the library's
    // flags, alternated, medians of 6, 2026-11-28): the crowds' settings 5.82 -> 5.63 ms (and 6.07 -> 5.80 in a
    // second round), the paper's halves 4.57 -> 4.42 ms, the same velocities bit for bit. Runs of 32: no different.
    const int row_order[5] = {0, near_side, -near_side, 2 * near_side, -2 * near_side};
    float d2s[kSearchRun];
    for (int r = 0; r < 2 * block + 1; ++r) {
      const int dz = row_order[r];
      const std::int64_t zz = static_cast<std::int64_t>(cz) + dz;
      if (zz < 0 || zz >= g.rows) continue;
      const double rz = ez2[static_cast<std::size_t>(dz + block)];
      if (rz > cull) continue;
      std::int64_t lo = std::max<std::int64_t>(static_cast<std::int64_t>(cx) - block, 0);
      std::int64_t hi = std::min<std::int64_t>(static_cast<std::int64_t>(cx) + block, g.cols - 1);
      const auto column_far = [&](std::int64_t xx) {
        return ex2[static_cast<std::size_t>(xx - static_cast<std::int64_t>(cx) + block)] + rz > cull;
      };
      while (lo <= hi && column_far(lo)) ++lo;
      while (hi >= lo && column_far(hi)) --hi;
      if (lo > hi) continue;
      const std::size_t row = static_cast<std::size_t>(zz) * g.cols;
      const std::uint32_t begin = s.cell_start[row + static_cast<std::size_t>(lo)];
      const std::uint32_t end = s.cell_start[row + static_cast<std::size_t>(hi) + 1];
      for (std::uint32_t base = begin; base < end; base += kSearchRun) {
        const std::uint32_t m = std::min<std::uint32_t>(kSearchRun, end - base);
        std::uint32_t bits = 0;
#if defined(__SSE2__)
        // Four at a time with the compare's sign bits as the mask (movmskps): GCC's vectorised form of the loop
        // below built the mask bit by bit. The same operations in the same order, so the same bits.
        {
          const __m128 ax = _mm_set1_ps(x), az = _mm_set1_ps(z), limit = _mm_set1_ps(admit);
          for (std::uint32_t k = 0; k < m; k += 4) {
            const __m128 ox = _mm_sub_ps(_mm_loadu_ps(s.sorted_x.data() + base + k), ax);
            const __m128 oz = _mm_sub_ps(_mm_loadu_ps(s.sorted_z.data() + base + k), az);
            const __m128 d2 = _mm_add_ps(_mm_mul_ps(ox, ox), _mm_mul_ps(oz, oz));
            _mm_storeu_ps(d2s + k, d2);
            bits |= static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmple_ps(d2, limit))) << k;
          }
          bits &= m == 32 ? ~0u : (1u << m) - 1u;
        }
#else
        for (std::uint32_t k = 0; k < m; ++k) {
          const float ox = s.sorted_x[base + k] - x, oz = s.sorted_z[base + k] - z;
          d2s[k] = ox * ox + oz * oz;
        }
        for (std::uint32_t k = 0; k < m; ++k) bits |= static_cast<std::uint32_t>(d2s[k] <= admit) << k;
#endif
        while (bits != 0) {
          const std::uint32_t k = static_cast<std::uint32_t>(std::countr_zero(bits));
          bits &= bits - 1;
          const float d2 = d2s[k];
          if (!(d2 <= admit)) continue;
          const std::uint32_t j = s.cell_agents[base + k];
          if (j == i) continue;
          if (count < capacity) {
            nearest[count++] = Nearest{d2, j};
            if (count < capacity) continue;
            sort_nearest(nearest, count);
          } else {
            keep_nearest(nearest, count, capacity, Nearest{d2, j});
          }
          admit = std::min(below_reach, nearest[count - 1].d2());
          cull = cull_at(nearest[count - 1].d2());
        }
      }
    }
    if (count < capacity) sort_nearest(nearest, count);
    return count;
  };
  const ObstacleSet* obstacle_set = obstacles;
  // Fixed chunks of 256 agents in grid order (a chunk is a patch of neighbouring cells, so the cells it scans
  // stay in cache: ~13 % faster at 10,000 agents than index order); each agent's result depends only on the
  // inputs, so neither the order nor the chunking changes a bit.
  auto pass = [&](const FirstPass* first) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      std::array<Nearest, kAvoidanceMaxNeighbors> nearest;
      for (std::size_t slot = r.begin(); slot < r.end(); ++slot) {
        const std::uint32_t i = s.cell_agents[slot];
        if (first != nullptr && first->infeasible[i] == 0) continue;
        const float x = px[i], z = pz[i];
        std::uint64_t* kept = s.kept_neighbors.data() + static_cast<std::size_t>(i) * capacity;
        std::uint32_t count;
        if (first == nullptr) {
          count = search(i, x, z, nearest.data());
        } else {
          // The second pass: the same positions, so the neighbours the first pass kept for this agent.
          count = s.kept_count[i];
          for (std::uint32_t k = 0; k < count; ++k) nearest[k].key = kept[k];
        }
        const vec2 p(x, z);
        const float edge_reach = params.obstacle_time_horizon * max_speed[i] + radius[i];
        auto edges = [&](auto&& visit) {
          if (obstacle_set != nullptr) obstacle_set->for_each_edge_near(p, edge_reach, visit);
        };
        bool infeasible = false;
        vec2 preferred(0.0f);
        const vec2 v = solve_agent(*this, i, nearest.data(), count, edges, first, plane_v, infeasible, &preferred);
        if (first == nullptr) {
          s.infeasible[i] = infeasible ? 1 : 0;
          if (infeasible) {
            s.kept_count[i] = count;
            for (std::uint32_t k = 0; k < count; ++k) kept[k] = nearest[k].key;
            s.kept_preferred_x[i] = preferred.x;
            s.kept_preferred_z[i] = preferred.y;
          }
        }
        new_vx[i] = v.x;
        new_vz[i] = v.y;
      }
    });
  };
  pass(nullptr);
  // The second pass (see FirstPass): only the agents whose half-planes left nothing, against what their
  // neighbours chose in the first. Measured on the test's 128-agent circle: steps with an overlap 44 -> 32, the
  // deepest 6.0 -> 4.1 cm; callgrind on the benchmark's 10,000 agents: 13 % more instructions.
  // Rejected: iterating to convergence (each pass is as costly as the first in a jam) and running the second
  // pass for every agent (the ones that succeeded already satisfy their neighbours' half-planes).
  if (params.second_pass &&
      std::find(s.infeasible.begin(), s.infeasible.begin() + static_cast<std::ptrdiff_t>(n), 1) !=
          s.infeasible.begin() + static_cast<std::ptrdiff_t>(n)) {
    std::copy(new_vx.begin(), new_vx.end(), s.first_vx.begin());
    std::copy(new_vz.begin(), new_vz.end(), s.first_vz.begin());
    const FirstPass first{s.first_vx.data(), s.first_vz.data(), s.infeasible.data(), s.kept_preferred_x.data(),
                          s.kept_preferred_z.data()};
    pass(&first);
  }
  return true;
}

glm::vec2 back_off_velocity(glm::vec2 v, glm::vec2 preferred, float limit) {
  if (!(limit >= 0.0f)) return v;
  const float p2 = preferred.x * preferred.x + preferred.y * preferred.y;
  const float against = -(v.x * preferred.x + v.y * preferred.y);  // the speed against it, times |preferred|
  // No square root unless it binds: against > limit |p|  <=>  against > 0 and against^2 > limit^2 p2.
  if (!(p2 > 1e-8f) || !(against > 0.0f) || !(against * against > limit * limit * p2)) return v;
  const float length = std::sqrt(p2);
  return v + ((against / length - limit) / length) * preferred;
}

bool run_avoidance_reference(const AvoidanceJob& job) {
  if (!validate_job(job, false)) return false;
  const std::size_t n = job.px.size();
  const float reach2 = job.params.neighbor_distance * job.params.neighbor_distance;
  std::array<Nearest, kAvoidanceMaxNeighbors> nearest;
  std::vector<std::uint8_t> infeasible(n, 0);  // the twin may allocate: it is for tests
  std::vector<float> first_vx(n), first_vz(n);
  const FirstPass second{first_vx.data(), first_vz.data(), infeasible.data()};
  std::vector<float> plane_vx(n), plane_vz(n);
  fill_back_off_velocities(job, plane_vx.data(), plane_vz.data());
  const PlaneVelocities plane_v{plane_vx.data(), plane_vz.data()};
  for (const FirstPass* first : {static_cast<const FirstPass*>(nullptr), &second}) {
    if (first != nullptr) {
      if (!job.params.second_pass || std::find(infeasible.begin(), infeasible.end(), 1) == infeasible.end()) break;
      std::copy(job.new_vx.begin(), job.new_vx.end(), first_vx.begin());
      std::copy(job.new_vz.begin(), job.new_vz.end(), first_vz.begin());
    }
    for (std::uint32_t i = 0; i < n; ++i) {
      if (first != nullptr && infeasible[i] == 0) continue;
      std::uint32_t count = 0;
      for (std::uint32_t j = 0; j < n; ++j) {
        if (j == i) continue;
        const float dx = job.px[j] - job.px[i], dz = job.pz[j] - job.pz[i];
        const float d2 = dx * dx + dz * dz;
        if (d2 < reach2) keep_nearest(nearest.data(), count, job.params.max_neighbors, Nearest{d2, j});
      }
      auto edges = [&](auto&& visit) {
        if (job.obstacles == nullptr) return;
        for (std::uint32_t e = 0; e < job.obstacles->edges().size(); ++e) visit(e);
      };
      bool failed = false;
      const vec2 v = solve_agent(job, i, nearest.data(), count, edges, first, plane_v, failed);
      if (first == nullptr) infeasible[i] = failed ? 1 : 0;
      job.new_vx[i] = v.x;
      job.new_vz[i] = v.y;
    }
  }
  return true;
}

}  // namespace strata
