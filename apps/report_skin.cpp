// strata report skin: the default body's levels, their binding (the paper's Table 1 columns) and how well linear
// blend skinning holds up over a walk cycle and at 120 deg elbow/knee flexion, for the three-step binding and
// for the automatic bone-heat weights side by side.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <set>

#include <glm/gtc/quaternion.hpp>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "reference/skin_walk.h"
#include "io/hanim_loader.h"
#include "rig/binding.h"
#include "rig/body_generator.h"
#include "rig/body_rig.h"
#include "rig/cor_centres.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "systems/skin_kernel.h"
#include "io/image_writer.h"
#include "render/camera.h"
#include "render/crowd_renderer.h"
#include "render/gl_context.h"
#include "scene/scene_setup.h"
#include "systems/fk.h"
#include "systems/pose_gather.h"
#include "reference/skin_metrics.h"
#include "reference/fk_reference.h"
#include "reference/skin_reference.h"

namespace strata::cli {
namespace {

struct SkinReportOptions {
  std::string json;
  std::string images;  // directory for the modes figure; empty = none
  float seconds = 2.5f;  // of walking: two gait cycles at the default cadence
  float fps = 60.0f;
  bool automatic = true;
  ShippedBody body = kDefaultShippedBody;
};

struct Quality {
  std::size_t inverted_triangles = 0;          // worst frame of the walk
  std::size_t flexion_inverted_triangles = 0;  // worst of the two 120 deg flexions
  double seam_gap_max_m = 0.0;
  std::size_t nan_count = 0;
  double elbow_volume_change_pct = 0.0, knee_volume_change_pct = 0.0;
};

// Walks one walker through `seconds` and a 120 deg flexion of the left elbow and knee; measures every frame.
Quality measure(const Rig& rig, const BodyLevel& level, const SkinReportOptions& o) {
  Quality q;
  const WalkSkinMetrics walk = measure_walk_skin(rig, level, o.seconds, o.fps);
  q.inverted_triangles = walk.inverted_triangles;
  q.seam_gap_max_m = walk.seam_gap_max_m;
  q.nan_count = walk.nan_count;
  const Skeleton& s = rig.skeleton;
  for (const char* name : {"l_elbow", "l_knee"}) {
    const int joint = s.find_joint(name);
    if (joint < 0) continue;
    // Flexion the way the joint's limits allow more of it (elbows -x, knees +x in H-Anim).
    const JointLimits& lim = s.limits[joint];
    const float angle = lim.present && -lim.lower.x > lim.upper.x ? -2.0944f : 2.0944f;
    std::vector<glm::quat> rotations(s.joint_count(), glm::quat(1, 0, 0, 0));
    rotations[joint] = glm::angleAxis(angle, glm::vec3(1, 0, 0));
    const ReferencePose pose = fk_reference(s, rotations, glm::vec3(0.0f));
    const SkinnedVertices posed = skin_reference(level.mesh, level.binding, pose.skinning);
    const SkinMetrics m = measure_skin(level.mesh, level.binding, pose.skinning, posed.positions);
    q.flexion_inverted_triangles = std::max(q.flexion_inverted_triangles, m.inverted_triangles);
    q.seam_gap_max_m = std::max(q.seam_gap_max_m, m.seam_gap_max_m);
    q.nan_count += m.nan_count;
    const double change = flexion_volume_change_pct(level.mesh, level.binding, s, joint, std::abs(angle),
                                                    std::string(name) == "l_elbow" ? 0.08f : 0.11f);
    (std::string(name) == "l_elbow" ? q.elbow_volume_change_pct : q.knee_volume_change_pct) = change;
  }
  return q;
}

nlohmann::json quality_json(const Quality& q) {
  return {{"inverted_triangles", q.inverted_triangles},
          {"flexion_inverted_triangles", q.flexion_inverted_triangles},
          {"seam_gap_max_m", q.seam_gap_max_m},
          {"elbow_volume_change_pct", q.elbow_volume_change_pct},
          {"knee_volume_change_pct", q.knee_volume_change_pct},
          {"nan_count", q.nan_count}};
}

// One skinning mode on level 0 (three-step binding): what the targets read.
struct ModeQuality {
  double elbow_volume_change_pct = 0.0, knee_volume_change_pct = 0.0;
  double twist90_area_ratio = 1.0, twist180_area_ratio = 1.0, twist_section_axial_m = 0.0;
  double bulge_mm_max = 0.0;
  std::size_t inverted_triangles_walk = 0;
  double vertices_per_second = 0.0;
};

// Level 0 skinned by the kernel on one core, one walker in a walking pose, without muscles: seconds per call,
// the best of several interleaved rounds per mode (interleaving spreads a shared machine's noise over every
// mode alike; the best round is the one least disturbed).
std::array<double, 3> kernel_seconds(const Rig& base, ShippedBody body) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Rig rig = base;
  rig.body = default_bound_body(body);
  rig.muscles = nullptr;
  std::array<std::unique_ptr<Crowd>, 3> scenes;
  std::array<std::vector<float>, 3> outs;
  std::array<SkinWalkerJob, 3> jobs;
  for (std::size_t m = 0; m < 3; ++m) {
    scenes[m] = std::make_unique<Crowd>(rig);
    CrowdConfig config;
    config.walkers = 1;
    config.motion = MotionSource::Walk;
    spawn_crowd(*scenes[m], config);
    set_skinning_mode(*scenes[m], kSkinningModes[m]);
    set_detail_level(*scenes[m], DetailLevel::mesh(0));
    Profiler profiler(8, false);
    for (int f = 0; f < 10; ++f) step(*scenes[m], 1.0f / 30.0f, profiler);
    const SkinLayout& layout = current_layout(*scenes[m]);
    const std::size_t padded = pad_to_lanes(layout.vertex_count);
    outs[m].assign(6 * padded, 0.0f);
    jobs[m] = make_skin_walker_job(layout, scenes[m]->table(initial_slot(*scenes[m])), 0,
                                   skin_output_in(outs[m].data(), padded), kSkinningModes[m]);
    if (!jobs[m].validate()) throw std::runtime_error("report skin: the timing job does not validate");
  }
  std::array<double, 3> best{1e30, 1e30, 1e30};
  for (int round = 0; round < 7; ++round)
    for (std::size_t m = 0; m < 3; ++m) {
      const int calls = 200;
      const auto t0 = std::chrono::steady_clock::now();
      for (int c = 0; c < calls; ++c) jobs[m].run();
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / calls;
      best[m] = std::min(best[m], s);
    }
  return best;
}

ModeQuality measure_mode(const Rig& rig, const BodyLevel& level, SkinningMode mode, std::span<const glm::vec3> centres,
                         const SkinReportOptions& o) {
  ModeQuality q;
  const Skeleton& s = rig.skeleton;
  q.inverted_triangles_walk = measure_walk_skin(rig, level, o.seconds, o.fps, mode, centres).inverted_triangles;
  const int elbow = s.find_joint("l_elbow"), wrist = s.find_joint("l_wrist");
  const int knee = s.find_joint("l_knee"), ankle = s.find_joint("l_ankle");
  if (elbow >= 0) {
    q.elbow_volume_change_pct =
        flexion_volume_change_pct(level.mesh, level.binding, s, elbow, 2.0944f, 0.08f, mode, centres);
    if (wrist >= 0) {
      q.bulge_mm_max = 1000.0 * flexion_bulge_m(level.mesh, level.binding, s, elbow, wrist, 2.0944f, 0.08f, mode, centres);
      const TwistSection t90 = twist_section(level.mesh, level.binding, s, elbow, wrist, 1.5708f, mode, centres);
      const TwistSection t180 = twist_section(level.mesh, level.binding, s, elbow, wrist, 3.14159f, mode, centres);
      q.twist90_area_ratio = t90.area_ratio;
      q.twist180_area_ratio = t180.area_ratio;
      q.twist_section_axial_m = t180.axial_m;
    }
  }
  if (knee >= 0) {
    q.knee_volume_change_pct =
        flexion_volume_change_pct(level.mesh, level.binding, s, knee, 2.0944f, 0.11f, mode, centres);
    if (ankle >= 0)
      q.bulge_mm_max = std::max(
          q.bulge_mm_max, 1000.0 * flexion_bulge_m(level.mesh, level.binding, s, knee, ankle, 2.0944f, 0.11f, mode, centres));
  }
  return q;
}

// The `modes` object: linear blending, dual quaternions and centres of rotation side by side on level 0.
// Its targets_met is its own (dqs and cor: volume within 5 %, twist 180 >= 0.9, no inversion over the walk, cost
// <= 1.3x linear blending); the report's top-level targets_met keeps meaning the level table's.
nlohmann::json modes_report(const Rig& rig, const BodyLevel& level, const SkinReportOptions& o) {
  bool targets = true;
  const CorCentres cor = compute_cor_centres(level.mesh, level.binding);  // uncached: its time is reported
  const std::array<double, 3> seconds = kernel_seconds(rig, o.body);
  nlohmann::json modes;
  std::printf("\n%-5s %10s %9s %9s %9s %10s %9s %13s %9s\n", "mode", "elbow vol%", "knee vol%", "twist 90",
              "twist 180", "bulge mm", "inverted", "M vertices/s", "cost/lbs");
  for (std::size_t m = 0; m < 3; ++m) {
    const SkinningMode mode = kSkinningModes[m];
    ModeQuality q = measure_mode(rig, level, mode, cor.centres, o);
    q.vertices_per_second = seconds[m] > 0.0 ? double(level.mesh.vertex_count()) / seconds[m] : 0.0;
    const double cost = seconds[0] > 0.0 ? seconds[m] / seconds[0] : 0.0;
    const bool ok = mode == SkinningMode::Linear ||
                    (std::abs(q.elbow_volume_change_pct) <= 5.0 && std::abs(q.knee_volume_change_pct) <= 5.0 &&
                     q.twist180_area_ratio >= 0.9 && q.inverted_triangles_walk == 0 && cost <= 1.3);
    targets = targets && ok;
    modes[skinning_mode_name(mode)] = {{"elbow_volume_change_pct", q.elbow_volume_change_pct},
                                       {"knee_volume_change_pct", q.knee_volume_change_pct},
                                       {"twist90_area_ratio", q.twist90_area_ratio},
                                       {"twist180_area_ratio", q.twist180_area_ratio},
                                       {"twist_section_axial_m", q.twist_section_axial_m},
                                       {"bulge_mm_max", q.bulge_mm_max},
                                       {"inverted_triangles_walk", q.inverted_triangles_walk},
                                       {"vertices_per_second", q.vertices_per_second},
                                       {"cost_vs_lbs", cost},
                                       {"targets_met", ok}};
    std::printf("%-5s %10.1f %9.1f %9.2f %9.2f %10.1f %9zu %13.0f %9.2f%s\n", skinning_mode_name(mode),
                q.elbow_volume_change_pct, q.knee_volume_change_pct, q.twist90_area_ratio, q.twist180_area_ratio,
                q.bulge_mm_max, q.inverted_triangles_walk, q.vertices_per_second / 1e6, cost, ok ? "" : "  MISSED");
  }
  modes["level"] = 0;
  modes["targets_met"] = targets;
  modes["kernel_isa"] = skin_kernel_isa_name(skin_kernel_isa());
  modes["cor_precompute_seconds"] = cor.seconds;
  modes["cor_vertices_solved"] = cor.solved;
  modes["cor_vertices_fallback"] = cor.fallback;
  std::printf("centres of rotation: %zu vertices, %zu kept at rest (no similar triangle), %.2f s to precompute; "
              "kernel %s, one core\n",
              cor.solved, cor.fallback, cor.seconds, skin_kernel_isa_name(skin_kernel_isa()));
  return modes;
}

// The modes figure: one column per mode (lbs, dqs, cor); top row the left elbow flexed 120 deg, bottom row the
// left forearm turned 180 deg about its own axis at the elbow; the arm raised 75 deg forward so both face the
// camera. Level 0, no muscle layer (its bulge would mix into the comparison).
void write_modes_figure(const std::filesystem::path& dir) {
  constexpr int kPanel = 400;
  constexpr float kDeg = 3.14159265f / 180.0f;
  auto context = create_headless_gl_context();
  CrowdRenderer renderer(kPanel, kPanel);
  renderer.options().draw_skeleton = false;
  renderer.options().draw_ground = false;
  std::vector<std::uint8_t> image(std::size_t(3) * kPanel * 2 * kPanel * 4), pixels;
  for (std::size_t m = 0; m < 3; ++m) {
    SceneOptions so;
    so.walkers = 1;
    so.rest = true;
    so.motion = "clip";
    so.muscles = "none";
    so.level = DetailLevel::mesh(0);
    so.skinning = kSkinningModes[m];
    std::unique_ptr<Crowd> scene = build_scene(so);
    const Skeleton& s = scene->rig().skeleton;
    const int shoulder = s.find_joint("l_shoulder"), elbow = s.find_joint("l_elbow"), wrist = s.find_joint("l_wrist");
    if (shoulder < 0 || elbow < 0 || wrist < 0) throw std::runtime_error("report skin: the default rig has no left arm");
    const WalkerLanes l = scene->lanes();
    const float placement[5] = {0.0f, 0.0f, 0.0f, 0.0f, 1.0f};
    for (int c = 0; c < 5; ++c) l.at(l.placement, c)[0] = placement[c];
    const glm::vec3 axis = glm::normalize(s.centers[static_cast<std::size_t>(wrist)] - s.centers[static_cast<std::size_t>(elbow)]);
    for (int row = 0; row < 2; ++row) {
      for (std::uint32_t j = 0; j < l.joints; ++j)
        for (int c = 0; c < 4; ++c) l.at(l.local_rotation, j * 4 + c)[0] = c == 3 ? 1.0f : 0.0f;
      auto set = [&](int joint, const glm::quat& q) {
        const float v[4] = {q.x, q.y, q.z, q.w};
        for (int c = 0; c < 4; ++c) l.at(l.local_rotation, std::size_t(joint) * 4 + c)[0] = v[c];
      };
      set(shoulder, glm::angleAxis(-75.0f * kDeg, glm::vec3(1, 0, 0)));
      set(elbow, row == 0 ? glm::angleAxis(-120.0f * kDeg, glm::vec3(1, 0, 0)) : glm::angleAxis(180.0f * kDeg, axis));
      run_or_throw(make_fk_job(s, scene->table(initial_slot(*scene))), "fk");
      SkinnedCrowd out;
      run_or_throw(make_skin_job(current_layout(*scene), scene->table(initial_slot(*scene)), out, nullptr,
                                 scene->skin.mode),
                   "skin");
      OrbitCamera camera;
      camera.yaw = 1.75f;  // from the walker's left, a little behind, looking down on the raised arm
      camera.pitch = 0.5f;
      // Top: the bent arm, shoulder to fist; bottom: the straight arm out to the hand.
      if (row == 0)
        camera.frame_box_tight(glm::vec3(0.12f, 1.30f, -0.10f), glm::vec3(0.30f, 1.70f, 0.35f), 1.0f, 1.05f);
      else
        camera.frame_box_tight(glm::vec3(0.10f, 1.15f, -0.10f), glm::vec3(0.30f, 1.65f, 0.75f), 1.0f, 1.05f);
      BodyDrawInput bodies;
      bodies.triangles = current_layout(*scene).triangles;
      bodies.px = out.px.data(), bodies.py = out.py.data(), bodies.pz = out.pz.data();
      bodies.nx = out.nx.data(), bodies.ny = out.ny.data(), bodies.nz = out.nz.data();
      bodies.stride = out.stride;
      bodies.vertex_count = out.vertex_count;
      bodies.walker_count = 1;
      std::vector<glm::vec3> joints;
      gather_joint_positions(scene->lanes(), joints);
      SkeletonDrawInput input{&s, joints, 1};
      renderer.render(input, camera.view(), camera.projection(1.0f), &bodies);
      renderer.read_rgba(pixels);
      for (int y = 0; y < kPanel; ++y)
        std::copy_n(pixels.begin() + std::ptrdiff_t(y) * kPanel * 4, kPanel * 4,
                    image.begin() + ((std::ptrdiff_t(row) * kPanel + y) * 3 * kPanel + std::ptrdiff_t(m) * kPanel) * 4);
    }
  }
  std::filesystem::create_directories(dir);
  write_image(dir / "skin_modes.png", 3 * kPanel, 2 * kPanel, 4, image);
}

// The body's proportions against the anthropometry notes' references (../shared/notes/anthropometry.md §5 and
// Winter's segment fractions of stature), scaled to the body's own stature: stature (sole to crown), shoulder
// width (the widest extent of the trunk and upper arms at the shoulder joints' height, deltoids included, against
// ANSUR's bideltoid breadth, 0.510 of 1.756 m), hip width (the widest extent at the hip joints' height against ANSUR's hip breadth, 0.346 of
// 1.756 m), and the limb segments joint to joint against Winter / Drillis & Contini (upper arm 0.186 H, forearm
// 0.146 H, thigh 0.245 H, shank 0.246 H).
nlohmann::json anthropometry_json(const Mesh& mesh, const Skeleton& skeleton) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (const glm::vec3& p : mesh.positions) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  const double stature = hi - lo;
  auto joint = [&](const char* name) {
    const int j = skeleton.find_joint(name);
    if (j < 0) throw std::runtime_error(std::string("report skin: the default skeleton has no ") + name);
    return glm::dvec3(skeleton.centers[static_cast<std::size_t>(j)]);
  };
  // Widest x extent of the body within 1.5 cm of height y (the hands excluded: at hip height they hang beside it).
  auto width_at = [&](double y) {
    double x0 = 1e9, x1 = -1e9;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      if (std::abs(mesh.positions[v].y - y) > 0.015) continue;
      const std::string& part = mesh.part.size() == mesh.vertex_count() ? mesh.part_names[mesh.part[v]] : std::string();
      if (part.find("Hand") != std::string::npos || part.find("ForeArm") != std::string::npos ||
          part.find("Thumb") != std::string::npos || part.find("Index") != std::string::npos ||
          part.find("Mid") != std::string::npos || part.find("Ring") != std::string::npos ||
          part.find("Pinky") != std::string::npos)
        continue;
      x0 = std::min(x0, static_cast<double>(mesh.positions[v].x));
      x1 = std::max(x1, static_cast<double>(mesh.positions[v].x));
    }
    return x1 > x0 ? x1 - x0 : 0.0;
  };
  const double shoulder_y = 0.5 * (joint("l_shoulder").y + joint("r_shoulder").y);
  const double hip_y = 0.5 * (joint("l_hip").y + joint("r_hip").y);
  struct Row {
    const char* key;
    double value, reference;
    const char* source;
  };
  const Row rows[] = {
      {"stature_m", stature, 1.75, "the notes' default adult male"},
      {"shoulder_width_m", width_at(shoulder_y), 0.510 / 1.756 * stature, "ANSUR II male bideltoid breadth 0.510 of 1.756 m"},
      {"hip_width_m", width_at(hip_y), 0.346 / 1.756 * stature, "ANSUR II male hip breadth 0.346 of 1.756 m"},
      {"upper_arm_m", glm::length(joint("l_shoulder") - joint("l_elbow")), 0.186 * stature, "Winter, 0.186 H"},
      {"forearm_m", glm::length(joint("l_elbow") - joint("l_wrist")), 0.146 * stature, "Winter, 0.146 H"},
      {"thigh_m", glm::length(joint("l_hip") - joint("l_knee")), 0.245 * stature, "Winter, 0.245 H"},
      {"shank_m", glm::length(joint("l_knee") - joint("l_ankle")), 0.246 * stature, "Winter, 0.246 H"},
  };
  nlohmann::json out = nlohmann::json::object();
  for (const Row& r : rows)
    out[r.key] = {{"value", r.value}, {"reference", r.reference}, {"ratio", r.value / r.reference}, {"reference_source", r.source}};
  return out;
}

int run_skin_report(const SkinReportOptions& o) {
  if (!check_outputs("report skin", {{"--json", o.json}, {"--images", o.images, true}})) return kExitFailure;
  try {
    const Rig rig = to_rig(load_default_humanoid());
    const BodyLevels& levels = shipped_body_levels(o.body);
    const int paper_vertices[3] = {17953, 8923, 5133};
    nlohmann::json out;
    nlohmann::json level_reports = nlohmann::json::array();
    bool targets = true;
    std::printf("%-5s %8s %9s %5s %9s %9s %9s %9s %11s %9s %9s\n", "level", "vertices", "triangles", "parts",
                "bound 1", "bound 2", "inverted", "seam gap", "elbow vol%", "knee vol%", "NaN");
    for (int l = 0; l < 3; ++l) {
      const Mesh& mesh = levels.levels[static_cast<std::size_t>(l)];
      BodyLevel level{mesh, bind_three_step(mesh, rig.skeleton, shipped_binding_tables(o.body))};
      const BindingStats stats = binding_stats(level.binding);
      std::set<std::uint16_t> parts(mesh.part.begin(), mesh.part.end());
      const Quality q = measure(rig, level, o);
      const double count_error = 100.0 * std::abs(double(mesh.vertex_count()) - paper_vertices[l]) / paper_vertices[l];
      const bool ok = parts.size() == 53 && count_error < 2.0 && q.seam_gap_max_m == 0.0 &&
                      q.inverted_triangles == 0 && q.nan_count == 0;
      targets = targets && ok;
      nlohmann::json j = {{"level", l},
                          {"vertices", mesh.vertex_count()},
                          {"triangles", mesh.triangle_count()},
                          {"parts", parts.size()},
                          {"vertex_count_error_pct", count_error},
                          {"bound_one_joint", stats.one_joint},
                          {"bound_two_joints", stats.two_joints},
                          {"bound_more_joints", stats.more_joints},
                          {"paper_vertices", paper_vertices[l]},
                          {"targets_met", ok}};
      j.update(quality_json(q));
      std::printf("%-5d %8zu %9zu %5zu %9zu %9zu %9zu %9.2g %11.1f %9.1f %9zu  three-step%s\n", l, mesh.vertex_count(),
                  mesh.triangle_count(), parts.size(), stats.one_joint, stats.two_joints, q.inverted_triangles,
                  q.seam_gap_max_m, q.elbow_volume_change_pct, q.knee_volume_change_pct, q.nan_count,
                  ok ? "" : "  MISSED");
      if (o.automatic) {
        BodyLevel automatic{mesh, bind_automatic(mesh, rig.skeleton)};
        const BindingStats a_stats = binding_stats(automatic.binding);
        const Quality a = measure(rig, automatic, o);
        nlohmann::json aj = {{"bound_one_joint", a_stats.one_joint},
                             {"bound_two_joints", a_stats.two_joints},
                             {"bound_more_joints", a_stats.more_joints}};
        aj.update(quality_json(a));
        j["automatic"] = aj;
        std::printf("%-5s %8s %9s %5s %9zu %9zu %9zu %9.2g %11.1f %9.1f %9zu  automatic (bone heat)\n", "", "", "",
                    "", a_stats.one_joint, a_stats.two_joints, a.inverted_triangles, a.seam_gap_max_m,
                    a.elbow_volume_change_pct, a.knee_volume_change_pct, a.nan_count);
      }
      level_reports.push_back(j);
    }
    out["levels"] = level_reports;
    {
      const Mesh& mesh0 = levels.levels[0];
      const BodyLevel level0{mesh0, bind_three_step(mesh0, rig.skeleton, shipped_binding_tables(o.body))};
      out["modes"] = modes_report(rig, level0, o);
    }
    out["cage"] = {{"vertices", levels.cage.vertex_count()}, {"triangles", levels.cage.triangle_count()}};
    out["body_source"] = shipped_body_name(o.body);
    out["anthropometry"] = anthropometry_json(levels.levels[0], rig.skeleton);
    std::printf("anthropometry (level 0 against the notes' references):");
    for (const auto& [key, row] : out["anthropometry"].items())
      std::printf(" %s %.3f (%.2fx)", key.c_str(), row["value"].get<double>(), row["ratio"].get<double>());
    std::printf("\n");
    out["walk_seconds"] = o.seconds;
    out["flexion_deg"] = 120;
    out["targets_met"] = targets;
    if (!o.images.empty()) write_modes_figure(o.images);
    if (!o.json.empty()) write_json_file(o.json, out);
    std::printf("cage: %zu vertices, %zu triangles; targets %s\n", levels.cage.vertex_count(),
                levels.cage.triangle_count(), targets ? "met" : "MISSED");
  } catch (const std::exception& e) {
    print_error("report skin", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_skin_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<SkinReportOptions>();
  auto* skin = report.add_subcommand("skin", "Measure the default body's levels, binding and skinning quality");
  skin->add_option("--json", o->json, "Write the report here");
  skin->add_option("--images", o->images,
                   "Write skin_modes.png here: the elbow at 120 deg and the forearm twisted 180 deg per skinning mode");
  skin->add_option("--seconds", o->seconds, "Seconds of walking measured")->capture_default_str()->check(positive_up_to(3600));
  skin->add_flag("!--no-automatic", o->automatic, "Skip the automatic (bone heat) binding comparison");
  skin->add_option_function<std::string>(
          "--body",
          [o](const std::string& value) {
            if (const auto body = parse_shipped_body(value)) o->body = *body;
            else throw CLI::ValidationError("--body", "must be makehuman or procedural, got '" + value + "'");
          },
          "Which shipped body to measure: makehuman or procedural")
      ->default_str(shipped_body_name(o->body));
  skin->callback([o, &exit_code] { exit_code = run_skin_report(*o); });
}

}  // namespace strata::cli
