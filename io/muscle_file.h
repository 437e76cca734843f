#pragma once
// The muscle file (JSON; the shipped default is data/muscles.json, which documents every field in its "_doc"):
//
//   { "format": "strata-muscles", "version": 1, "min_length_ratio": 0.5,
//     "muscles": [
//       { "name": "l_biceps",
//         "origin":    { "joint": "l_acromioclavicular", "offset_from": "l_shoulder", "offset": [0, -0.03, 0.02] },
//         "insertion": { "joint": "l_elbow", "offset": [0, -0.035, 0.018] },
//         "outward": [0, 0, 1], "control_points": 5, "parts": ["lShldr"], "radius": 0.075,
//         "forces": [ [[0, 1, 0, 0.0], ...], ... ] },          one list per control point of [dx, dy, dz, magnitude]
//       { "name": "r_biceps", "mirror_of": "l_biceps" } ] }
//
// An end rides on `joint`; its rest position is the rest centre of `offset_from` (default: `joint`) plus
// `offset` (metres, humanoid axes). Force directions are in the control point's local frame (components/muscle.h).
// `mirror_of` copies an earlier muscle through the body's midplane: joint names swap l_/r_, part names swap their
// leading l/r, x of every offset and of `outward` is negated, and so is the local x of every force direction
// (mirroring turns the frame left-handed; negating x turns it back).
//
// The second file, the per-muscle overrides (`strata crowd --muscle-overrides FILE`), scales forces at run time:
//   { "gain": 1.0, "muscles": { "l_biceps": 1.5, "r_biceps": 1.5 } }
#include <string>
#include <string_view>

#include "components/muscle.h"
#include "components/skeleton.h"

namespace strata {

// Parses a muscle file against `skeleton` (joint names resolved to indices, ends placed at rest, rest lengths
// computed). Throws LoadError "SOURCE: muscles[i] (name).field: reason" naming the file and the element at fault
// (or the JSON line and column for a syntax error); nothing is returned half-built.
MuscleSet parse_muscles(std::string_view json, std::string_view source, const Skeleton& skeleton);
MuscleSet load_muscle_file(const std::string& path, const Skeleton& skeleton);
// The shipped 12 muscles (data/muscles.json, embedded) for `skeleton`, which needs the default joint names.
MuscleSet default_muscles(const Skeleton& skeleton);

// Parses an overrides file against `set`: unknown muscle names, non-finite or negative gains are LoadErrors.
MuscleGains parse_muscle_overrides(std::string_view json, std::string_view source, const MuscleSet& set);
MuscleGains load_muscle_overrides(const std::string& path, const MuscleSet& set);

}  // namespace strata
