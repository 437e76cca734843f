// strata report retarget: how faithfully a motion capture lands on the rig, measured through the engine's own
// frame step (mocap drive, foot-lock IK, FK), not through the retargeter's arithmetic. Per mapped bone, over
// `--loops` passes of the clip: the angle between the capture's world-space bone and the walker's, after the
// rest-pose compensation, mean and max. Limb bones (aligned by direction) compare directions: the capture's bone
// direction against the walker's joint -> aim direction. Root, spine, neck and head (retargeted rest-relative)
// compare whole rotations, twist included. Then how far a locked foot moves while its lock holds.
// Targets (issue 17): every bone <= 5 deg mean and <= 10 deg max.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "io/bvh.h"
#include "motion/retarget.h"
#include "profiling/profiler.h"
#include "scene/crowd.h"
#include "scene/scene_setup.h"
#include "scene/step.h"
#include "systems/ik.h"
#include "systems/mocap_drive.h"

namespace strata::cli {
namespace {

struct RetargetReportOptions {
  SceneOptions scene;
  std::string json;
  float loops = 2.0f;
};

constexpr double kMeanTargetDeg = 5.0, kMaxTargetDeg = 10.0;

double angle_between_deg(const glm::dvec3& a, const glm::dvec3& b) {
  return glm::degrees(std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)));
}

double rotation_angle_deg(const glm::dquat& a, const glm::dquat& b) {
  const glm::dquat d = glm::conjugate(a) * b;
  return glm::degrees(2.0 * std::atan2(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), std::abs(d.w)));
}

// Joint j's rotation from FK's world matrix F(j) (humanoid space; columns at 0, 3, 6), scale removed.
glm::dquat walker_rotation(const WalkerLanes& lanes, std::size_t w, std::int32_t j) {
  glm::dmat3 m;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      m[c][r] = lanes.at(lanes.world, static_cast<std::size_t>(j) * 12 + static_cast<std::size_t>(3 * c + r))[w];
  for (int c = 0; c < 3; ++c) m[c] = glm::normalize(m[c]);
  return glm::normalize(glm::quat_cast(m));
}

int run_retarget_report(const RetargetReportOptions& o) {
  if (!check_outputs("report retarget", {{"--json", o.json}})) return kExitFailure;
  try {
    if (o.scene.motion.empty() || !std::filesystem::path(o.scene.motion).has_extension())
      throw std::invalid_argument("--motion FILE.bvh is required");
    SceneOptions scene_options = o.scene;
    scene_options.walkers = 1;
    scene_options.level = DetailLevel::none();
    check_scene_inputs(scene_options);
    std::unique_ptr<Crowd> scene = build_scene(scene_options);
    const Skeleton& skeleton = scene->rig().skeleton;
    // The scene's own retarget (its resolved map and axes); the file again for the capture's frames, which the
    // scene does not keep.
    if (!scene->motion.mocap) throw std::invalid_argument("--motion " + scene_options.motion + " set up no capture");
    const RetargetResult& capture = *scene->motion.mocap;
    const BvhMotion motion = load_bvh_file(scene_options.motion);
    const glm::dquat turn = glm::dquat(glm::quat_cast(capture.axes));
    const double dt = motion.frame_time;
    const double duration = capture.clip.duration;
    const auto steps = static_cast<std::size_t>(std::ceil(static_cast<double>(o.loops) * duration / dt));

    struct BoneStats {
      double sum = 0.0, max = 0.0;
    };
    std::vector<BoneStats> stats(capture.bones.size());
    std::vector<glm::quat> bvh_rot[2] = {std::vector<glm::quat>(motion.joint_count()),
                                         std::vector<glm::quat>(motion.joint_count())};
    std::vector<glm::vec3> bvh_pos(motion.joint_count());
    Profiler profiler(120, false);
    std::size_t samples = 0;
    // Foot locks: a locked foot's contact point (heel, then ball; systems/mocap_drive.h) in the world, against
    // where it was when that contact began.
    const std::int32_t ankles[2] = {scene->limbs().size() > kRightLeg ? scene->limbs()[kLeftLeg].lower : -1,
                                    scene->limbs().size() > kRightLeg ? scene->limbs()[kRightLeg].lower : -1};
    const MocapRig& mocap_rig = *scene->motion.mocap_rig;
    struct Lock {
      int interval = -1;
      float point = -1.0f;
      glm::dvec3 start{0.0};
    } locks[2];
    double slide_max = 0.0;
    std::size_t locked_frames = 0;
    for (std::size_t s = 0; s < steps; ++s) {
      step(*scene, static_cast<float>(dt), profiler);
      const WalkerLanes lanes = scene->lanes();
      // The capture at the walker's clip time: the two frames around it, blended.
      const double t = std::clamp(static_cast<double>(lanes.clock[0]), 0.0, duration);
      const double key = t / dt;
      const std::size_t k0 = std::min(static_cast<std::size_t>(key), motion.frame_count - 1 - capture.skipped_frames);
      const std::size_t k1 = std::min(k0 + 1, motion.frame_count - 1 - capture.skipped_frames);
      const double f = std::clamp(key - static_cast<double>(k0), 0.0, 1.0);
      motion.pose(k0 + capture.skipped_frames, bvh_rot[0], bvh_pos);
      motion.pose(k1 + capture.skipped_frames, bvh_rot[1], bvh_pos);
      for (std::size_t b = 0; b < capture.bones.size(); ++b) {
        const RetargetBone& bone = capture.bones[b];
        const auto src = static_cast<std::size_t>(bone.bvh);
        const glm::dquat g = glm::slerp(glm::dquat(bvh_rot[0][src]), glm::dquat(bvh_rot[1][src]), f);
        // The capture's rotation in H-Anim axes, compensated for the rest pose: what the H-Anim joint should be.
        const glm::dquat wanted = turn * g * glm::conjugate(turn) * glm::dquat(bone.align);
        const glm::dquat got = walker_rotation(lanes, 0, bone.hanim);
        const double a = bone.aimed ? angle_between_deg(wanted * glm::dvec3(bone.hanim_dir), got * glm::dvec3(bone.hanim_dir))
                                    : rotation_angle_deg(wanted, got);
        stats[b].sum += a;
        stats[b].max = std::max(stats[b].max, a);
      }
      ++samples;
      const Placement place = placement_of(lanes, 0);
      for (int leg = 0; leg < 2; ++leg) {
        if (ankles[leg] < 0) continue;
        const float* lock = lanes.foot_lock + static_cast<std::size_t>(leg) * kLockFloats * lanes.stride;
        const bool on = lock[kLockOn * lanes.stride] > 0.5f;
        const int interval = static_cast<int>(lock[kLockInterval * lanes.stride]);
        const float point = lock[kLockPoint * lanes.stride];
        // The ankle's world matrix from FK (3x4 column-major, components/walker.h) carries the contact point.
        float m[kAffineFloats];
        for (std::uint32_t c = 0; c < kAffineFloats; ++c)
          m[c] = lanes.at(lanes.world, static_cast<std::size_t>(ankles[leg]) * kAffineFloats + c)[0];
        const glm::vec3 offset = point == kContactBall ? mocap_rig.ball_offset[leg] : mocap_rig.heel_offset[leg];
        const glm::vec3 contact = glm::vec3(m[9], m[10], m[11]) + offset.x * glm::vec3(m[0], m[1], m[2]) +
                                  offset.y * glm::vec3(m[3], m[4], m[5]) + offset.z * glm::vec3(m[6], m[7], m[8]);
        const glm::dvec3 world(place.point(contact));
        if (!on) {
          locks[leg].interval = -1;
        } else if (locks[leg].interval != interval || locks[leg].point != point) {
          locks[leg] = {interval, point, world};
        } else {
          slide_max = std::max(slide_max, glm::length(world - locks[leg].start));
          ++locked_frames;
        }
      }
    }

    nlohmann::json bones = nlohmann::json::object();
    double worst_mean = 0.0, worst_max = 0.0;
    std::string worst_bone;
    std::printf("report retarget: %s (%s) onto %s, %zu frames through the engine\n", motion.source.c_str(),
                capture.family.c_str(), skeleton.name.c_str(), samples);
    std::printf("  %-20s %-16s %9s %9s  %s\n", "H-Anim joint", "BVH joint", "mean deg", "max deg", "compared");
    for (std::size_t b = 0; b < capture.bones.size(); ++b) {
      const RetargetBone& bone = capture.bones[b];
      const double mean = samples ? stats[b].sum / static_cast<double>(samples) : 0.0;
      const std::string& name = skeleton.joint_names[static_cast<std::size_t>(bone.hanim)];
      const std::string& source = motion.joints[static_cast<std::size_t>(bone.bvh)].name;
      bones[name] = {{"bvh", source},
                     {"compared", bone.aimed ? "direction" : "rotation"},
                     {"mean_deg", mean},
                     {"max_deg", stats[b].max}};
      std::printf("  %-20s %-16s %9.2f %9.2f  %s\n", name.c_str(), source.c_str(), mean, stats[b].max,
                  bone.aimed ? "direction" : "rotation");
      if (mean > worst_mean) worst_mean = mean;
      if (stats[b].max > worst_max) {
        worst_max = stats[b].max;
        worst_bone = name;
      }
    }
    const bool pass = worst_mean <= kMeanTargetDeg && worst_max <= kMaxTargetDeg;
    std::printf("  worst mean %.2f deg (target <= %.0f), worst max %.2f deg at %s (target <= %.0f): %s\n", worst_mean,
                kMeanTargetDeg, worst_max, worst_bone.c_str(), kMaxTargetDeg, pass ? "met" : "NOT met");
    std::printf("  foot-lock slide max %.3f mm over %zu locked leg-frames\n", slide_max * 1000.0, locked_frames);
    std::string missing;
    for (const std::string& m : capture.missing_on_rig) missing += (missing.empty() ? "" : " ") + m;
    if (!missing.empty()) std::printf("  not on this rig (left out): %s\n", missing.c_str());
    if (!o.json.empty()) {
      const nlohmann::json report = {
          {"motion", scene_options.motion},
          {"family", capture.family},
          {"skeleton", skeleton.name},
          {"frames", samples},
          {"loops", o.loops},
          {"bones", bones},
          {"worst_mean_deg", worst_mean},
          {"worst_max_deg", worst_max},
          {"worst_bone", worst_bone},
          {"foot_lock_slide_mm_max", slide_max * 1000.0},
          {"locked_leg_frames", locked_frames},
          {"missing_on_rig", capture.missing_on_rig},
          {"targets", {{"mean_deg", kMeanTargetDeg}, {"max_deg", kMaxTargetDeg}}},
          {"targets_met", pass}};
      write_json_file(o.json, report);
    }
    return kExitOk;
  } catch (const std::exception& e) {
    print_error("report retarget", error_text(e));
    return kExitFailure;
  }
}

}  // namespace

void add_retarget_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<RetargetReportOptions>();
  auto* cmd = report.add_subcommand(
      "retarget", "Play a motion capture on the rig through the engine and measure, per mapped bone, the angle "
                  "between the capture's and the walker's world-space bones, and the foot-lock slide");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--loops", o->loops, "Passes of the clip measured")->capture_default_str()->check(positive_up_to(1000));
  cmd->add_option("--json", o->json, "Write the report here");
  cmd->callback([o, &exit_code] { exit_code = run_retarget_report(*o); });
}

}  // namespace strata::cli
