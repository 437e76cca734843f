// strata report gait: walk a crowd without rendering and write the measured gait quality as JSON.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <cstdio>
#include <optional>
#include <iostream>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/report_gait_cycle.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "systems/gait_metrics.h"
#include "scene/gait_cycle.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

struct GaitReportOptions {
  SceneOptions scene;
  double seconds = 60.0;
  float fps = 60.0f;
  std::string json;
  std::string plot;
  bool gait_cycle = true;
};

// The gait cycle of the default walker (the crowds' mean stature at the middle of their lane speeds) with its
// curves, and, per walker class the crowds spawn (slow, middle and fast lane speeds; short and tall walkers), its
// features: the report checks every class, not only the one it draws.
struct GaitCycleSection {
  nlohmann::json json;
  std::vector<GaitCycle> drawn;
  bool met = true;              // every walker's targets, RMS included
  bool default_met = true;      // the default walker's targets
  bool class_features_met = true;  // every class's feature targets
};
GaitCycleSection gait_cycle_section(const Crowd& scene) {
  GaitCycleSection out;
  const NormativeGait& normative = shipped_normative_gait();
  const CrowdConfig crowd;
  GaitCycleOptions base;
  base.height = crowd.height_mean;
  base.speed = 0.5f * (crowd.speed_min + crowd.speed_max);
  const GaitCycle main = measure_gait_cycle(scene.rig(), scene.motion.style, base);
  out.json["gait_cycle"] = gait_cycle_json(main, normative, true);
  out.json["gait_cycle"]["walker_class"] = "default";
  out.met = out.json["gait_cycle"]["targets_met"].get<bool>();
  out.default_met = out.met;
  out.drawn.push_back(main);
  nlohmann::json classes = nlohmann::json::array();
  const float heights[] = {crowd.height_mean - crowd.height_spread, crowd.height_mean + crowd.height_spread};
  const float speeds[] = {0.8f, 1.3f, 1.8f};  // the range the crowds walk at (lanes plus their speed schedules)
  for (const float height : heights) {
    for (const float speed : speeds) {
      GaitCycleOptions o = base;
      o.height = height;
      o.speed = speed;
      const GaitCycle c = measure_gait_cycle(scene.rig(), scene.motion.style, o);
      nlohmann::json j = gait_cycle_json(c, normative, false);
      out.met = out.met && j["targets_met"].get<bool>();
      out.class_features_met = out.class_features_met && j["features_met"].get<bool>();
      classes.push_back(std::move(j));
      if (speed != speeds[1]) out.drawn.push_back(c);  // the extremes; the middle ones lie between
    }
  }
  out.json["gait_cycle_classes"] = classes;
  return out;
}

int run_gait_report(const GaitReportOptions& o) {
  if (!check_outputs("report gait", {{"--json", o.json}, {"--plot", o.plot}})) return kExitFailure;
  if (const std::string why = check_crowd_memory(o.scene); !why.empty()) {
    print_error("report gait", why);
    return kExitFailure;
  }
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    SceneOptions scene_options = o.scene;
    scene_options.motion = "walk";
    // The report measures every walker's pose, and it has no camera: impostors have no pose, and auto without a
    // camera would leave a walking crowd as the impostors it is spawned as. Auto is every walker at level 0
    // here, as it always was without a camera.
    if (scene_options.level.is_impostor())
      throw std::invalid_argument("--level impostor: the gait report measures posed walkers, impostors have no pose "
                                  "(use 0, 1, 2, auto or -1)");
    if (scene_options.level.is_automatic()) scene_options.level = DetailLevel::mesh(0);
    check_scene_inputs(scene_options);
    std::unique_ptr<Crowd> scene = build_scene(scene_options);
    GaitMetrics metrics(scene->rig().skeleton, *scene->motion.locomotion.get(), scene->motion.style);
    Profiler profiler(120, false);
    const float dt = 1.0f / o.fps;
    const auto frames = static_cast<std::size_t>(o.seconds * o.fps + 0.5);
    for (std::size_t f = 0; f < frames && !interrupted(); ++f) {
      profiler.begin_frame();
      step(*scene, dt, profiler);
      metrics.observe(scene->lanes(), scene->motion.paths, dt);
      profiler.end_frame();
    }
    const GaitReport r = metrics.report();
    const bool slide_ok = r.foot_slide_mm_max < 1.0, ik_ok = r.ik_position_error_max_m < 1e-5,
               limits_ok = r.limit_violations == 0, nan_ok = r.nan_count == 0,
               stride_ok = r.stride_length_error_pct < 2.0;
    nlohmann::json j;
    j["walkers"] = r.walkers;
    j["interrupted"] = interrupted();
    j["inputs"] = scene_inputs_json(o.scene);
    j["seconds"] = r.seconds;
    j["frames"] = r.frames;
    j["fps"] = o.fps;
    j["seed"] = o.scene.seed;
    j["foot_slide_mm_max"] = r.foot_slide_mm_max;
    j["foot_slide_ball_mm_max"] = r.foot_slide_ball_mm_max;
    j["foot_slide_ankle_mm_max"] = r.foot_slide_ankle_mm_max;
    j["foot_slide_heel_mm_max"] = r.foot_slide_heel_mm_max;
    j["foot_slide_tip_mm_max"] = r.foot_slide_tip_mm_max;
    j["ik_position_error_max_m"] = r.ik_position_error_max_m;
    j["ik_unreachable_limb_frames"] = r.ik_unreachable;
    j["ik_limits_infeasible_limb_frames"] = r.ik_limits_infeasible;
    j["ik_orientation_clamped_limb_frames"] = r.ik_orientation_clamped;
    j["limit_violations"] = r.limit_violations;
    j["limit_violation_max_rad"] = r.limit_violation_max_rad;
    j["nan_count"] = r.nan_count;
    j["strides"] = r.strides;
    j["stride_length_error_pct"] = r.stride_length_error_pct;
    j["stride_length_mean_m"] = r.stride_length_mean_m;
    j["pelvis_bob_cm_mean"] = r.pelvis_bob_cm_mean;
    j["cadence_min"] = r.cadence_min;
    j["cadence_max"] = r.cadence_max;
    j["swing_clearance_min_mm"] = r.swing_clearance_min_mm;
    j["body_speed_max_mps"] = r.body_speed_max_mps;
    j["body_accel_max_mps2"] = r.body_accel_max_mps2;
    j["body_jolts"] = r.body_jolts;
    j["targets_met"] = slide_ok && ik_ok && limits_ok && nan_ok && stride_ok;
    std::optional<GaitCycleSection> cycle;
    if (o.gait_cycle) {
      cycle = gait_cycle_section(*scene);
      for (auto& [key, value] : cycle->json.items()) j[key] = value;
      j["gait_cycle_targets_met"] = cycle->met;
      if (!o.plot.empty()) write_file_atomically(o.plot, gait_cycle_svg(cycle->drawn, shipped_normative_gait()));
    }
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"mean_ms", s.mean_ms}, {"p95_ms", s.p95_ms}});
    j["systems"] = systems;
    if (!o.json.empty()) write_json_file(o.json, j);
    auto line = [](const char* name, double value, const char* target, bool ok) {
      std::printf("%-26s %14.6g   %-12s %s\n", name, value, target, ok ? "ok" : "MISSED");
    };
    std::printf("gait report: %zu walkers, %.0f s at %.0f fps, %llu strides, cadence %.0f-%.0f steps/min\n",
                r.walkers, r.seconds, static_cast<double>(o.fps), static_cast<unsigned long long>(r.strides),
                r.cadence_min, r.cadence_max);
    line("foot_slide_mm_max", r.foot_slide_mm_max, "< 1", slide_ok);
    line("ik_position_error_max_m", r.ik_position_error_max_m, "< 1e-5", ik_ok);
    line("limit_violations", static_cast<double>(r.limit_violations), "0", limits_ok);
    line("nan_count", static_cast<double>(r.nan_count), "0", nan_ok);
    line("stride_length_error_pct", r.stride_length_error_pct, "< 2", stride_ok);
    std::printf("pelvis bob %.1f cm peak to peak (mean), mean stride %.3f m, swing clearance >= %.0f mm; bodies at "
                "most %.2f m/s, %.1f m/s^2, %llu walker-frames past %.0f m/s^2\n",
                r.pelvis_bob_cm_mean, r.stride_length_mean_m, r.swing_clearance_min_mm, r.body_speed_max_mps,
                r.body_accel_max_mps2, static_cast<unsigned long long>(r.body_jolts), kBodyJoltAccel);
    if (cycle) {
      const nlohmann::json& c = cycle->json["gait_cycle"];
      const nlohmann::json& f = c["features"];
      std::printf("gait cycle (%.2f m, %.2f m/s): knee %.1f at heel strike, %.1f loading, %.1f stance min, %.1f swing "
                  "peak; hip %.1f..%.1f; ankle %.1f..%.1f; trunk %.1f..%.1f; pelvis %.1f cm; rms knee %.1f hip %.1f "
                  "ankle %.1f deg: %s; classes' features %s, classes' RMS %s\n",
                  c["height_m"].get<double>(), c["speed_m_s"].get<double>(), f["heel_strike_knee_deg"].get<double>(),
                  f["loading_knee_peak_deg"].get<double>(), f["stance_knee_min_deg"].get<double>(),
                  f["swing_knee_peak_deg"].get<double>(), f["hip_min_deg"].get<double>(),
                  f["hip_max_deg"].get<double>(), f["ankle_min_deg"].get<double>(), f["ankle_max_deg"].get<double>(),
                  f["trunk_min_deg"].get<double>(), f["trunk_max_deg"].get<double>(),
                  c["pelvis_vertical_excursion_cm"].get<double>(), c["normative_rms_deg"]["knee"].get<double>(),
                  c["normative_rms_deg"]["hip"].get<double>(), c["normative_rms_deg"]["ankle"].get<double>(),
                  cycle->default_met ? "ok" : "MISSED", cycle->class_features_met ? "ok" : "MISSED",
                  cycle->met ? "ok" : "MISSED");
    }
    if (interrupted()) {
      print_error("report gait", "interrupted after " + std::to_string(r.frames) + " of " + std::to_string(frames) +
                                     " frames; the report covers the frames done");
      return interrupted_exit_code();
    }
  } catch (const std::exception& e) {
    print_error("report gait", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_report_command(CLI::App& app, int& exit_code) {
  auto* report = app.add_subcommand("report", "Measure a layer of the engine and write the numbers as JSON");
  report->require_subcommand(1);
  auto o = std::make_shared<GaitReportOptions>();
  auto* gait = report->add_subcommand("gait", "Walk a crowd (no rendering) and measure foot slide, IK accuracy, "
                                              "joint limits, NaN and stride length against the gait formula");
  add_scene_options(*gait, o->scene);
  gait->add_option("--seconds", o->seconds, "Simulated seconds")->capture_default_str()->check(positive_up_to(86400));
  gait->add_option("--fps", o->fps, "Simulation steps per second")->capture_default_str()->check(positive_up_to(1000));
  gait->add_option("--json", o->json, "Write the report here");
  gait->add_option("--plot", o->plot,
                   "Write the gait cycle's joint-angle curves against the normative subject here (SVG)");
  gait->add_flag("!--no-gait-cycle", o->gait_cycle, "Skip the gait cycle measurement (joint-angle curves)");
  gait->callback([o, &exit_code] { exit_code = run_gait_report(*o); });
  add_skin_report(*report, exit_code);
  add_muscle_report(*report, exit_code);
  add_subdiv_report(*report, exit_code);
  add_lod_report(*report, exit_code);
  add_crowd_report(*report, exit_code);
  add_retarget_report(*report, exit_code);
}

}  // namespace strata::cli
