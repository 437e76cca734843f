#pragma once
// The command-line flags every scene command shares (crowd, view, bench, soak, the reports), filling a
// SceneOptions (scene/scene_setup.h).
#include <cstdint>

#include <nlohmann/json_fwd.hpp>

#include "scene/scene_setup.h"

namespace CLI {
class App;
}

namespace strata::cli {

// Registers --walkers, --skeleton, --mesh, --motion, --clip, --rest, --seed, --spacing, --threads, --level,
// --skinning, the muscle options (--muscles, --muscle-gain, --muscle-overrides) and --binding-overrides on `cmd`.
// Also --max-input-mb (add_input_limit_option).
void add_scene_options(CLI::App& cmd, SceneOptions& options);

// --max-input-mb: raises the input size limit (scene/input_formats.h) for this run.
void add_input_limit_option(CLI::App& cmd);

// Checks every input file the options name (skeleton, mesh, motion capture, muscle and override files) with
// check_input_path before any is read: a FIFO, a device, a symbolic link loop or an oversized file is refused
// with one line naming the flag. Throws LoadError.
void check_scene_inputs(const SceneOptions& options);

// A lower bound on the memory a crowd of these options needs (per-walker joint state and each walker's skinned
// vertices at the requested level), for the shipped body; imported bodies are only known once loaded, so for
// them the bound counts joints alone. A lower bound so that the check below never refuses a crowd that fits.
std::uint64_t estimate_crowd_bytes(const SceneOptions& options);
// Empty when estimate_crowd_bytes fits in available_memory_bytes(), else the one-line reason.
std::string check_crowd_memory(const SceneOptions& options);

// What summary files record about the inputs: skeleton, mesh, motion, muscles and override files as given
// (null where the shipped default was used).
nlohmann::json scene_inputs_json(const SceneOptions& options);

}  // namespace strata::cli
