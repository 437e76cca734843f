// Retargeting the real CMU walk onto the shipped 25-joint skeleton, checked through the engine's own pipeline
// (sample_clip -> FkJob), not through the retargeter's internal FK.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>

#include <glm/gtc/quaternion.hpp>

#include "components/walker.h"
#include "io/bvh.h"
#include "io/hanim_loader.h"
#include "motion/retarget.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "systems/ik.h"
#include "systems/mocap_drive.h"

namespace strata {
namespace {

const std::filesystem::path kWalk = std::filesystem::path(STRATA_SHARED_DATA) / "cmu_mocap_bvh" / "02_02_daz.bvh";

// Every frame of the clip posed by the engine: sampled at the key times, FK'd as one walker per frame.
struct PosedClip {
  std::size_t frames = 0;
  float dt = 0.0f;
  std::unique_ptr<SoaTable> table;
  WalkerLanes lanes;

  // Skinning matrix S(j) of frame k applied to a rest point: where that point of joint j's segment is.
  glm::vec3 point(std::size_t k, std::int32_t j, const glm::vec3& rest) const {
    const float* s = lanes.skinning;
    glm::vec3 out;
    for (int r = 0; r < 3; ++r) {
      const std::size_t base = static_cast<std::size_t>(j) * kAffineFloats;
      out[r] = s[(base + 0 + r) * lanes.stride + k] * rest.x + s[(base + 3 + r) * lanes.stride + k] * rest.y +
               s[(base + 6 + r) * lanes.stride + k] * rest.z + s[(base + 9 + r) * lanes.stride + k];
    }
    return out;
  }
};

PosedClip pose_clip(const Skeleton& skeleton, const AnimationClip& clip, std::size_t frames, float dt) {
  PosedClip p;
  p.frames = frames;
  p.dt = dt;
  const auto joints = static_cast<std::uint32_t>(skeleton.joint_count());
  p.table = make_walker_table("test", joints);
  for (std::size_t k = 0; k < frames; ++k) p.table->add(Entity{static_cast<std::uint32_t>(k + 1), 1});
  p.lanes = walker_lanes(*p.table, joints);
  std::vector<glm::quat> rot(joints);
  for (std::size_t k = 0; k < frames; ++k) {
    glm::vec3 root;
    // Key times exactly; the last key is the loop's end, so sample just before it instead of wrapping to key 0.
    const float t = std::min(static_cast<float>(k) * dt, clip.duration - 1e-5f);
    sample_clip(clip, t, rot, root);
    for (std::uint32_t j = 0; j < joints; ++j)
      for (int c = 0; c < 4; ++c) p.lanes.at(p.lanes.local_rotation, j * 4 + c)[k] = rot[j][c];
    for (int c = 0; c < 3; ++c) p.lanes.at(p.lanes.root_translation, c)[k] = root[c];
  }
  EXPECT_TRUE(make_fk_job(skeleton, *p.table).run());
  return p;
}

class RetargetWalk : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists(kWalk)) return;
    motion_ = new BvhMotion(load_bvh_file(kWalk));
    skeleton_ = new Skeleton(load_default_humanoid().skeleton);
    result_ = new RetargetResult(retarget_bvh(*motion_, *skeleton_));
    frames_ = result_->clip.translations.at(0).times.size();
    posed_ = new PosedClip(pose_clip(*skeleton_, result_->clip, frames_, motion_->frame_time));
  }
  static void TearDownTestSuite() {
    delete posed_;
    delete result_;
    delete skeleton_;
    delete motion_;
  }
  void SetUp() override {
    if (!motion_) GTEST_SKIP() << "no shared data at " << kWalk;
  }
  static std::int32_t joint(const char* name) { return skeleton_->find_joint(name); }
  static glm::vec3 at(std::size_t k, const char* name) {
    const std::int32_t j = joint(name);
    return posed_->point(k, j, skeleton_->centers[j]);
  }
  // Lowest point of a foot at frame k: the ball (midtarsal centre, on the sole at rest) or the heel's underside
  // (the calcaneus site marks the back of the heel, so it is lowered to the ball's rest height).
  static float foot_low(std::size_t k, char side) {
    const std::string p(1, side);
    const std::int32_t ball = joint((p + "_midtarsal").c_str());
    const SkeletonSite& heel = skeleton_->sites[skeleton_->find_site(p + "_calcaneous_post_pt")];
    const glm::vec3 heel_sole(heel.position.x, skeleton_->centers[ball].y, heel.position.z);
    return std::min(posed_->point(k, ball, skeleton_->centers[ball]).y, posed_->point(k, heel.joint, heel_sole).y);
  }

  static inline BvhMotion* motion_ = nullptr;
  static inline Skeleton* skeleton_ = nullptr;
  static inline RetargetResult* result_ = nullptr;
  static inline PosedClip* posed_ = nullptr;
  static inline std::size_t frames_ = 0;
};

TEST_F(RetargetWalk, ClipShapeScaleAndNoNaN) {
  const RetargetResult& r = *result_;
  EXPECT_EQ(r.skipped_frames, 5);
  EXPECT_EQ(frames_, 299u - 5u);
  EXPECT_NEAR(r.clip.duration, 293 * motion_->frame_time, 1e-5f);
  // cm -> m with a slightly longer H-Anim leg: about 0.0104 m per unit.
  EXPECT_GT(r.scale, 0.009f);
  EXPECT_LT(r.scale, 0.0115f);
  for (const RotationTrack& t : r.clip.rotations) {
    ASSERT_EQ(t.values.size(), frames_);
    for (const glm::quat& q : t.values) {
      ASSERT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w));
      ASSERT_NEAR(glm::length(q), 1.0f, 1e-4f);
    }
  }
  for (const glm::vec3& v : r.clip.translations.at(0).values) ASSERT_TRUE(std::isfinite(v.x + v.y + v.z));
  // 25 joints, 19 driven; the six without a Poser counterpart are reported.
  EXPECT_EQ(r.clip.rotations.size(), 19u);
  const std::vector<std::string> unmapped = {"sacroiliac", "l_midtarsal", "r_midtarsal", "vt1",
                                             "l_acromioclavicular", "r_acromioclavicular"};
  for (const std::string& name : unmapped)
    EXPECT_NE(std::find(r.unmapped_hanim.begin(), r.unmapped_hanim.end(), name), r.unmapped_hanim.end()) << name;
}

TEST_F(RetargetWalk, WalksAboutFourMetresAlongPlusZ) {
  // data-README: the root travels ~394 units along +Z over the whole file; in H-Anim metres about 3.9 m.
  const glm::vec3 start = at(0, "HumanoidRoot");
  const glm::vec3 end = at(frames_ - 1, "HumanoidRoot");
  EXPECT_NEAR(end.z - start.z, 3.9f, 0.39f);
  EXPECT_LT(std::abs(end.x - start.x), 0.1f * (end.z - start.z)) << "straight ahead, not sideways";
  EXPECT_NEAR(result_->root_travel.z, end.z - start.z, 1e-3f);
  EXPECT_NEAR(start.x, 0.0f, 1e-4f) << "the clip starts at the origin";
  EXPECT_NEAR(start.z, 0.0f + skeleton_->centers[0].z, 1e-4f);
}

TEST_F(RetargetWalk, FeetTouchTheGroundInStance) {
  for (int leg = 0; leg < 2; ++leg) {
    const char side = leg == 0 ? 'l' : 'r';
    for (const StanceInterval& s : result_->contacts.legs[leg]) {
      for (std::size_t k = 0; k < frames_; ++k) {
        const float t = static_cast<float>(k) * posed_->dt;
        if (t < s.begin || t >= s.end) continue;
        EXPECT_LT(std::abs(foot_low(k, side)), 0.03f) << side << " foot at frame " << k;
      }
    }
  }
  // Never far through the floor either.
  for (std::size_t k = 0; k < frames_; ++k) EXPECT_GT(std::min(foot_low(k, 'l'), foot_low(k, 'r')), -0.03f) << k;
}

TEST_F(RetargetWalk, StanceIntervalsAlternateWithAWalkingDutyFactor) {
  const FootContacts& c = result_->contacts;
  struct Event {
    float begin;
    int leg;
  };
  std::vector<Event> events;
  for (int leg = 0; leg < 2; ++leg) {
    const auto& legs = c.legs[leg];
    ASSERT_GE(legs.size(), 2u) << "leg " << leg;
    // Duty factor = stance time / stride time, from whole stances (not cut by the clip's ends) and the period
    // between consecutive stance starts.
    float stance = 0.0f;
    int whole = 0;
    for (const StanceInterval& s : legs) {
      EXPECT_LT(s.begin, s.end);
      events.push_back({s.begin, leg});
      if (s.begin > 0.0f && s.end < result_->clip.duration) {
        stance += s.end - s.begin;
        ++whole;
      }
    }
    ASSERT_GT(whole, 0) << "leg " << leg;
    // Period from stance starts that are real heel strikes (a stance already under way at t = 0 starts at 0).
    std::vector<float> strikes;
    for (const StanceInterval& s : legs)
      if (s.begin > 0.0f) strikes.push_back(s.begin);
    ASSERT_GE(strikes.size(), 2u) << "leg " << leg;
    const float period = (strikes.back() - strikes.front()) / static_cast<float>(strikes.size() - 1);
    const float duty = stance / static_cast<float>(whole) / period;
    EXPECT_GT(duty, 0.5f) << "leg " << leg;
    EXPECT_LT(duty, 0.75f) << "leg " << leg;
    EXPECT_GT(period, 0.8f) << "a walking stride at ~1.6 m/s takes about a second";
    EXPECT_LT(period, 1.3f);
  }
  std::sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.begin < b.begin; });
  for (std::size_t i = 1; i < events.size(); ++i)
    EXPECT_NE(events[i].leg, events[i - 1].leg) << "stance " << i << " at " << events[i].begin << " s";
  EXPECT_EQ(c.stance_at(events[1].leg, events[1].begin), events[1].leg == events[0].leg ? 1 : 0);
  EXPECT_EQ(c.stance_at(0, -1.0f), -1);
}

TEST_F(RetargetWalk, ThighsSwingInAntiPhase) {
  // Forward component of each thigh (knee relative to hip), centred; Pearson correlation left vs right.
  std::vector<float> l(frames_), r(frames_);
  for (std::size_t k = 0; k < frames_; ++k) {
    l[k] = at(k, "l_knee").z - at(k, "l_hip").z;
    r[k] = at(k, "r_knee").z - at(k, "r_hip").z;
  }
  auto centre = [](std::vector<float>& v) {
    const float mean = std::accumulate(v.begin(), v.end(), 0.0f) / static_cast<float>(v.size());
    for (float& x : v) x -= mean;
  };
  centre(l);
  centre(r);
  const float lr = std::inner_product(l.begin(), l.end(), r.begin(), 0.0f);
  const float ll = std::inner_product(l.begin(), l.end(), l.begin(), 0.0f);
  const float rr = std::inner_product(r.begin(), r.end(), r.begin(), 0.0f);
  const float correlation = lr / std::sqrt(ll * rr);
  EXPECT_LT(correlation, -0.5f);
  EXPECT_GT(std::sqrt(ll / static_cast<float>(frames_)), 0.05f) << "the thighs really swing";
}

// Forward lean of a direction in the sagittal plane (degrees, positive forward = +Z).
float sagittal_lean_deg(const glm::vec3& d) { return glm::degrees(std::atan2(d.z, d.y)); }

TEST_F(RetargetWalk, TrunkAndNeckLeanAsTheCapturesDo) {
  // Spine, neck and head are retargeted relative to their rest: the trunk (HumanoidRoot -> vc4) and the neck
  // (vc4 -> skullbase) lean as the capture's hip -> neck and neck -> head do, each against its own rest pose. With
  // the bones aimed at each other the walker's chest leant ~27 deg further back than the capture's (H-Anim's
  // thoracic bone leans forward at rest, the Poser chest does not), and it looked at the sky.
  const std::vector<glm::vec3> bvh_rest = motion_->rest_positions();
  const std::int32_t hip = motion_->find_joint("hip"), neck = motion_->find_joint("neck"),
                     head = motion_->find_joint("head");
  ASSERT_GE(hip, 0);
  ASSERT_GE(neck, 0);
  ASSERT_GE(head, 0);
  auto centre = [&](const char* name) { return skeleton_->centers[joint(name)]; };
  const float trunk_rest = sagittal_lean_deg(centre("vc4") - centre("HumanoidRoot")) -
                           sagittal_lean_deg(bvh_rest[neck] - bvh_rest[hip]);
  const float neck_rest = sagittal_lean_deg(centre("skullbase") - centre("vc4")) -
                          sagittal_lean_deg(bvh_rest[head] - bvh_rest[neck]);
  std::vector<glm::quat> rot(motion_->joint_count());
  std::vector<glm::vec3> pos(motion_->joint_count());
  float worst_trunk = 0.0f, worst_neck = 0.0f, most_back = 0.0f;
  const std::size_t skip = static_cast<std::size_t>(RetargetOptions{}.skip_frames);
  for (std::size_t k = 0; k < frames_ && k + skip < motion_->frame_count; ++k) {
    motion_->pose(k + skip, rot, pos);
    const float trunk = sagittal_lean_deg(at(k, "vc4") - at(k, "HumanoidRoot"));
    const float neck_lean = sagittal_lean_deg(at(k, "skullbase") - at(k, "vc4"));
    worst_trunk = std::max(worst_trunk, std::abs(trunk - trunk_rest - sagittal_lean_deg(pos[neck] - pos[hip])));
    worst_neck = std::max(worst_neck, std::abs(neck_lean - neck_rest - sagittal_lean_deg(pos[head] - pos[neck])));
    most_back = std::min(most_back, trunk);
  }
  EXPECT_LT(worst_trunk, 2.0f);
  EXPECT_LT(worst_neck, 2.0f);
  // The capture walks upright, leaning a little forward: the trunk never leans back by more than 5 deg.
  EXPECT_GT(most_back, -5.0f);
}

TEST_F(RetargetWalk, ArmsHangDownNotInATPose) {
  // The BVH rest is a T-pose (wrists ~55 cm out to the side at shoulder height); compensated, the arms hang and
  // swing fore and aft. In the first walking frame the left arm hangs nearly straight down; the right one is swung
  // forward (wrist 33 cm ahead), still well below the shoulder and not out to the side.
  const glm::vec3 l_shoulder = at(0, "l_shoulder"), l_wrist = at(0, "l_wrist");
  const glm::vec3 r_shoulder = at(0, "r_shoulder"), r_wrist = at(0, "r_wrist");
  EXPECT_LT(l_wrist.y, l_shoulder.y - 0.4f);
  EXPECT_LT(r_wrist.y, r_shoulder.y - 0.25f);
  EXPECT_LT(std::abs(l_wrist.x - l_shoulder.x), 0.15f);
  EXPECT_LT(std::abs(r_wrist.x - r_shoulder.x), 0.15f);
  // Over the whole walk both wrists hang on average more than 0.4 m below their shoulders.
  for (const char* side : {"l", "r"}) {
    const std::string s(side);
    float drop = 0.0f;
    for (std::size_t k = 0; k < frames_; ++k) drop += at(k, (s + "_shoulder").c_str()).y - at(k, (s + "_wrist").c_str()).y;
    EXPECT_GT(drop / static_cast<float>(frames_), 0.4f) << s;
  }
  // And the left arm is on the left (+X): the BVH's axes are H-Anim's.
  EXPECT_GT(l_wrist.x, r_wrist.x);
  EXPECT_GT(at(0, "l_hip").x, at(0, "r_hip").x);
}

// The mocap walker: over several loops, a foot in stance stays where it landed (IK on the captured ankle
// position), and the walker keeps walking forward across loops instead of snapping back.
TEST_F(RetargetWalk, MocapDriveLocksFeetAcrossLoops) {
  const Skeleton& skeleton = *skeleton_;
  const auto joints = static_cast<std::uint32_t>(skeleton.joint_count());
  const MocapRig rig = make_mocap_rig(skeleton, result_->clip, result_->contacts);
  auto table = make_walker_table("mocap", joints);
  const float headings[3] = {0.0f, 0.7f, -2.0f};
  const float scales[3] = {1.0f, 1.0f, 1.1f};
  for (std::uint32_t w = 0; w < 3; ++w) {
    const std::uint32_t b = table->add(Entity{w + 1, 1});
    const float place[5] = {2.0f * static_cast<float>(w), 0.0f, -1.0f, headings[w], scales[w]};
    for (std::uint32_t c = 0; c < 5; ++c) table->f32(kWalkerPlacement, c)[b] = place[c];
    table->f32(kWalkerClock, 0)[b] = 0.37f * static_cast<float>(w);
    table->f32(kWalkerClock, 1)[b] = 1.0f;
  }
  WalkerLanes lanes = walker_lanes(*table, joints);
  const float dt = 1.0f / 60.0f;
  const std::int32_t ankles[2] = {rig.limbs[kLeftLeg].lower, rig.limbs[kRightLeg].lower};
  struct Lock {
    bool locked = false;
    int interval = -1;
    glm::vec3 world{0.0f};
    float point = -1.0f;
  };
  auto lock_of = [&](std::size_t w, int leg) {
    auto c = [&](std::uint32_t k) { return lanes.at(lanes.foot_lock, static_cast<std::size_t>(leg) * kLockFloats + k)[w]; };
    return Lock{c(kLockOn) > 0.5f, static_cast<int>(c(kLockInterval)), {c(kLockX), c(kLockY), c(kLockZ)}, c(kLockPoint)};
  };
  std::size_t rolled_onto_ball = 0;
  std::vector<Lock> previous(6);
  std::size_t locked_frames = 0;
  float worst = 0.0f;
  const glm::vec3 start0(lanes.at(lanes.placement, 0)[0], 0.0f, lanes.at(lanes.placement, 2)[0]);
  const int steps = static_cast<int>(3.2f * result_->clip.duration / dt);  // a little over three loops
  for (int step = 0; step < steps; ++step) {
    ASSERT_TRUE(make_mocap_drive_job(rig, *table, dt).run());
    ASSERT_TRUE(make_ik_job(skeleton, rig.limbs, *table).run());
    ASSERT_TRUE(make_fk_job(skeleton, *table).run());
    for (std::size_t w = 0; w < 3; ++w) {
      const glm::vec3 origin(lanes.at(lanes.placement, 0)[w], lanes.at(lanes.placement, 1)[w],
                             lanes.at(lanes.placement, 2)[w]);
      const glm::quat heading = glm::angleAxis(lanes.at(lanes.placement, 3)[w], glm::vec3(0, 1, 0));
      const float scale = lanes.at(lanes.placement, 4)[w];
      for (int leg = 0; leg < 2; ++leg) {
        const Lock now = lock_of(w, leg);
        Lock& before = previous[w * 2 + leg];
        if (now.locked && before.locked && now.interval == before.interval) {
          // The held contact point (heel, then ball) from FK's world matrix F(ankle) and the placement.
          float m[kAffineFloats];
          for (std::uint32_t c = 0; c < kAffineFloats; ++c)
            m[c] = lanes.at(lanes.world, static_cast<std::size_t>(ankles[leg]) * kAffineFloats + c)[w];
          const glm::vec3 offset = now.point == kContactBall ? rig.ball_offset[leg] : rig.heel_offset[leg];
          const glm::vec3 contact = glm::vec3(m[9], m[10], m[11]) + offset.x * glm::vec3(m[0], m[1], m[2]) +
                                    offset.y * glm::vec3(m[3], m[4], m[5]) + offset.z * glm::vec3(m[6], m[7], m[8]);
          const glm::vec3 world = origin + heading * (contact * scale);
          const float error = glm::length(world - now.world);
          worst = std::max(worst, error);
          EXPECT_LT(error, 1e-3f) << "walker " << w << " leg " << leg << " step " << step << " flags "
                                  << lanes.ik_flags[leg * lanes.stride + w] << " ik error "
                                  << lanes.at(lanes.ik_result, leg * kIkResultFloats)[w];
          if (now.point == before.point) {
            EXPECT_EQ(now.world, before.world) << "the lock itself moves only when the foot rolls onto its ball";
          } else {
            // Heel to ball, never back; the ball is held where the held foot put it, so nothing jumps.
            EXPECT_EQ(before.point, kContactHeel);
            EXPECT_EQ(now.point, kContactBall);
            ++rolled_onto_ball;
          }
          ++locked_frames;
        }
        before = now;
      }
    }
  }
  RecordProperty("worst_locked_foot_error_m", std::to_string(worst));
  EXPECT_GT(locked_frames, static_cast<std::size_t>(steps));  // both legs of 3 walkers: plenty of stance frames
  EXPECT_GT(rolled_onto_ball, 6u);  // most stances roll from the heel onto the ball
  // Three wraps later walker 0 (heading 0) is about three loop displacements further along +Z, not back at the start.
  const glm::vec3 end0(lanes.at(lanes.placement, 0)[0], 0.0f, lanes.at(lanes.placement, 2)[0]);
  EXPECT_NEAR(glm::length(end0 - start0), 3.0f * glm::length(rig.loop_displacement), 1e-3f);
  EXPECT_GT(end0.z - start0.z, 3.0f * 3.5f);
  // Walker 2 (scaled 1.1, heading -2 rad) moves along its own heading.
  const glm::vec3 dir2 = glm::angleAxis(-2.0f, glm::vec3(0, 1, 0)) * glm::vec3(0, 0, 1);
  const glm::vec3 moved2(lanes.at(lanes.placement, 0)[2] - 4.0f, 0.0f, lanes.at(lanes.placement, 2)[2] + 1.0f);
  EXPECT_GT(glm::dot(moved2, dir2), 0.95f * glm::length(moved2));
}

TEST(Retarget, MissingRequiredJointIsReported) {
  const std::string text =
      "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n End Site\n {\n  OFFSET 0 1 0\n"
      " }\n}\nMOTION\nFrames: 8\nFrame Time: 0.1\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n";
  const BvhMotion m = load_bvh_text(text, "tiny.bvh");
  const Skeleton s = load_default_humanoid().skeleton;
  try {
    retarget_bvh(m, s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    // One line, naming the file, every H-Anim joint nothing matched, why the shape did not do, and the way out.
    const std::string what = e.what();
    EXPECT_NE(what.find("tiny.bvh: cannot map the capture's joints: no joint name matched l_sternoclavicular, "),
              std::string::npos)
        << what;
    EXPECT_NE(what.find(", r_knee, "), std::string::npos) << what;
    EXPECT_NE(what.find("by shape: no joint where the legs and the spine branch"), std::string::npos) << what;
    EXPECT_NE(what.find("pass --retarget-map FILE"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace strata
