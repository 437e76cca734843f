#pragma once
// What every `strata` subcommand shares beyond its scene flags: the exit-code contract, checked numeric flags,
// output paths checked before a run, one-line error text, SIGINT/SIGTERM as a request to stop, and the progress
// line. Kept in one place so that a subcommand cannot drift from the contract the README documents.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "components/detail_level.h"
#include "render/crowd_renderer.h"
#include "render/gl_context.h"

namespace strata::cli {

// The exit-code contract (README "Exit codes"). 1 covers bad input files and failures at run time (an unwritable
// output, ffmpeg failing, a soak that was not flat); 2 covers a command line that cannot run at all, decided
// before any work. A run stopped by a signal exits 128 + the signal, as a shell reports it: 130 for SIGINT, 143
// for SIGTERM.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// ---- Numeric flags ---------------------------------------------------------------------------------------------
// One validator per numeric flag, run by CLI11 on the text before conversion, so the message names the flag
// ("--fps: must be a finite number > 0, got 'nan'"). CLI11's own Range and PositiveNumber were rejected: NaN
// passes both (every comparison with NaN is false, which is how `--fps nan` hung report gait), "abc" is
// reported as out of range, and an unsigned option takes "-1" and wraps it to 2^64-1.
struct NumberRule {
  double lo = -std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::max();
  bool lo_open = false;  // lo itself excluded (> lo rather than >= lo)
  bool integer = false;  // whole numbers only
  bool non_negative_integer = false;  // an unsigned flag: "-1" is refused, not wrapped
};
CLI::Validator number_check(const NumberRule& rule);
// Finite, in [lo, hi].
inline CLI::Validator finite_in(double lo, double hi) { return number_check({lo, hi, false, false, false}); }
// Finite, > 0 and <= hi.
inline CLI::Validator positive_up_to(double hi) { return number_check({0.0, hi, true, false, false}); }
// A whole number in [lo, hi]; `is_unsigned` for flags stored unsigned.
inline CLI::Validator whole_in(double lo, double hi, bool is_unsigned = false) {
  return number_check({lo, hi, false, true, is_unsigned});
}
// Parses `text` as a rule would; empty on success, else the reason (without the flag name).
std::string check_number(const std::string& text, const NumberRule& rule);

// ---- Output paths ----------------------------------------------------------------------------------------------
// Empty when `path` can be written as a file (the parent directory exists and is writable, the path is not a
// directory or a device); otherwise the reason, naming `flag` and the path. Checked before a run starts, so an
// hour-long soak does not fail at its last step.
std::string check_output_file(std::string_view flag, const std::filesystem::path& path);
// The same for an output directory: it exists as a writable directory, or the nearest existing ancestor is one
// (so it can be created).
std::string check_output_dir(std::string_view flag, const std::filesystem::path& path);

// One output a command will write: the flag that names it, the path (empty: not asked for), a directory or a file.
struct OutputPath {
  std::string_view flag;
  std::filesystem::path path;
  bool directory = false;
};
// Checks every output with check_output_file / check_output_dir; prints the first failure as "strata <command>:
// ..." and returns false.
bool check_outputs(std::string_view command, std::initializer_list<OutputPath> outputs);

// Under mpirun (apps/crowd_distributed.h): --rebalance-seconds (simulated seconds between recutting the ranks'
// slabs) and --mpi-timeout (seconds a rank may go without progress before the job is stopped).
void add_mpi_options(CLI::App& cmd, double& rebalance_seconds, double& timeout_seconds);

// ---- Render targets ---------------------------------------------------------------------------------------------
// Empty when a width x height image fits the live context (renderbuffer and viewport limits) and the memory its
// multisampled targets and read-back need (with up to 4 samples, as the renderer takes); otherwise the reason,
// naming --width/--height and the limit.
std::string check_render_size(const GlContext::Limits& limits, int width, int height);
// The one-line reason when the renderer could not make a width x height target although the limits allowed it.
std::string render_target_error(int width, int height, const GlContext::Limits& limits, const std::exception& e);
// The renderer for --width/--height, made before any work (crowd, soak --render, bench --render): the size is
// checked against the context's limits, then the render target is built, so a size the driver refuses fails at
// once with the flags named. Null, with `error` set, on failure.
// --quality low|high on `cmd` (render/render_options.h RenderQuality), with `quality`'s value as the default.
void add_quality_option(CLI::App& cmd, RenderQuality& quality);
// --renderer gl|embree (render/render_options.h RenderBackend) and its name in summaries.
void add_renderer_option(CLI::App& cmd, RenderBackend& backend);
const char* renderer_name(RenderBackend backend);
// Why `level` or the overlay cannot be drawn by `backend` (the ray tracer draws meshes only); empty when they can.
std::string check_renderer_level(RenderBackend backend, const DetailLevel& level, bool skeleton_overlay);
const char* quality_name(RenderQuality quality);
std::unique_ptr<CrowdRenderer> make_checked_renderer(GlContext& context, int width, int height, std::string& error);

// ---- Errors ----------------------------------------------------------------------------------------------------
// The one-line text for an exception that ended a command: std::bad_alloc becomes an out-of-memory message that
// says what to change; line breaks are folded so the message stays one line.
std::string error_text(const std::exception& e);
// One line to stderr: "strata <command>: <message>".
void print_error(std::string_view command, std::string_view message);
// Under mpirun every rank runs the same command line, and an error in it is every rank's: only rank 0 prints
// (print_error stays silent on the others). launcher_rank()/launcher_size() read the launcher's environment
// (OpenMPI's, or PMI's), without MPI: -1 and 0 outside mpirun.
int launcher_rank();
int launcher_size();

// ---- Memory ----------------------------------------------------------------------------------------------------
// Bytes this process may still allocate: the least of MemAvailable, the cgroup's memory.max minus its current
// use, and RLIMIT_AS minus the address space in use; 0 when none can be read.
std::uint64_t available_memory_bytes();
// Empty when `needed` bytes fit in what is available (or nothing is known), else a message for `what`.
std::string check_memory(std::uint64_t needed, std::string_view what);
// This process's resident set now, KiB (-1 when /proc cannot be read): statm's second field is resident pages.
// /proc rather than getrusage, whose ru_maxrss is a high-water mark and cannot show memory being given back.
long resident_kib();

// ---- Signals ---------------------------------------------------------------------------------------------------
// SIGINT and SIGTERM set a flag that the frame loops read between frames; the run then writes what it has
// (marked "interrupted") and exits 128 + signal. A second signal ends the process at once (default action), so a
// stuck run can still be stopped. Ending at once on the first signal was rejected: an hour of soak samples or a
// half-rendered crowd would leave no summary.
void install_interrupt_handlers();
// The signal received (SIGINT, SIGTERM) or 0.
int interrupt_signal();
inline bool interrupted() { return interrupt_signal() != 0; }
// 128 + the signal received.
int interrupted_exit_code();

// ---- Progress --------------------------------------------------------------------------------------------------
// One line that rewrites itself with done/total, rate and ETA, cut to the terminal's width so it never wraps;
// only when stderr is a terminal, so logs and CI output stay clean.
class ProgressLine {
 public:
  ProgressLine(std::string unit, bool enabled);
  bool enabled() const { return enabled_; }
  // done of total units at `rate` units per second; the ETA follows from them. A total of 0 shows no bar.
  void update(double done, double total, double rate, std::string_view extra = {});
  // Ends the line (a newline) if anything was drawn.
  void finish();

 private:
  std::string unit_;
  bool enabled_;
  bool drawn_ = false;
};

// Whether stderr is a terminal (status lines with '\r' only then).
bool stderr_is_terminal();

}  // namespace strata::cli
