// strata report muscle: the muscle layer measured through the engine's own systems (fk -> muscle -> skin) on
// one walker of the default rig: zero displacement at rest, the biceps bulge over an elbow flexion with the arm
// raised forward (the paper's Figure 6) and its relaxation on extension, finiteness over a walk, the SIMD kernel
// against its scalar twin, and optionally the Figure 6 renders.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <glm/gtc/quaternion.hpp>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "scene/scene_setup.h"
#include "apps/json_output.h"
#include "io/image_writer.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/crowd_renderer.h"
#include "systems/fk.h"
#include "systems/muscle.h"
#include "systems/pose_gather.h"
#include "reference/skin_reference.h"
#include "scene/body_settings.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

constexpr float kDeg = 3.14159265f / 180.0f;
const float kFlexions[] = {0.0f, 30.0f, 60.0f, 90.0f, 120.0f};

struct MuscleReportOptions {
  std::string json;
  std::string images;  // directory for the Figure 6 renders; empty = none
  float seconds = 2.5f;
  float fps = 60.0f;
};

// One walker of the default rig held in a pose written straight into its rotation columns.
class PosedWalker {
 public:
  explicit PosedWalker(int level) {
    SceneOptions o;
    o.walkers = 1;
    o.rest = true;
    o.motion = "clip";
    o.level = DetailLevel::mesh(level);
    scene_ = build_scene(o);
    const Skeleton& s = scene_->rig().skeleton;
    shoulder_ = s.find_joint("l_shoulder");
    elbow_ = s.find_joint("l_elbow");
    if (shoulder_ < 0 || elbow_ < 0 || !scene_->has_muscles()) throw std::runtime_error("default rig lacks muscles");
    // At the origin, facing +Z, unscaled: world space is humanoid space, as the scalar twin computes it.
    const WalkerLanes l = scene_->lanes();
    const float placement[5] = {0.0f, 0.0f, 0.0f, 0.0f, 1.0f};
    for (int c = 0; c < 5; ++c) l.at(l.placement, c)[0] = placement[c];
  }

  Crowd& scene() { return *scene_; }

  // Arm raised forward by `raise` degrees at the shoulder, elbow flexed by `flex` degrees (both about -X in
  // H-Anim: towards the front).
  void pose(float raise, float flex) {
    const WalkerLanes l = scene_->lanes();
    for (std::uint32_t j = 0; j < l.joints; ++j)
      for (int c = 0; c < 4; ++c) l.at(l.local_rotation, j * 4 + c)[0] = c == 3 ? 1.0f : 0.0f;
    set_rotation(l, shoulder_, glm::angleAxis(-raise * kDeg, glm::vec3(1, 0, 0)));
    set_rotation(l, elbow_, glm::angleAxis(-flex * kDeg, glm::vec3(1, 0, 0)));
  }

  // fk -> muscle -> skin with the given force gain (0 = pure linear blend skinning on the same layout).
  const SkinnedCrowd& run(float gain) {
    MuscleGains gains = scene_->skin.gains;
    gains.global = gain;
    set_muscle_gains(*scene_, gains);
    run_or_throw(make_fk_job(scene_->rig().skeleton, scene_->table(initial_slot(*scene_))), "fk");
    run_or_throw(make_muscle_job(scene_->rig().muscles->set, scene_->table(initial_slot(*scene_))), "muscle");
    run_or_throw(make_skin_job(current_layout(*scene_), scene_->table(initial_slot(*scene_)), out_), "skin");
    return out_;
  }

  // Largest displacement along the normal of the vertices bound to `muscle` between gain 1 and gain 0, m.
  double bulge(int muscle) {
    const SkinnedCrowd lbs = run(0.0f);
    const SkinnedCrowd& with = run(1.0f);
    const SkinLayout& layout = current_layout(*scene_);
    const MuscleBinding& binding = scene_->rig().muscles->levels[static_cast<std::size_t>(scene_->skin.level.index())];
    double best = -1e30;
    for (std::size_t i = 0; i < layout.vertex_count; ++i) {
      const std::uint32_t b = layout.muscle_slot[i];
      if (b == SkinLayout::kNoMuscle || binding.line[b] != muscle) continue;
      best = std::max(best, double(glm::dot(with.position(0, i) - lbs.position(0, i), with.normal(0, i))));
    }
    return best;
  }

  float force(int muscle) {
    const ActionLine& line = scene_->rig().muscles->set.lines[static_cast<std::size_t>(muscle)];
    const WalkerLanes l = scene_->lanes();
    return l.at(l.muscle_force, line.first_point + line.point_count / 2)[0];
  }

 private:
  static void set_rotation(const WalkerLanes& l, int joint, const glm::quat& q) {
    const float v[4] = {q.x, q.y, q.z, q.w};
    for (int c = 0; c < 4; ++c) l.at(l.local_rotation, std::size_t(joint) * 4 + c)[0] = v[c];
  }

  std::unique_ptr<Crowd> scene_;
  int shoulder_ = -1, elbow_ = -1;
  SkinnedCrowd out_;
};

std::size_t count_non_finite(const SkinnedCrowd& s) {
  std::size_t bad = 0;
  for (std::size_t w = 0; w < s.walkers; ++w)
    for (std::size_t v = 0; v < s.vertex_count; ++v) {
      const glm::vec3 p = s.position(w, v), n = s.normal(w, v);
      for (int c = 0; c < 3; ++c) bad += !std::isfinite(p[c]) + !std::isfinite(n[c]);
    }
  return bad;
}

// Walks a few walkers with muscles at `level` and counts non-finite skin and muscle values.
std::size_t walk_nan_count(int level, const MuscleReportOptions& o) {
  SceneOptions so;
  so.walkers = 4;
  so.level = DetailLevel::mesh(level);
  std::unique_ptr<Crowd> scene = build_scene(so);
  Profiler profiler(8, false);
  std::size_t bad = 0;
  const auto frames = static_cast<int>(o.seconds * o.fps);
  for (int f = 0; f < frames; ++f) {
    step(*scene, 1.0f / o.fps, profiler);
    bad += count_non_finite(current_skinned(*scene));
    const WalkerLanes l = scene->lanes();
    for (std::size_t w = 0; w < l.count; ++w)
      for (std::size_t p = 0; p < l.muscle_points; ++p)
        bad += !std::isfinite(l.at(l.muscle_force, p)[w]) + !std::isfinite(l.at(l.muscle_length, p)[w]) +
               !std::isfinite(l.at(l.muscle_point, p * 3)[w]);
  }
  return bad;
}

// The kernel's output (layout order, world space; the walker stands at the origin unscaled) against the scalar
// twin with muscles, largest position difference in metres.
double kernel_vs_reference(PosedWalker& walker) {
  Crowd& scene = walker.scene();
  const SkinnedCrowd& kernel = walker.run(1.0f);
  const WalkerLanes l = scene.lanes();
  const auto level = static_cast<std::size_t>(scene.skin.level.index());
  const BodyLevel& body = scene.rig().body->levels[level];
  const std::vector<float> force = walker_muscle_forces(l, 0);
  const MuscleReference m{&scene.rig().muscles->set, &scene.rig().muscles->levels[level], scene.skin.gains, force};
  const SkinnedVertices ref = skin_reference(body.mesh, body.binding, walker_skinning_matrices(l, 0), m);
  double worst = 0.0;
  const SkinLayout& layout = current_layout(scene);
  for (std::size_t i = 0; i < layout.vertex_count; ++i)
    worst = std::max(worst, double(glm::length(kernel.position(0, i) - ref.positions[layout.original[i]])));
  return worst;
}

// Figure 6: the arm raised forward, then flexed without and with the muscle layer, side by side in one PNG.
void write_figure(PosedWalker& walker, const std::filesystem::path& dir) {
  constexpr int kPanel = 480;
  auto context = create_headless_gl_context();
  CrowdRenderer renderer(kPanel, kPanel);
  renderer.options().draw_skeleton = false;
  renderer.options().draw_ground = false;
  Crowd& scene = walker.scene();
  struct Shot {
    float flex, gain;
  };
  const Shot shots[] = {{0.0f, 1.0f}, {120.0f, 0.0f}, {120.0f, 1.0f}};
  std::vector<std::uint8_t> image(std::size_t(3) * kPanel * kPanel * 4), pixels;
  OrbitCamera camera;
  camera.yaw = 1.75f;  // from the walker's left, a little behind, looking down on the top of the raised arm
  camera.pitch = 0.5f;
  for (int s = 0; s < 3; ++s) {
    walker.pose(75.0f, shots[s].flex);
    const SkinnedCrowd& skin = walker.run(shots[s].gain);
    if (s == 0) {
      // Frame the raised arm: the left upper arm and forearm, from the shoulder forward.
      const glm::vec3 lo(0.12f, 1.30f, -0.10f), hi(0.30f, 1.70f, 0.35f);
      camera.frame_box_tight(lo, hi, 1.0f, 1.05f);
    }
    BodyDrawInput bodies;
    bodies.triangles = current_layout(scene).triangles;
    bodies.px = skin.px.data(), bodies.py = skin.py.data(), bodies.pz = skin.pz.data();
    bodies.nx = skin.nx.data(), bodies.ny = skin.ny.data(), bodies.nz = skin.nz.data();
    bodies.stride = skin.stride;
    bodies.vertex_count = skin.vertex_count;
    bodies.walker_count = 1;
    std::vector<glm::vec3> joints;
    gather_joint_positions(scene.lanes(), joints);
    SkeletonDrawInput input{&scene.rig().skeleton, joints, 1};
    renderer.render(input, camera.view(), camera.projection(1.0f), &bodies);
    renderer.read_rgba(pixels);
    for (int y = 0; y < kPanel; ++y)
      std::copy_n(pixels.begin() + std::ptrdiff_t(y) * kPanel * 4, kPanel * 4,
                  image.begin() + (std::ptrdiff_t(y) * 3 * kPanel + s * kPanel) * 4);
  }
  std::filesystem::create_directories(dir);
  write_image(dir / "muscle_figure6.png", 3 * kPanel, kPanel, 4, image);
}

int run_muscle_report(const MuscleReportOptions& o) {
  if (!check_outputs("report muscle", {{"--json", o.json}, {"--images", o.images, true}})) return kExitFailure;
  try {
    nlohmann::json out;
    nlohmann::json levels = nlohmann::json::array();
    double rest_max = 0.0;
    std::size_t nan_count = 0;
    std::printf("%-5s %8s %14s %22s %8s\n", "level", "bound", "rest disp (m)", "kernel vs scalar (m)", "NaN");
    for (int level = 0; level < 3; ++level) {
      PosedWalker walker(level);
      walker.pose(0.0f, 0.0f);
      const SkinnedCrowd lbs = walker.run(0.0f);
      const SkinnedCrowd& with = walker.run(1.0f);
      double rest = 0.0;
      for (std::size_t i = 0; i < with.vertex_count; ++i)
        rest = std::max(rest, double(glm::length(with.position(0, i) - lbs.position(0, i))));
      walker.pose(90.0f, 120.0f);
      const double twin = kernel_vs_reference(walker);
      const std::size_t nan = walk_nan_count(level, o);
      const MuscleBinding& binding = walker.scene().rig().muscles->levels[static_cast<std::size_t>(level)];
      rest_max = std::max(rest_max, rest);
      nan_count += nan;
      levels.push_back({{"level", level},
                        {"vertices", with.vertex_count},
                        {"bound_vertices", binding.size()},
                        {"rest_displacement_max_m", rest},
                        {"kernel_vs_reference_max_m", twin},
                        {"nan_count", nan}});
      std::printf("%-5d %8zu %14.3g %22.3g %8zu\n", level, binding.size(), rest, twin, nan);
    }

    PosedWalker walker(0);
    const MuscleSet& set = walker.scene().rig().muscles->set;
    const int biceps = set.find("l_biceps");
    nlohmann::json bulge = nlohmann::json::object(), force = nlohmann::json::object();
    std::vector<double> flex_up, flex_down;
    for (float a : kFlexions) {
      walker.pose(90.0f, a);
      flex_up.push_back(walker.bulge(biceps) * 1000.0);
      bulge[std::to_string(int(a))] = flex_up.back();
      force[std::to_string(int(a))] = walker.force(biceps);
    }
    for (auto it = std::rbegin(kFlexions); it != std::rend(kFlexions); ++it) {
      walker.pose(90.0f, *it);
      flex_down.push_back(walker.bulge(biceps) * 1000.0);
    }
    bool increasing = true, relaxes = true;
    for (std::size_t i = 1; i < flex_up.size(); ++i) increasing = increasing && flex_up[i] > flex_up[i - 1];
    for (std::size_t i = 1; i < flex_down.size(); ++i) relaxes = relaxes && flex_down[i] < flex_down[i - 1];
    relaxes = relaxes && std::fabs(flex_down.back()) <= 1e-3;  // back to the rest shape (mm)

    nlohmann::json per_muscle = nlohmann::json::object();
    const MuscleBinding& b0 = walker.scene().rig().muscles->levels[0];
    for (std::size_t m = 0; m < set.lines.size(); ++m)
      per_muscle[set.lines[m].name] = std::count(b0.line.begin(), b0.line.end(), static_cast<std::uint16_t>(m));

    out["muscles"] = set.lines.size();
    out["control_points"] = set.point_count;
    out["bound_vertices"] = b0.size();
    out["bound_vertices_per_muscle"] = per_muscle;
    out["rest_displacement_max_m"] = rest_max;
    out["biceps_bulge_mm"] = bulge;
    out["biceps_force_factor"] = force;
    out["biceps_bulge_increases"] = increasing;
    out["relaxes_on_extension"] = relaxes;
    out["nan_count"] = nan_count;
    out["levels"] = levels;
    const bool ok = rest_max < 1e-6 && increasing && relaxes && nan_count == 0;
    out["targets_met"] = ok;
    if (!o.images.empty()) write_figure(walker, o.images);
    if (!o.json.empty()) write_json_file(o.json, out);

    std::printf("biceps bulge (mm) at elbow flexion 0/30/60/90/120 deg, arm raised forward:");
    for (double v : flex_up) std::printf(" %.2f", v);
    std::printf("\nback down 120..0 deg:");
    for (double v : flex_down) std::printf(" %.2f", v);
    std::printf("\nmuscles %zu, control points %u, bound vertices (level 0) %zu; rest displacement %.3g m; "
                "increases %s, relaxes %s, NaN %zu; targets %s\n",
                set.lines.size(), set.point_count, b0.size(), rest_max, increasing ? "yes" : "NO",
                relaxes ? "yes" : "NO", nan_count, ok ? "met" : "MISSED");
  } catch (const std::exception& e) {
    print_error("report muscle", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_muscle_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<MuscleReportOptions>();
  auto* cmd = report.add_subcommand("muscle", "Measure the muscle layer: rest displacement, biceps bulge over an "
                                              "elbow flexion, relaxation, NaN, kernel vs scalar twin");
  cmd->add_option("--json", o->json, "Write the report here");
  cmd->add_option("--images", o->images, "Write the paper's Figure 6 (raised, flexed without / with muscles) here");
  cmd->add_option("--seconds", o->seconds, "Seconds of walking checked for NaN per level")->capture_default_str()
      ->check(positive_up_to(3600));
  cmd->callback([o, &exit_code] { exit_code = run_muscle_report(*o); });
}

}  // namespace strata::cli
