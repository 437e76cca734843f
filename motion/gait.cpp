#include "motion/gait.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace strata {

GaitParameters gait_parameters(float height, float cadence) {
  if (!(height > 0.0f) || !std::isfinite(height))
    throw std::invalid_argument("gait: body height must be positive, got " + std::to_string(height));
  if (!(cadence >= kMinCadence && cadence <= kMaxCadence))
    throw std::invalid_argument("gait: cadence " + std::to_string(cadence) + " steps/min outside [" +
                                std::to_string(kMinCadence) + ", " + std::to_string(kMaxCadence) + "]");
  GaitParameters g;
  g.height = height;
  g.cadence = cadence;
  g.step_length = 0.004f * cadence * height;
  g.stride_length = 2.0f * g.step_length;
  g.speed = g.step_length * cadence / 60.0f;
  g.step_time = 60.0f / cadence;
  g.cycle_time = 2.0f * g.step_time;
  g.double_support = (-0.0016f * cadence + 0.2908f) * g.cycle_time;
  g.stance_time = g.step_time + g.double_support;
  g.swing_time = g.step_time - g.double_support;
  return g;
}

float cadence_for_speed(float speed, float height) {
  if (!(height > 0.0f) || !(speed > 0.0f)) return kMinCadence;
  return std::clamp(std::sqrt(15000.0f * speed / height), kMinCadence, kMaxCadence);
}

}  // namespace strata
