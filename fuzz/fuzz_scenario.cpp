// libFuzzer target: the scenario file (io/scenario_file.h). A parsed scenario is checked against the promises of
// components/scenario.h (counter-clockwise simple polygons, counts in range), which a loader bug would break
// silently otherwise; the navigation mesh is not built (Recast is not part of the fuzzed loaders and a build can
// take seconds).
#include <cstdlib>

#include "components/scenario.h"
#include "fuzz/fuzz_common.h"
#include "io/scenario_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  strata::Scenario s;
  try {
    s = strata::parse_scenario(strata::fuzz::as_text(data, size), "fuzz_scenario.json");
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz_scenario.json");
    return 0;
  }
  for (const strata::ScenarioPolygon& p : s.obstacles) {
    double area = 0.0;
    for (std::size_t i = 0; i < p.points.size(); ++i) {
      const glm::vec2 a = p.points[i], b = p.points[(i + 1) % p.points.size()];
      area += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
    }
    if (p.points.size() < 3 || !(area > 0.0)) std::abort();
  }
  if (s.agent_count() > 1000000 || !(s.duration_s > 0.0f) || !(s.agents.radius > 0.0f)) std::abort();
  if (!s.has_track && s.groups.empty()) std::abort();
  return 0;
}
