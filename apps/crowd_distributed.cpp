#include "apps/crowd_distributed.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <sys/resource.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "apps/cli_support.h"
#include "dist/agent_exchange.h"
#include "dist/migration.h"
#include "dist/partition.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "render/crowd_renderer.h"
#include "render/scene_draw.h"
#include "scene/crowd.h"
#include "scene/crowd_agents.h"
#include "scene/crowd_metrics.h"
#include "scene/state_hash.h"

#if defined(STRATA_HAVE_MPI)
#include "dist/mpi_world.h"
#endif

namespace strata {

std::unique_ptr<CrowdDistribution> join_if_launched(const char* command, double rebalance_seconds,
                                                    double timeout_seconds, bool& failed) {
  failed = false;
  if (!CrowdDistribution::launched()) return nullptr;
  try {
    return std::make_unique<CrowdDistribution>(command, rebalance_seconds, timeout_seconds);
  } catch (const std::exception& e) {
    cli::print_error(command, cli::error_text(e));
    failed = true;
    return nullptr;
  }
}

bool frame_whole_crowd(const Crowd& crowd, OrbitCamera& camera, float aspect, RenderScratch& scratch,
                       CrowdDistribution* dist) {
  glm::vec3 lo, hi;
  bool any = crowd_frame_bounds(crowd, scratch, lo, hi);
  if (dist) any = dist->share_box(any, lo, hi);
  if (any) camera.frame_box_tight(lo, hi, aspect);
  return any;
}

bool Refusal::stop(const char* command, CrowdDistribution* dist) const {
  if (dist) return dist->report_failures(command, message);
  if (!message.empty()) cli::print_error(command, message);
  return !message.empty();
}

#if defined(STRATA_HAVE_MPI)

namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double p95_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(v.size())))];
}

// CrowdDistribution::Impl::owner for a walker nobody owns (no finite placement: held, culled, by every rank) and
// for one another rank holds.
constexpr std::int32_t kNobody = -1;
constexpr std::int32_t kElsewhere = -2;

template <class T>
void append_bytes(std::vector<std::uint8_t>& out, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

}  // namespace

struct CrowdDistribution::Impl {
  MpiWorld world;
  std::string command;  // for the watchdog's line
  double rebalance_s = 2.0, timeout_s = 600.0;
  CrowdPartition partition;
  double next_cut_s = 0.0;
  std::size_t recuts = 0;
  bool started = false;
  std::vector<Entity> walkers;       // every walker, creation order (the same on every rank)
  std::vector<std::int32_t> owner;   // their owners at the last assign_walkers: this rank, kNobody or kElsewhere
  std::size_t owned = 0;
  // This rank's traffic over the run: walkers and bytes migrated out, placement histograms sent for recuts, ghosts
  // and plan offers sent and ghosts received (scene/crowd_agents.h AgentExchange).
  std::size_t migrated_out = 0, migration_bytes = 0, recut_bytes = 0;
  std::size_t ghost_bytes = 0, plan_bytes = 0, ghosts_received = 0, agent_steps = 0;
  std::size_t observation_bytes = 0;  // `strata report crowd`'s border observations sent
  std::vector<double> compute_ms, composite_ms, depth_read_ms, wait_ms;
  std::vector<float> depth;
  std::vector<std::uint8_t> composited;
  // The watchdog: a rank that has not beaten for timeout_s ends its process, and mpirun then ends the job.
  std::atomic<double> last_beat{0.0};
  std::atomic<bool> stopping{false};
  std::thread watchdog;

  Impl(std::string name, double rebalance, double timeout)
      : command(std::move(name)), rebalance_s(rebalance), timeout_s(timeout) {
    last_beat = now_s();
    if (timeout_s > 0)
      watchdog = std::thread([this] {
        while (!stopping.load()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(200));
          if (now_s() - last_beat.load() > timeout_s) {
            std::fprintf(stderr, "strata %s: rank %d: no progress for %.0f s (--mpi-timeout); stopping every rank\n",
                         command.c_str(), world.rank(), timeout_s);
            std::fflush(stderr);
            std::_Exit(1);
          }
        }
      });
  }
  ~Impl() {
    stopping = true;
    if (watchdog.joinable()) watchdog.join();
  }
  void beat() { last_beat = now_s(); }

  // The agents' exchange over this job (dist/agent_exchange.h), one Alltoallv each.
  struct Agents final : AgentExchange {
    Impl& d;
    float reach;
    Agents(Impl& impl, float ghost_reach) : d(impl), reach(ghost_reach) {}
    void exchange_ghosts(std::span<const AgentSnapshot> mine, std::vector<AgentSnapshot>& ghosts) override {
      const std::vector<std::vector<std::uint8_t>> to_rank = pack_ghosts(mine, d.partition, d.world.rank(), reach);
      for (const std::vector<std::uint8_t>& bytes : to_rank) d.ghost_bytes += bytes.size();
      const std::size_t before = ghosts.size();
      unpack_ghosts(d.world.exchange(to_rank), ghosts);
      d.ghosts_received += ghosts.size() - before;
      ++d.agent_steps;
    }
    void select_plans(std::vector<PlanCandidate>& mine, std::size_t take) override {
      const std::vector<std::uint8_t> offers = pack_plan_offers(mine);
      const std::vector<std::vector<std::uint8_t>> to_all(static_cast<std::size_t>(d.world.size()), offers);
      d.plan_bytes += offers.size() * static_cast<std::size_t>(d.world.size() - 1);
      keep_most_urgent(mine, d.world.exchange(to_all), take);
    }
  };
};

bool CrowdDistribution::launched() { return MpiWorld::launched(); }

CrowdDistribution::CrowdDistribution(const std::string& command, double rebalance_seconds, double timeout_seconds)
    : impl_(std::make_unique<Impl>(command, rebalance_seconds, timeout_seconds)) {}
CrowdDistribution::~CrowdDistribution() = default;

int CrowdDistribution::rank() const { return impl_->world.rank(); }
int CrowdDistribution::ranks() const { return impl_->world.size(); }
bool CrowdDistribution::all_ok(bool ok) { return impl_->world.all_ok(ok); }

bool CrowdDistribution::report_failures(const std::string& command, const std::string& my_error) {
  const bool failed_here = !my_error.empty();
  if (impl_->world.all_ok(!failed_here)) return false;
  // Did rank 0 fail? Then its line is the one: the same input fails the same way on every rank.
  const std::vector<double> failed = impl_->world.all_gather(failed_here ? 1.0 : 0.0);
  if (failed_here && (root() || failed[0] == 0.0)) {
    if (root()) std::fprintf(stderr, "strata %s: %s\n", command.c_str(), my_error.c_str());
    else std::fprintf(stderr, "strata %s: rank %d: %s\n", command.c_str(), rank(), my_error.c_str());
    std::fflush(stderr);
  }
  return true;
}

void CrowdDistribution::assign_walkers(Crowd& crowd, double time_s) {
  Impl& d = *impl_;
  d.beat();
  const std::vector<Entity> walkers = crowd.world.entities();
  const std::size_t n = walkers.size();
  // A crowd not seen before is whole on every rank (built from the same inputs and seed); a known one holds only
  // this rank's walkers, the rest in its remote table.
  const bool known = d.started && walkers == d.walkers;
  if (!known) d.walkers = walkers;
  if (!known || time_s + 1e-9 >= d.next_cut_s || d.partition.ranks() != ranks()) {
    std::vector<float> xs, zs;
    held_placements(crowd, xs, zs);
    if (known && ranks() > 1) {
      // Each rank holds its own walkers: the slabs are cut from the sum of every rank's histogram of placements
      // over the box of all of them (dist/partition.h), bytes independent of the crowd's size.
      float lo[2] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
      float hi[2] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest()};
      for (std::size_t i = 0; i < xs.size(); ++i) {
        if (!std::isfinite(xs[i]) || !std::isfinite(zs[i])) continue;
        lo[0] = std::min(lo[0], xs[i]), hi[0] = std::max(hi[0], xs[i]);
        lo[1] = std::min(lo[1], zs[i]), hi[1] = std::max(hi[1], zs[i]);
      }
      d.world.min_max(lo, hi);
      PlacementHistogram h = placement_histogram(xs, zs, lo[0], hi[0], lo[1], hi[1]);
      // Both axes' counts in one reduction.
      std::vector<std::uint32_t> counts(h.x.begin(), h.x.end());
      counts.insert(counts.end(), h.z.begin(), h.z.end());
      d.world.sum(counts);
      std::copy(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(h.x.size()), h.x.begin());
      std::copy(counts.begin() + static_cast<std::ptrdiff_t>(h.x.size()), counts.end(), h.z.begin());
      d.recut_bytes += 4 * sizeof(float) + (h.x.size() + h.z.size()) * sizeof(std::uint32_t);
      d.partition = partition_from_histogram(h, ranks());
    } else {
      // A crowd every rank holds whole (the start): the exact cut from every placement.
      d.partition = partition_by_density(xs, zs, ranks());
    }
    d.next_cut_s = time_s + d.rebalance_s;
    ++d.recuts;
  }
  if (!known) {
    keep_owned(crowd, d.partition, rank());
    d.started = true;
  } else if (ranks() > 1) {
    // Walkers this rank held in the last step and another owns now travel there, row and all (dist/migration.h).
    std::size_t leaving = 0;
    const std::vector<std::vector<std::uint8_t>> to_rank = pack_leaving(crowd, d.partition, rank(), leaving);
    d.migrated_out += leaving;
    for (const std::vector<std::uint8_t>& bytes : to_rank) d.migration_bytes += bytes.size();
    unpack_walkers(crowd, d.world.exchange(to_rank));
  }
  crowd.lod.ownership = d.partition.region(rank());
  d.owner.assign(n, kElsewhere);
  d.owned = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const EntityLocation at = crowd.world.location(walkers[i]);
    if (at.table == crowd.remote_table) continue;
    const SoaTable& t = crowd.world.table(at.table);
    d.owner[i] = d.partition.owner(t.f32(kWalkerPlacement, 0)[at.block], t.f32(kWalkerPlacement, 2)[at.block]);
    d.owned += d.owner[i] == rank();
  }
  if (crowd.agents && !crowd.agents->exchange)
    crowd.agents->exchange = std::make_shared<Impl::Agents>(d, ghost_reach(crowd.agents->avoidance));
}

std::vector<double> CrowdDistribution::all_gather(double value) { return impl_->world.all_gather(value); }

std::vector<AgentObservation> CrowdDistribution::exchange_border_observations(std::span<const AgentObservation> mine,
                                                                              float reach) {
  Impl& d = *impl_;
  const std::vector<std::vector<std::uint8_t>> to_rank =
      pack_border_observations(mine, d.partition, d.world.rank(), reach);
  for (const std::vector<std::uint8_t>& bytes : to_rank) d.observation_bytes += bytes.size();
  std::vector<AgentObservation> border;
  unpack_border_observations(d.world.exchange(to_rank), border);
  return border;
}

std::vector<std::uint8_t> CrowdDistribution::gather_to_root(std::span<const std::uint8_t> bytes,
                                                            std::vector<std::size_t>* sizes) {
  std::vector<std::size_t> counts;
  std::vector<std::uint8_t> all = impl_->world.gather_to_root(bytes, counts);
  if (sizes) *sizes = std::move(counts);
  return all;
}

void CrowdDistribution::share_bounds(glm::vec3& lo, glm::vec3& hi) {
  float l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
  impl_->world.min_max(l, h);
  lo = glm::vec3(l[0], l[1], l[2]);
  hi = glm::vec3(h[0], h[1], h[2]);
}

bool CrowdDistribution::share_box(bool any, glm::vec3& lo, glm::vec3& hi) {
  if (!any) lo = glm::vec3(std::numeric_limits<float>::max()), hi = glm::vec3(std::numeric_limits<float>::lowest());
  share_bounds(lo, hi);
  return lo.x <= hi.x;
}

void CrowdDistribution::composite(const CrowdRenderer& renderer, std::vector<std::uint8_t>& pixels, int width,
                                  int height) {
  Impl& d = *impl_;
  using clock = std::chrono::steady_clock;
  const auto ms_since = [](clock::time_point t) {
    return std::chrono::duration<double, std::milli>(clock::now() - t).count();
  };
  auto t = clock::now();
  renderer.read_depth(d.depth);
  d.depth_read_ms.push_back(ms_since(t));
  // The wait for the slowest rank is load imbalance, not compositing: timed apart at a barrier.
  t = clock::now();
  d.world.barrier();
  d.wait_ms.push_back(ms_since(t));
  t = clock::now();
  // Only the pixels this rank's walkers and their shadows can have touched travel (dist/composite.h footprints).
  const PixelRect f = renderer.last_footprint();
  d.world.composite(pixels, d.depth, width, height, ImageRect{f.x0, f.y0, f.x1, f.y1}, d.composited);
  if (root()) pixels.swap(d.composited);
  d.composite_ms.push_back(ms_since(t));
  d.beat();
}

void CrowdDistribution::frame_done(double compute_ms) {
  impl_->compute_ms.push_back(compute_ms);
  impl_->beat();
}

std::uint64_t CrowdDistribution::state_hash(const Crowd& crowd) {
  Impl& d = *impl_;
  const std::vector<Entity> walkers = crowd.world.entities();
  if (walkers.size() != d.walkers.size())
    throw std::logic_error("CrowdDistribution::state_hash: the crowd changed since assign_walkers");
  std::vector<std::uint8_t> mine;
  for (std::size_t i = 0; i < walkers.size(); ++i)
    if (d.owner[i] == rank()) {
      append_bytes(mine, static_cast<std::uint64_t>(i));
      append_bytes(mine, walker_state_digest(crowd, walkers[i]));
    }
  std::vector<std::size_t> sizes;
  const std::vector<std::uint8_t> all = d.world.gather_to_root(mine, sizes);
  if (!root()) return 0;
  // A walker nobody owned (no finite placement) was held by every rank as culled: rank 0's own digest stands.
  std::vector<std::uint64_t> digests(walkers.size());
  for (std::size_t i = 0; i < walkers.size(); ++i)
    if (d.owner[i] == kNobody) digests[i] = walker_state_digest(crowd, walkers[i]);
  for (std::size_t at = 0; at + 16 <= all.size(); at += 16) {
    std::uint64_t index = 0, digest = 0;
    std::memcpy(&index, &all[at], 8);
    std::memcpy(&digest, &all[at + 8], 8);
    if (index < digests.size()) digests[index] = digest;
  }
  return combine_walker_digests(digests);
}

void CrowdDistribution::write_merged_trace(const Profiler& profiler, const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  // Each rank's trace through a private temporary file (the profiler writes files), rewritten as its process.
  const fs::path tmp = fs::temp_directory_path() /
                       ("strata-trace-" + std::to_string(::getpid()) + "-" + std::to_string(rank()) + ".json");
  profiler.write_chrome_trace(tmp);
  nlohmann::json mine;
  {
    std::ifstream in(tmp);
    mine = nlohmann::json::parse(in);
  }
  std::error_code ec;
  fs::remove(tmp, ec);
  const int pid = rank() + 1;
  for (nlohmann::json& e : mine.at("traceEvents")) {
    e["pid"] = pid;
    if (e.value("name", "") == "process_name")
      e["args"]["name"] = "strata rank " + std::to_string(rank()) + " on " + impl_->world.processor_name();
  }
  const std::string text = mine.at("traceEvents").dump();
  std::vector<std::size_t> sizes;
  const std::vector<std::uint8_t> all =
      impl_->world.gather_to_root(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), sizes);
  if (!root()) return;
  nlohmann::json merged;
  merged["traceEvents"] = nlohmann::json::array();
  std::size_t at = 0;
  for (const std::size_t n : sizes) {
    const nlohmann::json events = nlohmann::json::parse(all.begin() + static_cast<std::ptrdiff_t>(at),
                                                        all.begin() + static_cast<std::ptrdiff_t>(at + n));
    for (const nlohmann::json& e : events) merged["traceEvents"].push_back(e);
    at += n;
  }
  merged["displayTimeUnit"] = "ms";
  merged["otherData"] = mine.value("otherData", nlohmann::json::object());
  merged["otherData"]["ranks"] = ranks();
  merged["otherData"]["clock"] =
      "steady_clock of each rank, microseconds since its profiler was created just after a common MPI barrier";
  std::ofstream out(path);
  out << merged.dump() << '\n';
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

nlohmann::json CrowdDistribution::summary(std::size_t frames) {
  Impl& d = *impl_;
  const std::vector<double> owned = d.world.all_gather(static_cast<double>(d.owned));
  const std::vector<double> compute = d.world.all_gather(mean_of(d.compute_ms));
  const std::vector<double> composite_mean = d.world.all_gather(mean_of(d.composite_ms));
  const std::vector<double> composite_p95 = d.world.all_gather(p95_of(d.composite_ms));
  const std::vector<double> depth_read = d.world.all_gather(mean_of(d.depth_read_ms));
  const std::vector<double> wait = d.world.all_gather(mean_of(d.wait_ms));
  const double per_frame = frames > 0 ? 1.0 / static_cast<double>(frames) : 0.0;
  const std::vector<double> composite_bytes =
      d.world.all_gather(static_cast<double>(d.world.composite_bytes_sent()) * per_frame);
  const std::vector<double> bytes = d.world.all_gather(static_cast<double>(d.world.bytes_sent()) * per_frame);
  const double frame_pixels = static_cast<double>(d.depth.size());
  const std::vector<double> footprint = d.world.all_gather(
      frame_pixels > 0 ? 100.0 * static_cast<double>(d.world.footprint_pixels()) * per_frame / frame_pixels : 0.0);
  const std::vector<double> migration = d.world.all_gather(static_cast<double>(d.migration_bytes) * per_frame);
  const std::vector<double> migrated = d.world.all_gather(static_cast<double>(d.migrated_out));
  const std::vector<double> recut = d.world.all_gather(static_cast<double>(d.recut_bytes) * per_frame);
  const std::vector<double> ghost_bytes = d.world.all_gather(static_cast<double>(d.ghost_bytes) * per_frame);
  const std::vector<double> observation_bytes =
      d.world.all_gather(static_cast<double>(d.observation_bytes) * per_frame);
  const std::vector<double> plan_bytes = d.world.all_gather(static_cast<double>(d.plan_bytes) * per_frame);
  const std::vector<double> ghosts = d.world.all_gather(
      d.agent_steps > 0 ? static_cast<double>(d.ghosts_received) / static_cast<double>(d.agent_steps) : 0.0);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);  // ru_maxrss: KiB on Linux
  const std::vector<double> peak_rss = d.world.all_gather(static_cast<double>(usage.ru_maxrss) / 1024.0);
  const std::string host = d.world.processor_name();
  std::vector<std::size_t> sizes;
  const std::vector<std::uint8_t> hosts_bytes =
      d.world.gather_to_root(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(host.data()), host.size()), sizes);
  if (!root()) return nullptr;
  nlohmann::json hosts = nlohmann::json::array();
  std::size_t at = 0;
  for (const std::size_t n : sizes) {
    hosts.push_back(std::string(hosts_bytes.begin() + static_cast<std::ptrdiff_t>(at),
                                hosts_bytes.begin() + static_cast<std::ptrdiff_t>(at + n)));
    at += n;
  }
  const double mean_compute = mean_of(compute);
  const double max_compute = compute.empty() ? 0.0 : *std::max_element(compute.begin(), compute.end());
  nlohmann::json j;
  j["ranks"] = ranks();
  j["hosts"] = hosts;
  j["compositor"] = "direct-send, footprints";
  j["partition_axis"] = d.partition.axis == 0 ? "x" : "z";
  j["partition_cuts_m"] = d.partition.cuts;
  j["rebalance_s"] = d.rebalance_s;
  j["repartitions"] = d.recuts;
  j["walkers_per_rank"] = owned;
  j["compute_ms_mean_per_rank"] = compute;
  // The slowest rank's frame over the mean rank's: 1 is perfect balance.
  j["load_imbalance"] = mean_compute > 0 ? max_compute / mean_compute : 1.0;
  j["depth_read_ms_mean_per_rank"] = depth_read;
  j["wait_ms_mean_per_rank"] = wait;
  j["composite_ms_mean_per_rank"] = composite_mean;
  j["composite_ms_p95_per_rank"] = composite_p95;
  j["composite_bytes_per_frame_per_rank"] = composite_bytes;
  // The share of the frame inside each rank's footprint, a frame's mean: what it sends of each band.
  j["composite_footprint_pct_per_rank"] = footprint;
  j["bytes_sent_per_frame_per_rank"] = bytes;
  // Simulation traffic: the rows of walkers changing owner, the placements sent for recuts, and for steered agents
  // the ghosts near the borders and the plan offers (dist/agent_exchange.h).
  j["migration_bytes_per_frame_per_rank"] = migration;
  j["walkers_migrated_per_rank"] = migrated;
  j["recut_bytes_per_frame_per_rank"] = recut;
  j["ghost_bytes_per_frame_per_rank"] = ghost_bytes;
  // `strata report crowd` only: the agents near the borders that the crowd's pair figures need (0 otherwise).
  j["report_border_bytes_per_frame_per_rank"] = observation_bytes;
  j["ghosts_received_mean_per_rank"] = ghosts;
  j["plan_offer_bytes_per_frame_per_rank"] = plan_bytes;
  j["peak_rss_mib_per_rank"] = peak_rss;
  return j;
}

void CrowdDistribution::abort(int code) { impl_->world.abort(code); }

#else  // built without MPI

struct CrowdDistribution::Impl {};
bool CrowdDistribution::launched() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(var)) return true;
  return false;
}
CrowdDistribution::CrowdDistribution(const std::string&, double, double) {
  throw std::runtime_error(
      "started by mpirun, but this strata was built without MPI (install libopenmpi-dev and rebuild)");
}
CrowdDistribution::~CrowdDistribution() = default;
int CrowdDistribution::rank() const { return 0; }
int CrowdDistribution::ranks() const { return 1; }
bool CrowdDistribution::all_ok(bool ok) { return ok; }
bool CrowdDistribution::report_failures(const std::string&, const std::string& e) { return !e.empty(); }
void CrowdDistribution::assign_walkers(Crowd&, double) {}
std::vector<double> CrowdDistribution::all_gather(double value) { return {value}; }
std::vector<AgentObservation> CrowdDistribution::exchange_border_observations(std::span<const AgentObservation>, float) {
  return {};
}
std::vector<std::uint8_t> CrowdDistribution::gather_to_root(std::span<const std::uint8_t> bytes,
                                                            std::vector<std::size_t>* sizes) {
  if (sizes) *sizes = {bytes.size()};
  return {bytes.begin(), bytes.end()};
}
void CrowdDistribution::share_bounds(glm::vec3&, glm::vec3&) {}
bool CrowdDistribution::share_box(bool any, glm::vec3&, glm::vec3&) { return any; }
void CrowdDistribution::composite(const CrowdRenderer&, std::vector<std::uint8_t>&, int, int) {}
void CrowdDistribution::frame_done(double) {}
std::uint64_t CrowdDistribution::state_hash(const Crowd&) { return 0; }
void CrowdDistribution::write_merged_trace(const Profiler&, const std::filesystem::path&) {}
nlohmann::json CrowdDistribution::summary(std::size_t) { return nullptr; }
void CrowdDistribution::abort(int code) { std::_Exit(code); }

#endif

}  // namespace strata
