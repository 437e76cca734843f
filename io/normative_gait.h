#pragma once
// The normative walk the gait report compares the generated walk with: knee flexion, hip flexion and ankle
// dorsiflexion of one measured subject (OpenSim subject01 walk, CC BY 3.0, Delp et al.; source note in
// data/normative_gait.csv, derived by scripts/normative_gait_table.py) as 101 samples over one gait cycle that
// starts at heel strike. Shipped (embedded) rather than read from ../shared, so the report runs anywhere; the
// licence allows it with the credit the file carries.
#include <array>
#include <string>
#include <string_view>

namespace strata {

inline constexpr int kGaitCycleSamples = 101;  // 0 %, 1 %, ..., 100 % of the cycle
using GaitCurve = std::array<float, kGaitCycleSamples>;

struct NormativeGait {
  GaitCurve knee_flexion{}, hip_flexion{}, ankle_dorsiflexion{};  // degrees
  std::string source;                                             // the file's comment lines, joined
};

// Parses the CSV format of data/normative_gait.csv ('#' comment lines, a header row, then 101 rows
// phase_pct,knee,hip,ankle with phase 0..100 in order). Throws std::runtime_error naming the line on anything else.
NormativeGait parse_normative_gait(std::string_view csv);

// The shipped table (data/normative_gait.csv, embedded).
const NormativeGait& shipped_normative_gait();

// Root mean square difference of two curves over the 101 samples, degrees.
double curve_rms(const GaitCurve& a, const GaitCurve& b);

}  // namespace strata
