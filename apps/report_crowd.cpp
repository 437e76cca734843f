// strata report crowd: run a scenario without rendering and write how the crowd behaved as JSON — overlaps,
// clearance, goals reached and how fast, stuck agents, foot slide of the walk that follows the agents, NaN, and
// what avoidance and navigation cost. Every figure is measured in this run.
//
// Walkers are simulated without a body (--level -1 by default): the walk, IK and FK run for every walker, so foot
// slide is measured on every one, and skinning, which the report does not measure, would only slow it.
//
// Under mpirun each rank steps its slab's agents (apps/crowd_distributed.h) and observes them, with the agents of
// other ranks near its slab for the pairs across borders (scene/crowd_metrics.h); rank 0 merges every rank's
// metrics at the end, so the crowd's figures are one process's while each step's traffic grows with the borders,
// not the crowd. Foot slide is followed by each rank for the walkers it holds, and the costs are the slowest
// rank's (each rank's in "mpi").
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <memory>
#include <string>
#include <vector>

#include "apps/cli_support.h"
#include "apps/crowd_distributed.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "profiling/profiler.h"
#include "scene/crowd.h"
#include "scene/crowd_agents.h"
#include "scene/crowd_metrics.h"
#include "scene/scene_setup.h"
#include "scene/step.h"
#include "systems/gait_metrics.h"

namespace strata::cli {
namespace {

struct CrowdReportOptions {
  SceneOptions scene;
  double seconds = 0;  // 0: the scenario's duration
  float fps = 30.0f;
  std::string json;
  bool keep_going = false;  // run the whole duration even when every agent has arrived
  bool body = false;
  double rebalance_seconds = 2.0;  // under mpirun (apps/crowd_distributed.h)
  double mpi_timeout_seconds = 600.0;
};

// Under mpirun, at the end: every rank's metrics merged on rank 0 (a few bytes an agent, once).
void merge_on_root(CrowdDistribution& dist, CrowdMetrics& metrics) {
  const std::vector<std::uint8_t> mine = metrics.pack();
  std::vector<std::size_t> sizes;
  const std::vector<std::uint8_t> all = dist.gather_to_root(mine, &sizes);
  if (!dist.root()) return;
  // In rank order: rank 0's own come first and are already in `metrics`.
  std::size_t at = sizes.empty() ? 0 : sizes[0];
  for (std::size_t r = 1; r < sizes.size(); ++r) {
    metrics.merge(std::span<const std::uint8_t>(all.data() + at, sizes[r]));
    at += sizes[r];
  }
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

int run_crowd_report(const CrowdReportOptions& o) {
  // Under mpirun each rank steps and observes the agents of its slab (apps/crowd_distributed.h); rank 0 merges.
  bool join_failed = false;
  const std::unique_ptr<CrowdDistribution> dist =
      join_if_launched("report crowd", o.rebalance_seconds, o.mpi_timeout_seconds, join_failed);
  if (join_failed) return kExitFailure;
  const bool root = !dist || dist->root();
  Refusal refusal;
  if (root && !o.json.empty()) refusal.refuse_if(kExitFailure, check_output_file("--json", o.json));
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  std::unique_ptr<Crowd> built;
  if (refusal.none()) {
    try {
      if (o.scene.scenario.empty())
        throw std::invalid_argument("--scenario is required (circle, crossing, bottleneck, plaza or a file)");
      SceneOptions scene_options = o.scene;
      if (!o.body) scene_options.level = DetailLevel::none();
      else if (scene_options.level.is_automatic() || scene_options.level.is_impostor()) scene_options.level = DetailLevel::mesh(0);
      check_scene_inputs(scene_options);
      built = build_scene(scene_options);
      if (!built->agents)
        throw std::invalid_argument("--scenario " + o.scene.scenario + " has no agents (the track is the lane walk; "
                                    "use `strata report gait` for it)");
    } catch (const std::exception& e) {
      refusal.refuse_if(kExitFailure, error_text(e));
    }
  }
  if (refusal.stop("report crowd", dist.get())) return refusal.exit_code();
  try {
    const std::unique_ptr<Crowd> scene = std::move(built);
    const Scenario& scenario = scene->agents->scenario;
    const double seconds = o.seconds > 0 ? o.seconds : scenario.duration_s;
    GaitMetrics gait(scene->rig().skeleton, *scene->motion.locomotion, scene->motion.style);
    CrowdMetrics metrics;
    Profiler profiler(120, false);
    const float dt = 1.0f / o.fps;
    auto frames = static_cast<std::size_t>(seconds * o.fps + 0.5);
    std::vector<double> avoidance_ms, navigation_ms;
    std::vector<AgentObservation> observed;
    // Other ranks' agents that can pair with this rank's: within the pair reach plus two bodies of its slab, and
    // a metre for how far an agent moves between the slab cut (at the step's start) and the observation.
    const float border_reach = static_cast<float>(metrics.pair_reach_m()) +
                               2.0f * (scenario.agents.radius + scene->agents->radius_margin) + 1.0f;
    std::vector<std::uint32_t> walker_ids;
    std::size_t done = 0;
    bool all_arrived = false;
    const auto stop_now = [&]() { return dist ? !dist->all_ok(!interrupted()) : interrupted(); };
    for (; done < frames && !stop_now(); ++done) {
      if (dist) dist->assign_walkers(*scene, static_cast<double>(done) * dt);
      profiler.begin_frame();
      const FrameProfile p = step(*scene, dt, profiler);
      profiler.end_frame();
      avoidance_ms.push_back(scene->agents->last_avoidance_ms);
      navigation_ms.push_back(p.stage_ms(Stage::Navigation));
      if (dist) {
        observed.clear();
        collect_agent_observations(*scene, observed);
        metrics.observe(observed, dist->exchange_border_observations(observed, border_reach), dt);
      } else {
        metrics.observe(*scene, dt);
      }
      // The walkers' own table, followed walker by walker: under mpirun its rows change as walkers migrate.
      // (No camera, so no culling or tiers: one table holds them; lanes() throws otherwise.)
      const WalkerLanes lanes = scene->lanes();
      walker_ids.clear();
      for (std::size_t slot = 0; slot < kDetailSlots; ++slot) {
        const SoaTable& t = scene->table(static_cast<DetailSlot>(slot));
        for (std::uint32_t r = 0; r < t.size(); ++r) walker_ids.push_back(t.owner(r).index);
      }
      gait.observe(lanes, scene->motion.paths, dt, walker_ids);
      // Final goals: stop a second after the last agent arrives (the last ones settle into their stance).
      const bool cycling = std::any_of(scenario.groups.begin(), scenario.groups.end(), [](const SpawnGroup& g) {
        return g.goal.kind == GoalKind::Random || g.goal.kind == GoalKind::Waypoints;
      });
      if (!o.keep_going && !cycling) {
        if (!all_arrived && (dist ? dist->all_ok(all_agents_arrived(*scene)) : all_agents_arrived(*scene))) {
          all_arrived = true;
          const auto settle = static_cast<std::size_t>(o.fps);
          frames = std::min(frames, done + settle + 1);
        }
      }
    }
    if (dist) merge_on_root(*dist, metrics);
    const CrowdMetricsReport r = metrics.report();
    GaitReport g = gait.report();
    double avoidance_mean = 0;
    for (const double v : avoidance_ms) avoidance_mean += v;
    avoidance_mean /= std::max<std::size_t>(avoidance_ms.size(), 1);
    double navigation_mean = 0;
    for (const double v : navigation_ms) navigation_mean += v;
    navigation_mean /= std::max<std::size_t>(navigation_ms.size(), 1);
    nlohmann::json mpi;
    if (dist) {
      // The walk's figures from every rank (each followed its own walkers), and the costs per rank: the slowest
      // rank's is the crowd's.
      const auto largest = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
      const auto total = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); };
      g.foot_slide_mm_max = largest(dist->all_gather(g.foot_slide_mm_max));
      g.nan_count = static_cast<std::uint64_t>(total(dist->all_gather(static_cast<double>(g.nan_count))));
      g.ik_unreachable = static_cast<std::uint64_t>(total(dist->all_gather(static_cast<double>(g.ik_unreachable))));
      g.body_speed_max_mps = largest(dist->all_gather(g.body_speed_max_mps));
      g.body_accel_max_mps2 = largest(dist->all_gather(g.body_accel_max_mps2));
      g.body_jolts = static_cast<std::uint64_t>(total(dist->all_gather(static_cast<double>(g.body_jolts))));
      const std::vector<double> avoidance_per_rank = dist->all_gather(avoidance_mean);
      const std::vector<double> navigation_per_rank = dist->all_gather(navigation_mean);
      avoidance_mean = largest(avoidance_per_rank);
      navigation_mean = largest(navigation_per_rank);
      mpi = dist->summary(done);
      if (root) {
        mpi["avoidance_ms_mean_per_rank"] = avoidance_per_rank;
        mpi["navigation_ms_mean_per_rank"] = navigation_per_rank;
      }
      if (!root) return interrupted() ? interrupted_exit_code() : kExitOk;
    }
    const std::uint64_t nans = r.nan_count + g.nan_count;
    const bool ok = r.overlaps == 0 && r.reached_goal_pct >= 100.0 && r.stuck_agents == 0 &&
                    g.foot_slide_mm_max < 1.0 && nans == 0;
    nlohmann::json j;
    j["scenario"] = scenario.name;
    j["scenario_source"] = scenario.source;
    j["inputs"] = scene_inputs_json(o.scene);
    j["seed"] = scenario.seed;
    j["agents"] = r.agents;
    j["frames"] = r.frames;
    j["seconds"] = r.seconds;
    j["fps"] = o.fps;
    j["threads"] = threads;
    j["interrupted"] = interrupted();
    j["overlaps"] = r.overlaps;
    j["min_clearance_m"] = r.min_clearance_m;
    j["reached_goal_pct"] = r.reached_goal_pct;
    j["time_to_goal_s"] = {{"mean", r.time_to_goal_mean_s}, {"p95", r.time_to_goal_p95_s}};
    j["stuck_agents"] = r.stuck_agents;
    j["foot_slide_mm_max"] = g.foot_slide_mm_max;
    j["nan_count"] = nans;
    j["avoidance_ms_per_step"] = {{"mean", avoidance_mean}, {"p95", percentile(avoidance_ms, 0.95)}};
    j["navigation_ms"] = scene->agents->navigation_build_ms;
    j["navigation_ms_per_step"] = {{"mean", navigation_mean}, {"p95", percentile(navigation_ms, 0.95)}};
    const NavBuildInfo& nav = scene->agents->navmesh->info();
    j["navigation_mesh"] = {{"polygons", nav.polygons}, {"bytes", nav.bytes}, {"from_cache", nav.from_cache},
                            {"build_ms", nav.build_ms}, {"load_ms", nav.load_ms}};
    j["ik_unreachable_limb_frames"] = g.ik_unreachable;
    j["body_speed_max_mps"] = g.body_speed_max_mps;
    j["body_accel_max_mps2"] = g.body_accel_max_mps2;
    j["body_jolts"] = g.body_jolts;
    j["targets_met"] = ok;
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"mean_ms", s.mean_ms}, {"p95_ms", s.p95_ms}});
    j["systems"] = systems;
    if (dist) j["mpi"] = mpi;
    if (!o.json.empty()) write_json_file(o.json, j);
    std::printf("crowd report: scenario %s, %zu agents, %zu frames (%.1f s at %.0f fps)\n", scenario.name.c_str(),
                r.agents, r.frames, r.seconds, static_cast<double>(o.fps));
    auto line = [](const char* name, double value, const char* target, bool met) {
      std::printf("%-26s %14.6g   %-12s %s\n", name, value, target, met ? "ok" : "MISSED");
    };
    line("overlaps", static_cast<double>(r.overlaps), "0", r.overlaps == 0);
    line("min_clearance_m", r.min_clearance_m, ">= -0.01", r.min_clearance_m >= -0.01);
    line("reached_goal_pct", r.reached_goal_pct, "100", r.reached_goal_pct >= 100.0);
    line("stuck_agents", static_cast<double>(r.stuck_agents), "0", r.stuck_agents == 0);
    line("foot_slide_mm_max", g.foot_slide_mm_max, "< 1", g.foot_slide_mm_max < 1.0);
    line("nan_count", static_cast<double>(nans), "0", nans == 0);
    std::printf("bodies: fastest %.2f m/s, sharpest change %.1f m/s^2, %llu walker-frames past %.0f m/s^2\n",
                g.body_speed_max_mps, g.body_accel_max_mps2, static_cast<unsigned long long>(g.body_jolts),
                kBodyJoltAccel);
    std::printf("time to goal %.1f s mean, %.1f s p95; avoidance %.3f ms/step mean, %.3f p95; navigation mesh %.1f ms "
                "(%s), planning %.3f ms/step\n",
                r.time_to_goal_mean_s, r.time_to_goal_p95_s, avoidance_mean, percentile(avoidance_ms, 0.95),
                scene->agents->navigation_build_ms, nav.from_cache ? "cache" : "built", navigation_mean);
    if (interrupted()) {
      print_error("report crowd", "interrupted after " + std::to_string(r.frames) + " frames; the report covers them");
      return interrupted_exit_code();
    }
  } catch (const std::exception& e) {
    if (dist) {
      std::fprintf(stderr, "strata report crowd: rank %d: %s; stopping every rank\n", dist->rank(), error_text(e).c_str());
      std::fflush(stderr);
      dist->abort(kExitFailure);
    }
    print_error("report crowd", error_text(e));
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void add_crowd_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<CrowdReportOptions>();
  auto* cmd = report.add_subcommand(
      "crowd", "Run a scenario (no rendering) and measure overlaps, clearance, goals reached, time to goal, stuck "
               "agents, foot slide, NaN, and the cost of avoidance and navigation");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--seconds", o->seconds, "Simulated seconds (default: the scenario's duration; a scenario with "
                                           "final goals stops a second after the last agent arrives)")
      ->check(positive_up_to(86400));
  cmd->add_option("--fps", o->fps, "Simulation steps per second")->capture_default_str()->check(positive_up_to(1000));
  cmd->add_option("--json", o->json, "Write the report here");
  cmd->add_flag("--whole-duration", o->keep_going, "Run the whole duration even when every agent has arrived");
  add_mpi_options(*cmd, o->rebalance_seconds, o->mpi_timeout_seconds);
  cmd->add_flag("--skinned", o->body, "Skin the bodies too (at --level, auto meaning 0; --body picks which); by default walkers have no body");
  cmd->callback([o, &exit_code] { exit_code = run_crowd_report(*o); });
}

}  // namespace strata::cli
