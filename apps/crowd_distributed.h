#pragma once
// What `strata crowd` (and `strata bench` and `strata report crowd`, for the simulation) does differently when
// started by mpirun (docs/scale-out.md): one crowd over K processes.
//
//   every rank   builds the same crowd from the same inputs and seed, then holds only the walkers in its slab of
//                ground (dist/partition.h, recut by walker density every --rebalance-seconds; the rest are
//                handles in the crowd's remote table, dist/migration.h) and runs the whole frame for those: a
//                scenario's agents with the other ranks' agents near its slab as ghosts (dist/agent_exchange.h),
//                IK, FK, muscles, skinning, drawing; renders them over the shared ground into colour + depth
//   compositing  each frame's pieces folded by depth (dist/composite.h) onto rank 0 (dist/mpi_world.h)
//   rank 0       writes the frames, the video, summary.json (with an "mpi" object: ranks, walkers per rank, load
//                imbalance, bytes sent per frame, compositing time) and one Chrome trace with a process per rank
//
// Failures: inputs every rank reads are checked on every rank and reported once, by rank 0; an error on one rank
// only is printed by that rank with its number, and every rank stops (MPI_Abort). A watchdog ends a rank that
// makes no progress for --mpi-timeout seconds, which makes mpirun stop the others: no run hangs.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json_fwd.hpp>

namespace strata {

struct AgentObservation;
struct Crowd;
class CrowdRenderer;
struct OrbitCamera;
class Profiler;
struct RenderScratch;

class CrowdDistribution;

// The start every distributed command shares: joins the job when started by mpirun and returns null otherwise.
// When joining fails, prints the command's one line and sets `failed`.
std::unique_ptr<CrowdDistribution> join_if_launched(const char* command, double rebalance_seconds,
                                                    double timeout_seconds, bool& failed);

// What a distributed command answers --renderer embree with: the ray tracer keeps no depth to composite.
inline constexpr const char* kDistributedRendererRefusal =
    "--renderer embree: a distributed run composites depth, which only the GL renderer keeps";

// Frames `camera` on the whole crowd (crowd_frame_bounds, tightly): under mpirun (`dist` not null) every rank's
// bounds, shared, so every rank gets the same camera. Collective then. False, camera untouched, when no rank has
// anything to frame.
bool frame_whole_crowd(const Crowd& crowd, OrbitCamera& camera, float aspect, RenderScratch& scratch,
                       CrowdDistribution* dist);

// A command's checks before any work: the first refusal is kept with its exit code, and stop() ends the command
// when there is one — under mpirun agreed between the ranks first and printed once, so that every rank leaves
// together (a rank whose own checks passed leaves with 1).
struct Refusal {
  std::string message;
  int code = 0;
  void refuse_if(int exit_code, std::string why) {
    if (message.empty() && !why.empty()) message = std::move(why), code = exit_code;
  }
  bool none() const { return message.empty(); }
  // True when the command must stop; then exit_code() is its status.
  bool stop(const char* command, CrowdDistribution* dist) const;
  int exit_code() const { return message.empty() ? 1 : code; }
};

class CrowdDistribution {
 public:
  // True when this process was started by mpirun / mpiexec.
  static bool launched();
  // Joins the job (MPI_Init) for `command` (its name in the watchdog's line). Throws std::runtime_error when this
  // strata was built without MPI or MPI fails.
  CrowdDistribution(const std::string& command, double rebalance_seconds, double timeout_seconds);
  ~CrowdDistribution();
  CrowdDistribution(const CrowdDistribution&) = delete;
  CrowdDistribution& operator=(const CrowdDistribution&) = delete;

  int rank() const;
  int ranks() const;
  bool root() const { return rank() == 0; }
  // True on every rank when `ok` is true on every rank.
  bool all_ok(bool ok);
  // Every rank's error line printed once: rank 0's when it has one, otherwise each failing rank's with its number.
  // Returns true when some rank failed (then every rank must stop).
  bool report_failures(const std::string& command, const std::string& my_error);

  // Before each step: recuts the slabs when due (at `time_s` 0 and every rebalance period after), gives the crowd
  // this rank's slab, and records every walker's owner for this frame.
  void assign_walkers(Crowd& crowd, double time_s);
  // Every rank's value, in rank order, on every rank.
  std::vector<double> all_gather(double value);
  // `strata report crowd`: sends every other rank this rank's observations within `reach` of its slab and returns
  // the other ranks' near this one's (dist/agent_exchange.h pack_border_observations); collective, each step.
  std::vector<AgentObservation> exchange_border_observations(std::span<const AgentObservation> mine, float reach);
  // Rank 0 receives every rank's bytes concatenated in rank order (and, given `sizes`, each rank's count); the
  // others get an empty vector.
  std::vector<std::uint8_t> gather_to_root(std::span<const std::uint8_t> bytes, std::vector<std::size_t>* sizes = nullptr);
  // Every rank's bounds: lo the minimum, hi the maximum.
  void share_bounds(glm::vec3& lo, glm::vec3& hi);
  // The box of every rank's box: `any` false means this rank has none (lo, hi ignored). False when no rank has one.
  bool share_box(bool any, glm::vec3& lo, glm::vec3& hi);
  // Reads the renderer's depth and composites every rank's frame; on rank 0 `pixels` becomes the whole frame.
  void composite(const CrowdRenderer& renderer, std::vector<std::uint8_t>& pixels, int width, int height);
  // After each frame: this rank's time for the frame without compositing (ms); feeds the watchdog.
  void frame_done(double compute_ms);

  // state_hash (scene/state_hash.h) of the whole crowd, on rank 0 (0 elsewhere): each walker's digest from the
  // rank that owned it in the last step.
  std::uint64_t state_hash(const Crowd& crowd);
  // Rank 0 writes to `path` one Chrome trace of every rank's `profiler` (a process per rank, clocks started at a
  // common barrier); the others send theirs.
  void write_merged_trace(const Profiler& profiler, const std::filesystem::path& path);
  // Rank 0: summary.json's "mpi" object (the others return null). Collective.
  nlohmann::json summary(std::size_t frames);
  // Ends every rank of the job now with exit status `code` (MPI_Abort).
  [[noreturn]] void abort(int code);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata
