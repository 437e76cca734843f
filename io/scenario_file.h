#pragma once
// The scenario file (JSON; the format, every key, its units and defaults: docs/scenarios.md). Five scenarios ship
// embedded in the library (data/scenarios/NAME.json): circle, crossing, bottleneck, plaza, track.
//
//   { "format": "strata-scenario", "version": 1, "name": "demo",
//     "ground": { "min": [-20, -20], "max": [20, 20] },
//     "obstacles": [ { "polygon": [[0, 0], [2, 0], [1, 2]] },
//                    { "box": { "center": [5, 5], "size": [4, 0.2], "angle_deg": 30 } } ],
//     "agents": { "radius": 0.25, "speed": { "mean": 1.3, "sd": 0.15, "min": 0.8, "max": 1.8 } },
//     "groups": [ { "name": "west", "count": 50,
//                   "spawn": { "shape": "rect", "min": [-18, -5], "max": [-12, 5] },
//                   "goal": { "kind": "region", "min": [12, -5], "max": [18, 5] } } ],
//     "duration_s": 60, "seed": 1 }
//
// Errors: every loader here throws LoadError "SOURCE: /json/pointer: reason" naming the file and the element at
// fault (or the JSON line and column for a syntax error); unknown keys are rejected with their pointer. Nothing
// is returned half-built.
#include <string>
#include <string_view>
#include <vector>

#include "components/scenario.h"

namespace strata {

// Parses and validates a scenario. `source_name` names it in errors and becomes Scenario::source; a relative
// `walkable_obj` is resolved against the directory of `source_name`.
Scenario parse_scenario(std::string_view json, const std::string& source_name);
// Reads and parses the file at `path` (a missing or unreadable file is a LoadError naming it).
Scenario load_scenario(const std::string& path);
// A shipped scenario by name (source "data/scenarios/NAME.json", read from the embedded copy). An unknown name is
// a LoadError listing the shipped ones.
Scenario shipped_scenario(const std::string& name);
// The shipped names, sorted.
std::vector<std::string> shipped_scenario_names();
// A shipped name if `name_or_file` is one, otherwise a path to a scenario file.
Scenario resolve_scenario(const std::string& name_or_file);

}  // namespace strata
