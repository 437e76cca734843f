// The walk's joint-angle curves (issue 21): one walker of each stature at slow, middle and fast crowd speeds,
// measured over whole cycles from the FK output (scene/gait_cycle.h), against features a gait lab reads off a
// normal walk (knee nearly straight at heel strike, yielding in loading response, nearly straight again in
// terminal stance, folding ~60 deg in swing; ankle near neutral at heel strike; arms swinging both sides of the
// hanging pose; pelvis rising and falling a few centimetres).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/hanim_loader.h"
#include "io/normative_gait.h"
#include "scene/gait_cycle.h"
#include "systems/gait_metrics.h"

namespace strata {
namespace {

const Rig& default_rig() {
  static const Rig rig = to_rig(load_default_humanoid());
  return rig;
}

struct Walker {
  float speed, height;
};

class GaitCycleFeaturesTest : public ::testing::TestWithParam<Walker> {};

TEST_P(GaitCycleFeaturesTest, CurvesHaveTheFeaturesOfANormalWalk) {
  const Walker w = GetParam();
  GaitCycleOptions o;
  o.speed = w.speed;
  o.height = w.height;
  o.cycles = 2;
  const GaitCycle c = measure_gait_cycle(default_rig(), GaitStyle{}, o);
  ASSERT_EQ(c.cycles, 2);
  EXPECT_NEAR(c.speed_m_s, w.speed, 0.02);
  EXPECT_NEAR(c.height_m, w.height, 1e-4);
  for (int i = 0; i < kGaitCycleSamples; ++i) {
    ASSERT_TRUE(std::isfinite(c.knee_flexion[i]) && std::isfinite(c.hip_flexion[i]) &&
                std::isfinite(c.ankle_dorsiflexion[i]) && std::isfinite(c.shoulder_flexion[i]) &&
                std::isfinite(c.trunk_pitch[i]));
  }
  const GaitCycleFeatures f = gait_cycle_features(c);
  // Heel strike with an extended knee (issue target 8 deg). Angles are a gait lab's since the rest leg is
  // straight (LocomotionRig::rest_*): 6.0-7.1 deg (the slow short steps landed 10.3-11.7 deg bent before the
  // footprint lead grew for short steps, GaitStyle::lead_short_step_rise).
  EXPECT_LE(f.heel_strike_knee_deg, 8.5);
  EXPECT_GE(f.heel_strike_knee_deg, -3.0) << "no hyperextension";
  // Loading response: the knee yields after heel strike.
  EXPECT_GE(f.loading_knee_peak_deg, f.heel_strike_knee_deg + 5.0);
  // Terminal stance nearly straight (the target 10): 4.4-5.3 deg (the short walker at 1.8 m/s
  // kept 14.8 before the heel rose earlier and long steps took a shorter lead, GaitStyle::lead_long_step_drop).
  EXPECT_LE(f.stance_knee_min_deg, 10.0);
  // The swing knee folds (target 55-70 deg; the old walk peaked at 51).
  EXPECT_GE(f.swing_knee_peak_deg, 55.0);
  EXPECT_LE(f.swing_knee_peak_deg, 70.0);
  // Hip: flexed at heel strike, extended before toe-off, not past -25 deg (the target): -16.6..-24.7 over
  // the six walkers (at 1.8 m/s -26.2 and -27.1 before the fast walk's push-off, GaitStyle::toe_off_long_step_rise).
  EXPECT_GT(c.hip_flexion[0], 10.0f);
  EXPECT_LT(f.hip_min_deg, 0.0);
  EXPECT_GE(f.hip_min_deg, -25.0);
  // Ankle near neutral at heel strike (the heel rocker; the strike pitch is fixed, so short slow steps land
  // 6.8 deg dorsiflexed), plantarflexed at push-off.
  EXPECT_NEAR(c.ankle_dorsiflexion[0], 0.0, 8.0);
  EXPECT_LT(f.ankle_min_deg, -10.0);
  // Arms swing both sides of the hanging pose, the left one back at left heel strike; the swing scales with the
  // step (at 0.8 m/s the short walker's reaches only +7.5 deg forward).
  EXPECT_LT(f.shoulder_min_deg, -10.0);
  EXPECT_GT(f.shoulder_max_deg, 5.0);
  EXPECT_LT(c.shoulder_flexion[0], 0.0f);
  EXPECT_GT(c.shoulder_flexion[50], 0.0f);
  // Trunk near vertical.
  EXPECT_LE(std::max(std::abs(f.trunk_min_deg), std::abs(f.trunk_max_deg)), 6.0);
  // The pelvis rises and falls a few centimetres (literature 3-5, target 2.5-5): 3.1-4.3 up to 1.3 m/s, 4.7 and
  // 4.9 at 1.8 m/s (5.5 and 5.7 before the fast walk's list and turn; 5.2-5.3 for the tall one with the later heel
  // rise before the bob softened for long steps, GaitStyle::bob_long_step_drop).
  EXPECT_GE(c.pelvis_vertical_excursion_cm, 2.5);
  EXPECT_LE(c.pelvis_vertical_excursion_cm, 5.0);
}

INSTANTIATE_TEST_SUITE_P(SpeedsAndStatures, GaitCycleFeaturesTest,
                         ::testing::Values(Walker{0.8f, 1.63f}, Walker{1.3f, 1.63f}, Walker{1.8f, 1.63f},
                                           Walker{0.8f, 1.81f}, Walker{1.3f, 1.81f}, Walker{1.8f, 1.81f}),
                         [](const ::testing::TestParamInfo<Walker>& info) {
                           return "v" + std::to_string(static_cast<int>(std::lround(info.param.speed * 10))) + "_h" +
                                  std::to_string(static_cast<int>(std::lround(info.param.height * 100)));
                         });

TEST(GaitCycle, CloserToTheNormativeSubjectThanTheCrouchedWalk) {
  // RMS against the subject at 1.2 m/s. Read as local rotations from ISO 200x's bent rest leg (which made a knee
  // 18 deg bent read 0): the walk before issue 21 measured knee 23.5, hip 22.0, ankle 14.7 deg; with rockers and a
  // hand-placed swing arc 12.1, 12.8, 12.2; with the swing on the normative angles and a deeper loading
  // response 5.9, 3.6, 10.9. That walk on the straightened leg, read in a gait lab's angles: 14.7, 4.4, 11.9. Now, the
  // stance knee held at the subject's angles by the pelvis and then by the heel rise: 7.3, 5.4, 7.3; after the joint
  // search of GaitStyle (heel-off, bob curvature): 7.7, 5.3, 7.1; with the longer lead, the list's lag and the
  // swing's catch-up: 6.0, 3.5, 5.7; with the fast walk's search: 5.9, 3.6, 5.5; with the later heel rise over the
  // longer lead (GaitStyle::heel_off, footprint_lead): 5.7, 3.3, 4.9, within the targets (6, 6, 5).
  const GaitCycle c = measure_gait_cycle(default_rig(), GaitStyle{}, {});
  const NormativeRms rms = normative_rms(c, shipped_normative_gait());
  EXPECT_LE(rms.knee, 6.0);
  EXPECT_LT(rms.hip, 4.5);
  EXPECT_LE(rms.ankle, 5.0);
}

// The fast walk's shapes (GaitStyle::*_long_step_*) grow with the step beyond the reference: the default walker at
// 1.2 m/s walks exactly as without them, and the short walker at 1.8 m/s needs them for the hip and
// pelvis targets (without them, on the other numbers of the same search: hip -29.8 deg, excursion 5.4 cm).
TEST(GaitCycle, TheFastWalkShapesChangeOnlyLongSteps) {
  GaitStyle plain;
  plain.yaw_long_step_rise = plain.tilt_long_step_rise = plain.toe_off_long_step_rise = 0.0f;
  plain.lift_long_step_drop = 0.0f;
  const GaitCycle with_default = measure_gait_cycle(default_rig(), GaitStyle{}, {});
  const GaitCycle plain_default = measure_gait_cycle(default_rig(), plain, {});
  for (int i = 0; i < kGaitCycleSamples; ++i) {
    ASSERT_EQ(with_default.knee_flexion[i], plain_default.knee_flexion[i]) << i;
    ASSERT_EQ(with_default.hip_flexion[i], plain_default.hip_flexion[i]) << i;
  }
  GaitCycleOptions fast;
  fast.speed = 1.8f;
  fast.height = 1.63f;
  fast.cycles = 2;
  const GaitCycle with = measure_gait_cycle(default_rig(), GaitStyle{}, fast);
  const GaitCycle without = measure_gait_cycle(default_rig(), plain, fast);
  const GaitCycleFeatures fw = gait_cycle_features(with), fo = gait_cycle_features(without);
  std::printf("1.63 m at 1.8 m/s: hip min %.1f with, %.1f without; excursion %.2f with, %.2f without\n", fw.hip_min_deg,
              fo.hip_min_deg, with.pelvis_vertical_excursion_cm, without.pelvis_vertical_excursion_cm);
  EXPECT_LT(fo.hip_min_deg, -25.0);
  EXPECT_GE(fw.hip_min_deg, -25.0);
  EXPECT_GT(without.pelvis_vertical_excursion_cm, 5.0);
  EXPECT_LE(with.pelvis_vertical_excursion_cm, 5.0);
}

// The swing follows the normative swing about the real hip between its catch-up and its landing
// (GaitStyle::swing_catch_up): spread evenly over the swing, the foot's misfits at toe-off and at heel strike held
// it behind the normative path through mid-swing, the thigh 2-4 deg behind the subject's from 70 to 80 % of the
// cycle. (Late swing is bound by the toe's ground clearance, with or without.) Since the footprint lead went to 0.6
// (2026-11-28) the landing misfit is smaller and so is the gain: 2.42 against 3.07 deg
// (the bound was 0.75 before).
TEST(GaitCycle, TheSwingThighFollowsTheSubjectWithTheCatchUp) {
  auto mid_swing_hip_rms = [](const GaitCycle& c) {
    const NormativeGait& n = shipped_normative_gait();
    double sum = 0.0;
    int count = 0;
    for (int i = 68; i <= 82; ++i, ++count) {
      const double d = c.hip_flexion[i] - n.hip_flexion[static_cast<std::size_t>(i)];
      sum += d * d;
    }
    return std::sqrt(sum / count);
  };
  GaitStyle spread;
  spread.swing_catch_up = 0.0f;
  const double with = mid_swing_hip_rms(measure_gait_cycle(default_rig(), GaitStyle{}, {}));
  const double without = mid_swing_hip_rms(measure_gait_cycle(default_rig(), spread, {}));
  std::printf("mid-swing hip RMS %.2f with, %.2f without\n", with, without);
  EXPECT_LT(with, 0.85 * without) << "with " << with << " deg, spread evenly " << without << " deg";
}

// The stance knee angles the pelvis and the heel rise hold (systems/locomotion.h kStanceKneeDeg) are the shipped
// table's, sampled evenly from its heel strike to its toe-off.
TEST(NormativeGait, TheWalksStanceKneeIsTheShippedTablesStanceKnee) {
  const NormativeGait& n = shipped_normative_gait();
  for (std::size_t k = 0; k < kStanceKnots; ++k) {
    const float x = kSwingToeOffPhase * static_cast<float>(k) / (kStanceKnots - 1) * (n.knee_flexion.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(x), n.knee_flexion.size() - 2);
    const float t = x - static_cast<float>(i);
    EXPECT_NEAR(kStanceKneeDeg[k], n.knee_flexion[i] + t * (n.knee_flexion[i + 1] - n.knee_flexion[i]), 0.02)
        << "knot " << k;
  }
}

// The swing the walk generator follows (systems/locomotion.h kSwingHipDeg...) is the shipped table's, sampled
// evenly from its toe-off to its heel strike.
TEST(NormativeGait, TheWalksSwingIsTheShippedTablesSwing) {
  const NormativeGait& n = shipped_normative_gait();
  auto at = [](const GaitCurve& curve, float phase) {
    const float x = phase * static_cast<float>(curve.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(x), curve.size() - 2);
    const float t = x - static_cast<float>(i);
    return curve[i] + t * (curve[i + 1] - curve[i]);
  };
  for (std::size_t k = 0; k < kSwingKnots; ++k) {
    const float phase = kSwingToeOffPhase + (1.0f - kSwingToeOffPhase) * static_cast<float>(k) / (kSwingKnots - 1);
    EXPECT_NEAR(kSwingHipDeg[k], at(n.hip_flexion, phase), 0.02) << "knot " << k;
    EXPECT_NEAR(kSwingKneeDeg[k], at(n.knee_flexion, phase), 0.02) << "knot " << k;
    EXPECT_NEAR(kSwingAnkleDeg[k], at(n.ankle_dorsiflexion, phase), 0.02) << "knot " << k;
  }
}

TEST(GaitCycle, RefusesBadOptions) {
  GaitCycleOptions o;
  o.speed = 0.0f;
  EXPECT_THROW(measure_gait_cycle(default_rig(), GaitStyle{}, o), std::invalid_argument);
  o = {};
  o.height = NAN;
  EXPECT_THROW(measure_gait_cycle(default_rig(), GaitStyle{}, o), std::invalid_argument);
}

TEST(NormativeGait, ShippedTableIsOneCycleFromHeelStrike) {
  const NormativeGait& n = shipped_normative_gait();
  EXPECT_NE(n.source.find("CC BY 3.0"), std::string::npos);
  EXPECT_NEAR(n.knee_flexion[0], 0.0, 5.0) << "heel strike with an extended knee";
  float swing_peak = 0.0f;
  for (float v : n.knee_flexion) swing_peak = std::max(swing_peak, v);
  EXPECT_NEAR(swing_peak, 69.6, 1.0);  // data-README: knee_angle_r reaches -69.6 deg
  EXPECT_DOUBLE_EQ(curve_rms(n.knee_flexion, n.knee_flexion), 0.0);
}

TEST(NormativeGait, ParserNamesTheBadLine) {
  EXPECT_THROW(parse_normative_gait("# x\nphase_pct,a,b,c\n0,1,2\n"), std::runtime_error);
  EXPECT_THROW(parse_normative_gait("0,1,2,3\n"), std::runtime_error);
  try {
    parse_normative_gait("# note\nphase_pct,k,h,a\n0,1,2,3\n2,1,2,3\n");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
