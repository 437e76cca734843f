#pragma once
// The command-line flags every scene command shares (crowd, view, bench, soak, the reports), filling a
// SceneOptions (scene/scene_setup.h).
#include "scene/scene_setup.h"

namespace CLI {
class App;
}

namespace strata::cli {

// Registers --walkers, --skeleton, --mesh, --motion, --clip, --rest, --seed, --spacing, --threads, --level, the
// muscle options (--muscles, --muscle-gain, --muscle-overrides) and --binding-overrides on `cmd`.
// Also --max-input-mb (add_input_limit_option).
void add_scene_options(CLI::App& cmd, SceneOptions& options);

// --max-input-mb: raises the input size limit (scene/input_formats.h) for this run.
void add_input_limit_option(CLI::App& cmd);

// Checks every input file the options name (skeleton, mesh, motion capture, muscle and override files) with
// check_input_path before any is read: a FIFO, a device, a symbolic link loop or an oversized file is refused
// with one line naming the flag. Throws LoadError.
void check_scene_inputs(const SceneOptions& options);

}  // namespace strata::cli
