// strata: the engine's command-line front end. See docs/commands.md for the commands and their outputs.
#include <CLI/CLI.hpp>

#include "apps/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"Strata: animate and render crowds of layered H-Anim humanoids"};
  app.require_subcommand(1);
  int exit_code = 0;
  strata::cli::add_info_command(app, exit_code);
  strata::cli::add_crowd_command(app, exit_code);
  strata::cli::add_view_command(app, exit_code);
  strata::cli::add_report_command(app, exit_code);
  strata::cli::add_bench_command(app, exit_code);
  strata::cli::add_export_command(app, exit_code);
  strata::cli::add_soak_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return exit_code;
}
