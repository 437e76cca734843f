#include "apps/report_gait_cycle.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace strata::cli {
namespace {

nlohmann::json curve_json(const GaitCurve& curve) {
  nlohmann::json out = nlohmann::json::array();
  // Two decimals: the curves are read by people and plotted; float noise in the JSON would only hide that.
  for (const float v : curve) out.push_back(std::round(static_cast<double>(v) * 100.0) / 100.0);
  return out;
}

}  // namespace

nlohmann::json gait_cycle_json(const GaitCycle& c, const NormativeGait& normative, bool curves,
                               const GaitCycleTargets& t) {
  const GaitCycleFeatures f = gait_cycle_features(c);
  const NormativeRms rms = normative_rms(c, normative);
  nlohmann::json j;
  j["height_m"] = c.height_m;
  j["speed_m_s"] = c.speed_m_s;
  j["cadence_steps_min"] = c.cadence_steps_min;
  j["cycles_averaged"] = c.cycles;
  j["stance_fraction"] = f.stance_fraction;
  if (curves) {
    j["phase_start"] = "left heel strike";
    j["knee_flexion_deg"] = curve_json(c.knee_flexion);
    j["hip_flexion_deg"] = curve_json(c.hip_flexion);
    j["ankle_dorsiflexion_deg"] = curve_json(c.ankle_dorsiflexion);
    j["shoulder_flexion_deg"] = curve_json(c.shoulder_flexion);
    j["trunk_pitch_deg"] = curve_json(c.trunk_pitch);
  }
  j["pelvis_vertical_excursion_cm"] = c.pelvis_vertical_excursion_cm;
  j["normative_rms_deg"] = {{"knee", rms.knee}, {"hip", rms.hip}, {"ankle", rms.ankle}};
  j["normative_source"] = normative.source;
  j["features"] = {{"heel_strike_knee_deg", f.heel_strike_knee_deg},
                   {"loading_knee_peak_deg", f.loading_knee_peak_deg},
                   {"stance_knee_min_deg", f.stance_knee_min_deg},
                   {"swing_knee_peak_deg", f.swing_knee_peak_deg},
                   {"hip_min_deg", f.hip_min_deg},
                   {"hip_max_deg", f.hip_max_deg},
                   {"ankle_min_deg", f.ankle_min_deg},
                   {"ankle_max_deg", f.ankle_max_deg},
                   {"shoulder_min_deg", f.shoulder_min_deg},
                   {"shoulder_max_deg", f.shoulder_max_deg},
                   {"trunk_min_deg", f.trunk_min_deg},
                   {"trunk_max_deg", f.trunk_max_deg}};
  // The features (a gait lab's normative ranges) apply at every speed; the RMS is against one subject walking one
  // speed (about 1.05 m/s on this leg), so a class's features_met is reported beside its targets_met.
  const bool features_met = c.cycles > 0 && f.heel_strike_knee_deg <= t.heel_strike_knee_max_deg &&
                             f.swing_knee_peak_deg >= t.swing_peak_min_deg &&
                             f.swing_knee_peak_deg <= t.swing_peak_max_deg &&
                             f.stance_knee_min_deg <= t.stance_knee_min_max_deg &&
                             f.hip_min_deg >= t.hip_min_deg && f.hip_max_deg <= t.hip_max_deg &&
                             c.pelvis_vertical_excursion_cm >= t.excursion_min_cm &&
                             c.pelvis_vertical_excursion_cm <= t.excursion_max_cm &&
                             std::max(std::abs(f.trunk_min_deg), std::abs(f.trunk_max_deg)) <= t.trunk_abs_max_deg;
  const bool met = features_met && rms.knee <= t.rms_knee_hip_deg && rms.hip <= t.rms_knee_hip_deg &&
                   rms.ankle <= t.rms_ankle_deg;
  j["features_met"] = features_met;
  j["targets_met"] = met;
  return j;
}

std::string gait_cycle_svg(const std::vector<GaitCycle>& cycles, const NormativeGait& normative) {
  // Five panels in a column, one per curve, 0-100 % of the cycle across; the normative subject grey and dashed.
  struct Panel {
    const char* title;
    const GaitCurve GaitCycle::*curve;
    const GaitCurve* reference;
    float lo, hi;
  };
  const Panel panels[] = {
      {"Knee flexion (deg)", &GaitCycle::knee_flexion, &normative.knee_flexion, -10.0f, 80.0f},
      {"Hip flexion (deg)", &GaitCycle::hip_flexion, &normative.hip_flexion, -40.0f, 60.0f},
      {"Ankle dorsiflexion (deg)", &GaitCycle::ankle_dorsiflexion, &normative.ankle_dorsiflexion, -30.0f, 25.0f},
      {"Shoulder flexion (deg)", &GaitCycle::shoulder_flexion, nullptr, -40.0f, 40.0f},
      {"Trunk pitch, forward + (deg)", &GaitCycle::trunk_pitch, nullptr, -10.0f, 10.0f},
  };
  const char* colours[] = {"#c0392b", "#2471a3", "#1e8449", "#7d3c98", "#b9770e", "#5d6d7e"};
  const float width = 640.0f, panel_h = 150.0f, left = 60.0f, right = 20.0f, top = 80.0f, gap = 40.0f;
  const float plot_w = width - left - right;
  const float height = top + 5.0f * (panel_h + gap) + 20.0f;
  std::string svg;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
                "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                width, height);
  svg += buf;
  std::snprintf(buf, sizeof buf, "<text x=\"%.0f\" y=\"20\" font-size=\"14\">Strata walk (colours) against the "
                "OpenSim subject (grey, dashed), one cycle from left heel strike</text>\n", left);
  svg += buf;
  for (std::size_t k = 0; k < cycles.size(); ++k) {
    // Three walkers to a legend row.
    std::snprintf(buf, sizeof buf, "<text x=\"%.0f\" y=\"%.0f\" fill=\"%s\">%.2f m, %.1f m/s%s</text>\n",
                  left + 180.0f * static_cast<float>(k % 3), 40.0f + 16.0f * static_cast<float>(k / 3),
                  colours[k % 6], cycles[k].height_m, cycles[k].speed_m_s, k == 0 ? " (bold)" : "");
    svg += buf;
  }
  for (int p = 0; p < 5; ++p) {
    const Panel& panel = panels[p];
    const float y0 = top + static_cast<float>(p) * (panel_h + gap);
    auto px = [&](float pct) { return left + plot_w * pct / 100.0f; };
    auto py = [&](float v) { return y0 + panel_h * (panel.hi - std::clamp(v, panel.lo, panel.hi)) / (panel.hi - panel.lo); };
    std::snprintf(buf, sizeof buf, "<text x=\"%.0f\" y=\"%.0f\" font-weight=\"bold\">%s</text>\n", left, y0 - 6.0f,
                  panel.title);
    svg += buf;
    // Stance of the first walker shaded.
    if (!cycles.empty()) {
      const double stance = gait_cycle_features(cycles[0]).stance_fraction;
      std::snprintf(buf, sizeof buf, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f2f3f4\"/>\n",
                    px(0.0f), y0, px(static_cast<float>(100.0 * stance)) - px(0.0f), panel_h);
      svg += buf;
    }
    const float step = (panel.hi - panel.lo) > 40.0f ? 20.0f : (panel.hi - panel.lo) > 20.0f ? 10.0f : 5.0f;
    for (float v = std::ceil(panel.lo / step) * step; v <= panel.hi + 1e-3f; v += step) {
      std::snprintf(buf, sizeof buf,
                    "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"1\"/>\n"
                    "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.0f</text>\n",
                    px(0.0f), py(v), px(100.0f), py(v), v == 0.0f ? "#888" : "#ddd", left - 6.0f, py(v) + 4.0f, v);
      svg += buf;
    }
    for (int pct = 0; pct <= 100; pct += 20) {
      std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#555\">%d%%</text>\n",
                    px(static_cast<float>(pct)), y0 + panel_h + 14.0f, pct);
      svg += buf;
    }
    std::snprintf(buf, sizeof buf,
                  "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#888\"/>\n",
                  px(0.0f), y0, plot_w, panel_h);
    svg += buf;
    auto polyline = [&](const GaitCurve& curve, const char* colour, float stroke, const char* dash) {
      svg += "<polyline fill=\"none\" stroke=\"";
      svg += colour;
      std::snprintf(buf, sizeof buf, "\" stroke-width=\"%.1f\"%s points=\"", stroke, dash);
      svg += buf;
      for (int i = 0; i < kGaitCycleSamples; ++i) {
        std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(static_cast<float>(i)), py(curve[i]));
        svg += buf;
      }
      svg += "\"/>\n";
    };
    if (panel.reference) polyline(*panel.reference, "#7f8c8d", 2.5f, " stroke-dasharray=\"6,4\"");
    for (std::size_t k = cycles.size(); k-- > 0;)
      polyline(cycles[k].*panel.curve, colours[k % 6], k == 0 ? 2.5f : 1.2f, "");
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace strata::cli
