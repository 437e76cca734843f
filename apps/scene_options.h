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
void add_scene_options(CLI::App& cmd, SceneOptions& options);

}  // namespace strata::cli
