#include "scene/crowd_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "components/walker.h"
#include "scene/crowd.h"
#include "scene/crowd_agents.h"

namespace strata {

void collect_agent_observations(const Crowd& crowd, std::vector<AgentObservation>& out) {
  if (!crowd.agents) return;
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (std::uint32_t row = 0; row < t.size(); ++row) {
      AgentObservation o;
      o.walker = t.owner(row).index;
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) o.nonfinite += !std::isfinite(t.f32(kWalkerAgent, c)[row]);
      o.x = t.f32(kWalkerAgent, kAgentPx)[row];
      o.z = t.f32(kWalkerAgent, kAgentPz)[row];
      o.radius = t.f32(kWalkerAgent, kAgentRadius)[row];
      o.since_progress = t.f32(kWalkerAgent, kAgentSinceProgress)[row];
      o.arrived = (t.u32(kWalkerAgentState, kAgentFlags)[row] & kAgentArrived) != 0u ? 1u : 0u;
      out.push_back(o);
    }
  }
}

void CrowdMetrics::observe(const Crowd& crowd, float dt) {
  if (!crowd.agents) return;
  observed_.clear();
  collect_agent_observations(crowd, observed_);
  observe(observed_, dt);
}

void CrowdMetrics::observe(std::span<const AgentObservation> agents, float dt) { observe(agents, {}, dt); }

void CrowdMetrics::observe(std::span<const AgentObservation> owned, std::span<const AgentObservation> border,
                           float dt) {
  const auto frame = static_cast<std::uint32_t>(report_.frames);
  ++report_.frames;
  report_.seconds += dt;
  x_.clear();
  z_.clear();
  r_.clear();
  walker_.clear();
  float max_radius = 0.0f;
  for (const AgentObservation& o : owned) {
    if (o.walker >= tracks_.size()) tracks_.resize(o.walker + 1);
    AgentTrack& track = tracks_[o.walker];
    track.seen = true;
    report_.nan_count += o.nonfinite;
    if (o.arrived != 0u && track.arrival_frame == kNever) {
      track.arrival_frame = frame;
      // Seconds since the run began: every agent's first goal is set when it spawns, and an agent with cycling
      // goals gets its next one (and a fresh travel clock) in the very step it arrives.
      track.time_to_goal = static_cast<float>(report_.seconds);
    }
    // Stuck counts only before the first arrival (report() compares the two frames).
    if (o.since_progress >= stuck_seconds_ && track.stuck_frame == kNever) track.stuck_frame = frame;
  }
  // Owned agents first, then the border's: index < owned_count tells them apart.
  const auto add = [&](const AgentObservation& o) {
    if (!std::isfinite(o.x) || !std::isfinite(o.z) || !std::isfinite(o.radius)) return;
    x_.push_back(o.x);
    z_.push_back(o.z);
    r_.push_back(o.radius);
    walker_.push_back(o.walker);
    max_radius = std::max(max_radius, o.radius);
  };
  for (const AgentObservation& o : owned) add(o);
  const std::size_t owned_count = x_.size();
  for (const AgentObservation& o : border) add(o);
  // Pairs within reach: a uniform grid of cells as wide as the farthest pair measured, each agent tested against
  // the cells around it.
  const std::size_t n = x_.size();
  if (n < 2 || owned_count == 0) return;
  const float cell = std::max(2.0f * max_radius + static_cast<float>(pair_reach_), 0.05f);
  float min_x = x_[0], min_z = z_[0], max_x = x_[0], max_z = z_[0];
  for (std::size_t i = 1; i < n; ++i) {
    min_x = std::min(min_x, x_[i]);
    max_x = std::max(max_x, x_[i]);
    min_z = std::min(min_z, z_[i]);
    max_z = std::max(max_z, z_[i]);
  }
  // Agents spread far apart would make a huge grid: cap it, cells then just hold more agents.
  const auto cols = static_cast<std::size_t>(std::min(4096.0f, (max_x - min_x) / cell + 1.0f));
  const auto rows = static_cast<std::size_t>(std::min(4096.0f, (max_z - min_z) / cell + 1.0f));
  const float cw = std::max((max_x - min_x) / static_cast<float>(cols), cell);
  const float ch = std::max((max_z - min_z) / static_cast<float>(rows), cell);
  auto cell_of = [&](float x, float z) {
    const auto cx = std::min(cols - 1, static_cast<std::size_t>((x - min_x) / cw));
    const auto cz = std::min(rows - 1, static_cast<std::size_t>((z - min_z) / ch));
    return cz * cols + cx;
  };
  cell_start_.assign(cols * rows + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++cell_start_[cell_of(x_[i], z_[i]) + 1];
  for (std::size_t c = 0; c < cols * rows; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_items_.resize(n);
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) cell_items_[fill[cell_of(x_[i], z_[i])]++] = static_cast<std::uint32_t>(i);
  for (std::size_t i = 0; i < owned_count; ++i) {
    const auto cx = static_cast<std::ptrdiff_t>(std::min(cols - 1, static_cast<std::size_t>((x_[i] - min_x) / cw)));
    const auto cz = static_cast<std::ptrdiff_t>(std::min(rows - 1, static_cast<std::size_t>((z_[i] - min_z) / ch)));
    for (std::ptrdiff_t dz = -1; dz <= 1; ++dz) {
      for (std::ptrdiff_t dx = -1; dx <= 1; ++dx) {
        const std::ptrdiff_t x = cx + dx, z = cz + dz;
        if (x < 0 || z < 0 || x >= static_cast<std::ptrdiff_t>(cols) || z >= static_cast<std::ptrdiff_t>(rows)) continue;
        const std::size_t c = static_cast<std::size_t>(z) * cols + static_cast<std::size_t>(x);
        for (std::uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
          const std::uint32_t j = cell_items_[k];
          // Two owned agents: each pair once. An owned and a border agent: on the process owning the lower index.
          if (j < owned_count ? j <= i : walker_[j] < walker_[i]) continue;
          const double d = std::hypot(static_cast<double>(x_[i]) - x_[j], static_cast<double>(z_[i]) - z_[j]);
          // The radii summed first (exactly, in double), so the clearance of a pair does not depend on which of
          // the two came first: the figures are the same whatever order the agents were observed in.
          const double clearance = d - (static_cast<double>(r_[i]) + static_cast<double>(r_[j]));
          if (!(clearance < pair_reach_)) continue;
          if (!any_clearance_ || clearance < report_.min_clearance_m) report_.min_clearance_m = clearance;
          any_clearance_ = true;
          if (clearance < -tolerance_) ++report_.overlaps;
        }
      }
    }
  }
}

CrowdMetricsReport CrowdMetrics::report() const {
  CrowdMetricsReport r = report_;
  if (!any_clearance_) r.min_clearance_m = pair_reach_;
  std::vector<float> times;
  std::size_t seen = 0;
  r.stuck_agents = 0;
  for (const AgentTrack& t : tracks_) {
    if (!t.seen) continue;
    ++seen;
    if (t.arrival_frame != kNever) times.push_back(t.time_to_goal);
    if (t.stuck_frame < t.arrival_frame) ++r.stuck_agents;
  }
  r.agents = seen;
  r.reached_goal_pct = seen > 0 ? 100.0 * static_cast<double>(times.size()) / static_cast<double>(seen) : 0.0;
  if (!times.empty()) {
    double sum = 0;
    for (const float t : times) sum += t;
    r.time_to_goal_mean_s = sum / static_cast<double>(times.size());
    std::sort(times.begin(), times.end());
    r.time_to_goal_p95_s = times[std::min(times.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(times.size())))];
  }
  return r;
}

namespace {

// The packed form: a header (frames, overlaps, NaN count, whether a clearance was seen, the clearance), then per
// agent seen its entity index, arrival and stuck frames and time to goal.
struct PackedHeader {
  std::uint64_t frames, overlaps, nan_count, any_clearance;
  double min_clearance;
};
struct PackedTrack {
  std::uint32_t walker, arrival_frame, stuck_frame;
  float time_to_goal;
};

}  // namespace

std::vector<std::uint8_t> CrowdMetrics::pack() const {
  const PackedHeader h{report_.frames, report_.overlaps, report_.nan_count, any_clearance_ ? 1u : 0u,
                       report_.min_clearance_m};
  std::vector<std::uint8_t> out(sizeof h);
  std::memcpy(out.data(), &h, sizeof h);
  for (std::size_t w = 0; w < tracks_.size(); ++w) {
    const AgentTrack& t = tracks_[w];
    if (!t.seen) continue;
    const PackedTrack p{static_cast<std::uint32_t>(w), t.arrival_frame, t.stuck_frame, t.time_to_goal};
    const std::size_t at = out.size();
    out.resize(at + sizeof p);
    std::memcpy(out.data() + at, &p, sizeof p);
  }
  return out;
}

void CrowdMetrics::merge(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < sizeof(PackedHeader) || (bytes.size() - sizeof(PackedHeader)) % sizeof(PackedTrack) != 0)
    throw std::runtime_error("CrowdMetrics::merge: " + std::to_string(bytes.size()) + " bytes are not packed metrics");
  PackedHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  if (h.frames != report_.frames)
    throw std::runtime_error("CrowdMetrics::merge: metrics of " + std::to_string(h.frames) + " steps, not " +
                             std::to_string(report_.frames));
  const std::size_t n = (bytes.size() - sizeof h) / sizeof(PackedTrack);
  std::vector<PackedTrack> tracks(n);
  if (n > 0) std::memcpy(tracks.data(), bytes.data() + sizeof h, n * sizeof(PackedTrack));
  for (const PackedTrack& p : tracks)
    if (p.walker == kNever || (p.arrival_frame != kNever && p.arrival_frame >= h.frames) ||
        (p.stuck_frame != kNever && p.stuck_frame >= h.frames) || !std::isfinite(p.time_to_goal))
      throw std::runtime_error("CrowdMetrics::merge: agent " + std::to_string(p.walker) + " has impossible frames");
  report_.overlaps += h.overlaps;
  report_.nan_count += h.nan_count;
  if (h.any_clearance != 0u && (!any_clearance_ || h.min_clearance < report_.min_clearance_m)) {
    report_.min_clearance_m = h.min_clearance;
    any_clearance_ = true;
  }
  for (const PackedTrack& p : tracks) {
    if (p.walker >= tracks_.size()) tracks_.resize(p.walker + 1);
    AgentTrack& t = tracks_[p.walker];
    t.seen = true;
    if (p.arrival_frame < t.arrival_frame) t.arrival_frame = p.arrival_frame, t.time_to_goal = p.time_to_goal;
    t.stuck_frame = std::min(t.stuck_frame, p.stuck_frame);
  }
}

}  // namespace strata
