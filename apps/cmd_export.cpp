// strata export: one skinned walker of the shipped rig (skeleton, body level, weights, a baked walk) as a file
// other tools open. glTF 2.0 binary is the one format; the Khronos validator accepts it with 0 errors
// (scripts/strata.sh validate-gltf).
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "io/gltf_export.h"
#include "io/hanim_loader.h"
#include "scene/walk_bake.h"
#include "rig/body_rig.h"

namespace strata::cli {
namespace {

struct ExportOptions {
  std::string format = "gltf";
  int level = 0;
  float seconds = 2.0f;
  float fps = 30.0f;
  std::uint64_t seed = 1;
  std::string out;
  bool rest = false;
};

int run_export(const ExportOptions& o) {
  if (!check_outputs("export", {{"--out", o.out}})) return kExitFailure;
  if (o.format != "gltf") {
    std::cerr << "strata export: unknown --format '" << o.format << "' (supported: gltf)\n";
    return 2;
  }
  if (!(o.seconds > 0.0f) || !(o.fps > 0.0f)) {
    std::cerr << "strata export: --seconds and --fps must be positive\n";
    return 2;
  }
  try {
    const auto start = std::chrono::steady_clock::now();
    Rig rig = to_rig(load_default_humanoid());
    rig.body = default_bound_body();
    if (o.level < 0 || static_cast<std::size_t>(o.level) >= rig.body->levels.size()) {
      std::cerr << "strata export: no body level " << o.level << " (the rig has " << rig.body->levels.size()
                << ")\n";
      return 2;
    }
    BakedWalk walk;
    if (!o.rest) walk = bake_walk(rig, WalkBakeOptions{o.seconds, o.fps, o.seed});
    const GltfExportStats stats = write_gltf_binary(o.out, rig.skeleton, rig.body->levels[o.level],
                                                    o.rest ? nullptr : &walk.clip, "strata_walker_level" +
                                                                                      std::to_string(o.level));
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "strata export: wrote " << o.out << " (" << stats.bytes << " bytes): level " << o.level << ", "
              << stats.vertices << " vertices";
    if (stats.written_vertices != stats.vertices)
      std::cout << " (" << stats.written_vertices << " in the file: split at UV seams)";
    std::cout << ", " << stats.triangles << " triangles, " << stats.joints << " joints";
    if (!o.rest) std::cout << ", walk " << walk.clip.duration << " s in " << stats.keys << " keys";
    std::cout << ", " << wall << " s\n";
  } catch (const std::exception& e) {
    print_error("export", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_export_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand("export", "Write one skinned walker of the shipped rig (skeleton, body level, "
                                           "weights, a baked walk) as glTF 2.0 binary");
  cmd->add_option("--format", o->format, "Output format (gltf: glTF 2.0 binary, .glb)")->capture_default_str();
  cmd->add_option("--level", o->level, "Body resolution level: 0 (finest) .. 2")->capture_default_str()
      ->check(whole_in(0, 2));
  cmd->add_option("--seconds", o->seconds, "Length of the baked walk")->capture_default_str()
      ->check(finite_in(0.001, 3600));
  cmd->add_option("--fps", o->fps, "Animation keys per second (the walk generator's dt = 1/fps)")
      ->capture_default_str()->check(finite_in(1, 1000));
  cmd->add_option("--seed", o->seed, "Seed of the walker's gait phase and speed")->capture_default_str()
      ->check(whole_in(0, 9007199254740992.0, true));
  cmd->add_flag("--rest", o->rest, "Write the rest pose only, no animation");
  cmd->add_option("--out,-o", o->out, "Output file (.glb)")->required();
  cmd->callback([o, &exit_code] { exit_code = run_export(*o); });
}

}  // namespace strata::cli
