// Gait formulas against the worked table in ../shared/notes/tech-brief.md section 3.3 (H = 1.75 m).
#include <gtest/gtest.h>

#include <cmath>

#include "motion/gait.h"

namespace strata {
namespace {

struct Row {
  float cadence, step, speed, cycle, ds_each, ds_pct, stance_pct;
};

TEST(Gait, MatchesTheWorkedTable) {
  // Values as printed in the notes (rounded there to 2-3 digits).
  const Row rows[] = {{90, 0.63f, 0.95f, 1.33f, 0.196f, 14.7f, 64.7f},
                      {110, 0.77f, 1.41f, 1.09f, 0.125f, 11.5f, 61.5f},
                      {120, 0.84f, 1.68f, 1.00f, 0.099f, 9.9f, 59.9f}};
  for (const Row& r : rows) {
    const GaitParameters g = gait_parameters(1.75f, r.cadence);
    EXPECT_NEAR(g.step_length, r.step, 0.005f) << r.cadence;
    EXPECT_NEAR(g.stride_length, 2.0f * g.step_length, 1e-6f);
    EXPECT_NEAR(g.speed, r.speed, 0.006f) << r.cadence;
    EXPECT_NEAR(g.cycle_time, r.cycle, 0.005f) << r.cadence;
    EXPECT_NEAR(g.double_support, r.ds_each, 0.0015f) << r.cadence;
    EXPECT_NEAR(100.0f * g.double_support_fraction(), r.ds_pct, 0.06f) << r.cadence;
    EXPECT_NEAR(100.0f * g.stance_fraction(), r.stance_pct, 0.06f) << r.cadence;
    EXPECT_NEAR(g.stance_time + g.swing_time, g.cycle_time, 1e-5f) << "stance + swing = one cycle";
  }
}

TEST(Gait, CadenceForSpeedInvertsTheSpeedFormula) {
  for (float h : {1.5f, 1.75f, 1.95f})
    for (float f : {70.0f, 100.0f, 140.0f}) {
      const GaitParameters g = gait_parameters(h, f);
      EXPECT_NEAR(cadence_for_speed(g.speed, h), f, 1e-3f);
    }
  EXPECT_EQ(cadence_for_speed(100.0f, 1.75f), kMaxCadence) << "clamped";
  EXPECT_EQ(cadence_for_speed(0.0f, 1.75f), kMinCadence);
}

TEST(Gait, RejectsNonsense) {
  EXPECT_THROW(gait_parameters(0.0f, 100.0f), std::invalid_argument);
  EXPECT_THROW(gait_parameters(1.75f, 300.0f), std::invalid_argument);
  EXPECT_THROW(gait_parameters(1.75f, std::nanf("")), std::invalid_argument);
  EXPECT_TRUE(in_stance(0.1f, 0.6f));
  EXPECT_FALSE(in_stance(0.7f, 0.6f));
}

}  // namespace
}  // namespace strata
