#pragma once
// Walk parameters from body height and cadence (Inman/Saunders; Bruderlin & Calvert; as used by Memisoglu;
// ../shared/notes/tech-brief.md section 3.3). f = cadence in steps/min, H = body height in metres:
//   step length L = 0.004 f H          speed v = L f / 60 = f^2 H / 15000
//   t_step = 60 / f                    t_cycle = 2 t_step (a stride is two steps)
//   t_ds = (-0.0016 f + 0.2908) t_cycle, the duration of EACH of the two double-support phases
//   t_stance = t_step + t_ds           t_swing = t_step - t_ds
// Phase convention (fraction of the cycle, left heel strike = 0): right toe-off at d = t_ds / t_cycle, right heel
// strike at 0.5, left toe-off at 0.5 + d. A leg is in stance for its first 0.5 + d of its own cycle.
namespace strata {

inline constexpr float kMinCadence = 40.0f;   // steps/min; below this the formulas leave their fitted range
inline constexpr float kMaxCadence = 182.0f;  // the notes' maximum walking cadence

struct GaitParameters {
  float height = 0;          // m
  float cadence = 0;         // steps/min
  float step_length = 0;     // m
  float stride_length = 0;   // m, two steps
  float speed = 0;           // m/s
  float step_time = 0;       // s
  float cycle_time = 0;      // s
  float double_support = 0;  // s, each of the two phases
  float stance_time = 0;     // s
  float swing_time = 0;      // s

  float double_support_fraction() const { return double_support / cycle_time; }  // d
  float stance_fraction() const { return stance_time / cycle_time; }              // 0.5 + d
};

// Throws std::invalid_argument when height <= 0 or the cadence lies outside [kMinCadence, kMaxCadence].
GaitParameters gait_parameters(float height, float cadence);

// The cadence that walks at `speed` (m/s) for a body of `height`: f = sqrt(15000 v / H), clamped to the range.
float cadence_for_speed(float speed, float height);

// Fraction of a leg's own cycle at time of its heel strike (0) through toe-off (stance_fraction) to the next
// heel strike (1): true while in stance.
inline bool in_stance(float leg_phase, float stance_fraction) { return leg_phase < stance_fraction; }

}  // namespace strata
