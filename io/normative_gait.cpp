#include "io/normative_gait.h"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "data/embedded.h"

namespace strata {
namespace {

[[noreturn]] void fail(std::size_t line, const std::string& why) {
  throw std::runtime_error("normative gait table, line " + std::to_string(line) + ": " + why);
}

}  // namespace

NormativeGait parse_normative_gait(std::string_view csv) {
  NormativeGait out;
  std::size_t line_no = 0, pos = 0;
  int row = 0;
  bool header = false;
  while (pos < csv.size()) {
    std::size_t end = csv.find('\n', pos);
    if (end == std::string_view::npos) end = csv.size();
    std::string line(csv.substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (line[0] == '#') {
      const std::size_t text = line.find_first_not_of("# ");
      if (text == std::string::npos) continue;
      if (!out.source.empty()) out.source += ' ';
      out.source.append(line, text, std::string::npos);
      continue;
    }
    if (!header) {
      if (line.rfind("phase_pct,", 0) != 0) fail(line_no, "expected the header row 'phase_pct,...'");
      header = true;
      continue;
    }
    if (row >= kGaitCycleSamples) fail(line_no, "more than 101 rows");
    float values[4];
    const char* p = line.c_str();
    for (int k = 0; k < 4; ++k) {
      char* next = nullptr;
      values[k] = std::strtof(p, &next);
      if (next == p || !std::isfinite(values[k])) fail(line_no, "expected 4 numbers");
      p = next;
      if (k < 3) {
        if (*p != ',') fail(line_no, "expected 4 comma-separated numbers");
        ++p;
      }
    }
    if (*p != '\0') fail(line_no, "trailing text after 4 numbers");
    if (values[0] != static_cast<float>(row)) fail(line_no, "phase " + std::to_string(values[0]) + " out of order");
    out.knee_flexion[row] = values[1];
    out.hip_flexion[row] = values[2];
    out.ankle_dorsiflexion[row] = values[3];
    ++row;
  }
  if (row != kGaitCycleSamples) fail(line_no, "expected 101 rows, got " + std::to_string(row));
  return out;
}

const NormativeGait& shipped_normative_gait() {
  static const NormativeGait table = [] {
    const auto bytes = embedded::find("data/normative_gait.csv");
    if (!bytes) throw std::runtime_error("normative gait table: data/normative_gait.csv is not embedded");
    return parse_normative_gait(*bytes);
  }();
  return table;
}

double curve_rms(const GaitCurve& a, const GaitCurve& b) {
  double sum = 0.0;
  for (int i = 0; i < kGaitCycleSamples; ++i) {
    const double d = static_cast<double>(a[i]) - b[i];
    sum += d * d;
  }
  return std::sqrt(sum / kGaitCycleSamples);
}

}  // namespace strata
