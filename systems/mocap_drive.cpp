#include "systems/mocap_drive.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <span>
#include <stdexcept>

#include <glm/gtc/quaternion.hpp>

#include "components/walker.h"
#include "systems/animation_sample.h"
#include "systems/locomotion.h"

namespace strata {

MocapRig make_mocap_rig(const Skeleton& skeleton, const AnimationClip& clip, const FootContacts& contacts) {
  MocapRig rig;
  rig.skeleton = &skeleton;
  rig.clip = &clip;
  rig.contacts = &contacts;
  rig.limbs = make_limbs(skeleton);
  for (int leg = 0; leg < 2; ++leg) {
    const LimbChain& l = rig.limbs[leg];
    // The longest hip-ankle distance the knee's hinge range allows: the H-Anim rest leg is slightly bent and the
    // knee may straighten only 0.05 rad past rest, so this is shorter than thigh + shin. Sampled rather than solved:
    // it runs once per rig.
    const glm::vec3 thigh = skeleton.centers[l.middle] - skeleton.centers[l.upper];
    const glm::vec3 shin = skeleton.centers[l.lower] - skeleton.centers[l.middle];
    const JointLimits& limits = skeleton.limits[l.middle];
    const glm::vec3 axis = glm::normalize(l.flexion_axis);
    const int axis_index = std::abs(axis.x) > 0.5f ? 0 : (std::abs(axis.y) > 0.5f ? 1 : 2);
    const float lo = limits.present ? limits.lower[axis_index] : -3.14159265f;
    const float hi = limits.present ? limits.upper[axis_index] : 3.14159265f;
    float longest = 0.0f;
    for (int k = 0; k <= 512; ++k) {
      const float theta = lo + (hi - lo) * static_cast<float>(k) / 512.0f;
      longest = std::max(longest, glm::length(thigh + glm::angleAxis(theta, axis) * shin));
    }
    rig.reach[leg] = longest * kMocapReachFraction;
  }
  // The contacts as the walk generator places them (its ball falls back past a missing midtarsal).
  const LocomotionRig walk = make_locomotion_rig(skeleton);
  for (int leg = 0; leg < 2; ++leg) {
    rig.heel_offset[leg] = walk.heel_rest[leg] - walk.ankle_rest[leg];
    rig.ball_offset[leg] = walk.ball_rest[leg] - walk.ankle_rest[leg];
  }
  for (const TranslationTrack& t : clip.translations) {
    if (t.joint != 0 || t.values.size() < 2) continue;
    rig.loop_displacement = t.values.back() - t.values.front();
    rig.loop_displacement.y = 0.0f;
  }
  return rig;
}

namespace {

// One leg's lock, in the walker's foot_lock columns.
struct LockRef {
  const ColumnView<float>& foot_lock;
  std::size_t walker;
  int leg;
  float& at(std::uint32_t c) const { return foot_lock.at(static_cast<std::uint32_t>(leg) * kLockFloats + c, walker); }
  bool locked() const { return at(kLockOn) > 0.5f; }
  void set_locked(bool on) const { at(kLockOn) = on ? 1.0f : 0.0f; }
  int interval() const { return static_cast<int>(at(kLockInterval)); }
  void set_interval(int i) const { at(kLockInterval) = static_cast<float>(i); }
  float point() const { return at(kLockPoint); }
  void set_point(float which) const { at(kLockPoint) = which; }
  glm::vec3 world() const { return {at(kLockX), at(kLockY), at(kLockZ)}; }
  void set_world(const glm::vec3& p) const {
    at(kLockX) = p.x;
    at(kLockY) = p.y;
    at(kLockZ) = p.z;
  }
};

}  // namespace

bool MocapDriveJob::validate() const {
  if (!rig || !rig->skeleton || !rig->clip || !rig->contacts || !std::isfinite(dt)) return false;
  const std::size_t joints = rig->skeleton->joint_count();
  if (joints == 0 || joints > kMaxJointsPerRig || rig->limbs.size() < 2) return false;
  for (int leg = 0; leg < 2; ++leg)
    if (rig->limbs[leg].upper < 0 || std::size_t(rig->limbs[leg].upper) >= joints || rig->limbs[leg].lower < 0 ||
        std::size_t(rig->limbs[leg].lower) >= joints)
      return false;
  const std::size_t n = time.count;
  if (!rate.fits(n, 1) || !time.fits(n, 1) || !placement.fits(n, 5) || !foot_lock.fits(n, 2 * kLockFloats) ||
      !local_rotation.fits(n, static_cast<std::uint32_t>(joints * 4)) || !root_translation.fits(n, 3) ||
      !ik_goal.fits(n, kIkLimbs * kIkGoalFloats) || !ik_mode.fits(n, kIkLimbs))
    return false;
  const ColumnView<const float> floats[] = {rate, time, placement, foot_lock, local_rotation, root_translation,
                                            ik_goal};
  for (std::size_t a = 0; a < std::size(floats); ++a) {
    if (floats[a].overlaps(ik_mode)) return false;
    for (std::size_t b = a + 1; b < std::size(floats); ++b)
      if (floats[a].overlaps(floats[b])) return false;
  }
  return true;
}

bool MocapDriveJob::run() const {
  if (!validate()) return false;
  const MocapRig& rig = *this->rig;
  const float dt = this->dt;
  const Skeleton& skeleton = *rig.skeleton;
  const std::size_t joints = skeleton.joint_count();
  const float duration = rig.clip->duration;
  const std::int32_t ankles[2] = {rig.limbs[kLeftLeg].lower, rig.limbs[kRightLeg].lower};
  // On the stack (22 KiB at the joint cap) rather than three vectors per frame: run() allocates nothing.
  glm::quat local_storage[kMaxJointsPerRig], global_storage[kMaxJointsPerRig];
  glm::vec3 pos_storage[kMaxJointsPerRig];
  const std::span<glm::quat> local(local_storage, joints), global(global_storage, joints);
  const std::span<glm::vec3> pos(pos_storage, joints);
  const std::size_t count = this->time.count;
  for (std::size_t i = 0; i < count; ++i) {
    float& time = this->time.at(0, i);
    const float rate = this->rate.at(0, i);
    float* place[4] = {&placement.at(0, i), &placement.at(1, i), &placement.at(2, i), &placement.at(3, i)};
    const float scale = placement.at(4, i);
    const glm::quat heading = glm::angleAxis(*place[3], glm::vec3(0, 1, 0));
    time += dt * rate;
    if (!std::isfinite(time)) time = 0.0f;
    int wraps = 0;
    if (duration > 0.0f) {
      // Whole loops at once, so a large dt or rate never spins here.
      const float loops = std::floor(time / duration);
      if (loops != 0.0f) {
        time -= loops * duration;
        if (time >= duration) time = 0.0f;  // rounding just below a multiple of duration
        wraps = static_cast<int>(loops);
        const glm::vec3 advance = heading * (rig.loop_displacement * (scale * loops));
        for (int c = 0; c < 3; ++c) *place[c] += advance[c];
      }
    }

    glm::vec3 root(0.0f);
    sample_clip(*rig.clip, time, local, root);
    for (std::size_t j = 0; j < joints; ++j)
      for (int c = 0; c < 4; ++c) local_rotation.at(static_cast<std::uint32_t>(j * 4 + c), i) = local[j][c];
    for (int c = 0; c < 3; ++c) root_translation.at(static_cast<std::uint32_t>(c), i) = root[c];
    pose_globals(skeleton, local, root, global, pos);

    const glm::vec3 origin(*place[0], *place[1], *place[2]);
    for (int leg = 0; leg < 2; ++leg) {
      LockRef s{foot_lock, i, leg};
      auto set = [&](std::uint32_t component, float v) {
        ik_goal.at(static_cast<std::uint32_t>(leg) * kIkGoalFloats + component, i) = v;
      };
      auto set_mode = [&](IkMode mode) { ik_mode.at(static_cast<std::uint32_t>(leg), i) = static_cast<std::int32_t>(mode); };
      const int interval = rig.contacts->stance_at(leg, time);
      if (wraps != 0) s.set_interval(-1);  // a new loop: never carry a lock over (see the header)
      if (interval < 0) {
        s.set_locked(false);
        s.set_interval(-1);
        set_mode(IkMode::Off);
        continue;
      }
      const std::int32_t ankle = ankles[leg];
      const glm::quat q = global[ankle];
      const glm::vec3 heel = pos[ankle] + q * rig.heel_offset[leg];
      const glm::vec3 ball = pos[ankle] + q * rig.ball_offset[leg];
      // World <-> this frame's humanoid space; the placement may have moved since the lock (a wrap never keeps
      // one, but a caller may move walkers).
      auto to_world = [&](const glm::vec3& p) { return origin + heading * (p * scale); };
      auto to_humanoid = [&](const glm::vec3& w) {
        return glm::inverse(heading) * (w - origin) / (scale != 0.0f ? scale : 1.0f);
      };
      if (s.interval() != interval) {
        s.set_locked(true);
        s.set_interval(interval);
        const bool on_ball = ball.y < heel.y;  // a stance that begins flat or on the toes
        s.set_point(on_ball ? kContactBall : kContactHeel);
        s.set_world(to_world(on_ball ? ball : heel));
      } else if (s.locked() && s.point() == kContactHeel && ball.y < heel.y) {
        // Rolled onto the ball: hold it where the held foot puts it now, so the ankle does not jump.
        s.set_point(kContactBall);
        s.set_world(to_world(to_humanoid(s.world()) + (ball - heel)));
      }
      const glm::vec3 contact = s.point() == kContactBall ? ball : heel;
      const glm::vec3 h = to_humanoid(s.world()) + (pos[ankle] - contact);
      // Release (for the rest of this stance) once the ankle goal is out of the leg's reach from where the clip
      // puts the hip: late in stance the body has moved on and the capture's foot lifts for push-off. IK would
      // clamp and flag it, leaving the foot off its lock anyway; releasing hands the foot back to the clip instead
      // of a stretched, clamped leg.
      if (s.locked() && glm::length(h - pos[rig.limbs[leg].upper]) > rig.reach[leg]) s.set_locked(false);
      if (!s.locked()) {
        set_mode(IkMode::Off);
        continue;
      }
      set(kGoalPx, h.x);
      set(kGoalPy, h.y);
      set(kGoalPz, h.z);
      set(kGoalQx, q.x);
      set(kGoalQy, q.y);
      set(kGoalQz, q.z);
      set(kGoalQw, q.w);
      set_mode(IkMode::PositionOrientation);
      set(kGoalSwivel, 0.0f);
      set(kGoalPoleX, 0.0f);
      set(kGoalPoleY, 0.0f);
      set(kGoalPoleZ, 0.0f);
    }
    for (std::uint32_t arm : {kLeftArm, kRightArm}) ik_mode.at(arm, i) = static_cast<std::int32_t>(IkMode::Off);
  }
  return true;
}

MocapDriveJob make_mocap_drive_job(const MocapRig& rig, SoaTable& walkers, float dt) {
  const ColumnView<float> clock = f32_view(walkers, kWalkerClock);
  return {&rig,
          dt,
          clock.columns(1, 1),
          clock.columns(0, 1),
          f32_view(walkers, kWalkerPlacement),
          f32_view(walkers, kWalkerFootLock),
          f32_view(walkers, kWalkerLocalRotation),
          f32_view(walkers, kWalkerRootTranslation),
          f32_view(walkers, kWalkerIkGoal),
          i32_view(walkers, kWalkerIkMode)};
}

}  // namespace strata
