#pragma once
// Subcommands of the `strata` executable. Each file registers one subcommand on the CLI11 app; the callback
// stores its exit status in `exit_code`. Errors are one line on stderr ("strata <cmd>: reason") and a non-zero
// status, never a stack trace.
namespace CLI {
class App;
}

namespace strata::cli {

void add_info_command(CLI::App& app, int& exit_code);
void add_crowd_command(CLI::App& app, int& exit_code);
void add_view_command(CLI::App& app, int& exit_code);
void add_report_command(CLI::App& app, int& exit_code);
void add_bench_command(CLI::App& app, int& exit_code);
void add_soak_command(CLI::App& app, int& exit_code);   // apps/cmd_soak.cpp
void add_export_command(CLI::App& app, int& exit_code);   // `strata export`, apps/cmd_export.cpp
void add_skin_report(CLI::App& report, int& exit_code);    // `strata report skin`, apps/report_skin.cpp
void add_muscle_report(CLI::App& report, int& exit_code);  // `strata report muscle`, apps/report_muscle.cpp
void add_subdiv_report(CLI::App& report, int& exit_code);  // `strata report subdiv`, apps/report_subdiv.cpp
void add_lod_report(CLI::App& report, int& exit_code);     // `strata report lod`, apps/report_lod.cpp
void add_crowd_report(CLI::App& report, int& exit_code);   // `strata report crowd`, apps/report_crowd.cpp
void add_retarget_report(CLI::App& report, int& exit_code);  // `strata report retarget`, apps/report_retarget.cpp

}  // namespace strata::cli
