// strata view: TEMPORARY registration while the GLFW window class is being written (replaced this session).
#include <CLI/CLI.hpp>

#include <iostream>

#include "apps/commands.h"

namespace strata::cli {
void add_view_command(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("view", "Open the crowd in a window");
  cmd->callback([&exit_code] {
    std::cerr << "strata view: not built yet\n";
    exit_code = 1;
  });
}
}  // namespace strata::cli
