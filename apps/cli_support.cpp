#include "apps/cli_support.h"

#include <sys/ioctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>

namespace strata::cli {
namespace fs = std::filesystem;

namespace {

std::string format_bound(double v) {
  if (v == std::floor(v) && std::fabs(v) < 1e18) return std::to_string(static_cast<long long>(v));
  std::ostringstream s;
  s.precision(15);
  s << v;
  return s.str();
}

std::string describe_rule(const NumberRule& r) {
  const bool has_lo = r.lo > -std::numeric_limits<double>::max();
  const bool has_hi = r.hi < std::numeric_limits<double>::max();
  std::string what = r.integer ? "a whole number" : "a finite number";
  if (has_lo && has_hi && !r.lo_open) return what + " from " + format_bound(r.lo) + " to " + format_bound(r.hi);
  if (has_lo && has_hi) return what + " > " + format_bound(r.lo) + " and <= " + format_bound(r.hi);
  if (has_lo) return what + (r.lo_open ? " > " : " >= ") + format_bound(r.lo);
  if (has_hi) return what + " <= " + format_bound(r.hi);
  return what;
}

}  // namespace

std::string check_number(const std::string& text, const NumberRule& rule) {
  const std::string expected = "must be " + describe_rule(rule) + ", got '" + text + "'";
  double value = 0.0;
  if (rule.integer) {
    // from_chars takes the whole text or nothing; strtoll would accept "12abc" and "1e3" would become 1.
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (first != last && *first == '+') ++first;
    long long parsed = 0;
    auto [end, ec] = std::from_chars(first, last, parsed);
    if (ec == std::errc::result_out_of_range) return expected;
    if (ec != std::errc() || end != last || first == last) return expected;
    if (rule.non_negative_integer && parsed < 0) return expected;
    value = static_cast<double>(parsed);
  } else {
    errno = 0;
    char* end = nullptr;
    value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size()) return expected;
    if (!std::isfinite(value)) return expected;
  }
  if (value < rule.lo || value > rule.hi || (rule.lo_open && value <= rule.lo)) return expected;
  return {};
}

CLI::Validator number_check(const NumberRule& rule) {
  return CLI::Validator([rule](std::string& text) { return check_number(text, rule); }, describe_rule(rule));
}

std::string check_output_file(std::string_view flag, const fs::path& path) {
  const std::string named = std::string(flag) + ": " + path.string();
  if (path.empty()) return std::string(flag) + ": empty path";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (fs::is_directory(status)) return named + " is a directory; give a file name";
  if (fs::exists(status) && !fs::is_regular_file(status)) return named + " is not a regular file";
  fs::path parent = path.parent_path();
  if (parent.empty()) parent = ".";
  const fs::file_status parent_status = fs::status(parent, ec);
  if (!fs::exists(parent_status)) return named + ": directory " + parent.string() + " does not exist";
  if (!fs::is_directory(parent_status)) return named + ": " + parent.string() + " is not a directory";
  if (::access(parent.c_str(), W_OK | X_OK) != 0)
    return named + ": cannot write in " + parent.string() + ": " + std::strerror(errno);
  return {};
}

std::string check_output_dir(std::string_view flag, const fs::path& path) {
  const std::string named = std::string(flag) + ": " + path.string();
  if (path.empty()) return std::string(flag) + ": empty path";
  std::error_code ec;
  fs::path at = path;
  // The nearest existing ancestor decides: it must be a directory we may create entries in.
  while (!at.empty() && !fs::exists(fs::symlink_status(at, ec))) {
    const fs::path up = at.parent_path();
    if (up == at) break;
    at = up;
  }
  if (at.empty()) at = ".";
  const fs::file_status status = fs::status(at, ec);
  if (!fs::is_directory(status))
    return named + (at == path ? " is not a directory" : ": " + at.string() + " is not a directory");
  if (::access(at.c_str(), W_OK | X_OK) != 0)
    return named + ": cannot write in " + at.string() + ": " + std::strerror(errno);
  return {};
}

bool check_outputs(std::string_view command, std::initializer_list<OutputPath> outputs) {
  for (const OutputPath& o : outputs) {
    if (o.path.empty()) continue;
    const std::string why = o.directory ? check_output_dir(o.flag, o.path) : check_output_file(o.flag, o.path);
    if (!why.empty()) {
      print_error(command, why);
      return false;
    }
  }
  return true;
}

std::string check_render_size(const GlContext::Limits& limits, int width, int height) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const int side = std::max(width, height);
  if (limits.max_renderbuffer_size > 0 && side > limits.max_renderbuffer_size)
    return "--width/--height: " + size + " is above this GL's largest render target (" +
           std::to_string(limits.max_renderbuffer_size) + " pixels a side)";
  if ((limits.max_viewport_width > 0 && width > limits.max_viewport_width) ||
      (limits.max_viewport_height > 0 && height > limits.max_viewport_height))
    return "--width/--height: " + size + " is above this GL's largest viewport (" +
           std::to_string(limits.max_viewport_width) + "x" + std::to_string(limits.max_viewport_height) + ")";
  // Multisampled colour + depth (4 bytes each per sample), the resolved colour, and the RGBA read-back; on a
  // software renderer (llvmpipe) all of it is system memory.
  const std::uint64_t samples = static_cast<std::uint64_t>(std::clamp(limits.max_samples, 1, 4));
  const std::uint64_t pixels = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  const std::string memory = check_memory(pixels * (samples * 8 + 8), "a " + size + " render target");
  return memory.empty() ? std::string{} : "--width/--height: " + memory;
}

std::string render_target_error(int width, int height, const GlContext::Limits& limits, const std::exception& e) {
  const double samples = std::clamp(limits.max_samples, 1, 4);
  char size[64];
  std::snprintf(size, sizeof size, "%.1f GiB", double(width) * double(height) * samples * 4.0 / (1024.0 * 1024.0 * 1024.0));
  return "--width/--height: this GL cannot make a " + std::to_string(width) + "x" + std::to_string(height) +
         " render target (" + std::to_string(static_cast<int>(samples)) + " samples, " + size +
         " per attachment); use a smaller size (" + error_text(e) + ")";
}

std::string error_text(const std::exception& e) {
  std::string text;
  if (dynamic_cast<const std::bad_alloc*>(&e))
    text = "out of memory (the allocation failed); use fewer --walkers or a coarser --level";
  else
    text = e.what();
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

namespace {
int launcher_env(std::initializer_list<const char*> names, int absent) {
  for (const char* name : names)
    if (const char* v = std::getenv(name)) {
      char* end = nullptr;
      const long n = std::strtol(v, &end, 10);
      if (end != v && n >= 0 && n < 1 << 24) return static_cast<int>(n);
    }
  return absent;
}
}  // namespace

int launcher_rank() { return launcher_env({"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}, -1); }
int launcher_size() { return launcher_env({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}, 0); }

void print_error(std::string_view command, std::string_view message) {
  if (launcher_rank() > 0) return;
  std::string line = "strata";
  if (!command.empty()) line.append(" ").append(command);
  line.append(": ").append(message);
  std::replace(line.begin(), line.end(), '\n', ' ');
  std::cerr << line << "\n";
}

std::uint64_t available_memory_bytes() {
  std::uint64_t best = 0;
  auto take = [&best](std::uint64_t v) {
    if (v > 0 && (best == 0 || v < best)) best = v;
  };
  {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    std::uint64_t kib = 0;
    std::string unit;
    while (meminfo >> key >> kib >> unit)
      if (key == "MemAvailable:") take(kib * 1024);
  }
  {
    // cgroup v2: the limit of this process's group less what it uses already.
    std::ifstream max("/sys/fs/cgroup/memory.max"), current("/sys/fs/cgroup/memory.current");
    std::string limit;
    std::uint64_t used = 0;
    if (max >> limit && limit != "max" && current >> used) {
      const std::uint64_t l = std::strtoull(limit.c_str(), nullptr, 10);
      if (l > used) take(l - used);
      else take(1);
    }
  }
  {
    rlimit as{};
    if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
      std::ifstream statm("/proc/self/statm");
      std::uint64_t pages = 0;
      statm >> pages;
      const std::uint64_t used = pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
      take(as.rlim_cur > used ? as.rlim_cur - used : 1);
    }
  }
  return best;
}

long resident_kib() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return -1;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

std::string check_memory(std::uint64_t needed, std::string_view what) {
  const std::uint64_t available = available_memory_bytes();
  if (available == 0 || needed <= available) return {};
  auto gib = [](std::uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GiB", static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0));
    return std::string(text);
  };
  return std::string(what) + " needs about " + gib(needed) + " of memory, " + gib(available) + " is available";
}

const char* quality_name(RenderQuality quality) { return quality == RenderQuality::High ? "high" : "low"; }

void add_mpi_options(CLI::App& cmd, double& rebalance_seconds, double& timeout_seconds) {
  cmd.add_option("--rebalance-seconds", rebalance_seconds,
                 "Under mpirun: simulated seconds between recutting the ranks' slabs by walker density")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 3600.0));
  cmd.add_option("--mpi-timeout", timeout_seconds,
                 "Under mpirun: seconds a rank may go without progress before the job is stopped (0: never)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 86400.0));
}

void add_quality_option(CLI::App& cmd, RenderQuality& quality) {
  const CLI::Validator low_or_high(
      [](std::string& value) -> std::string {
        if (value == "low" || value == "high") return {};
        return "must be low or high, got '" + value + "'";
      },
      "low|high");
  cmd.add_option_function<std::string>(
         "--quality", [&quality](const std::string& value) { quality = value == "high" ? RenderQuality::High : RenderQuality::Low; },
         "Rendering: high (sun with shadows, ambient occlusion, skin material, each walker in its own colours, "
         "tone mapped) or low (one headlight, no shadows: what the render benchmarks time)")
      ->check(low_or_high)->default_str(quality_name(quality));
}

const char* renderer_name(RenderBackend backend) { return backend == RenderBackend::RayTraced ? "embree" : "gl"; }

void add_renderer_option(CLI::App& cmd, RenderBackend& backend) {
  const CLI::Validator gl_or_embree(
      [](std::string& value) -> std::string {
        if (value == "gl" || value == "embree") return {};
        return "must be gl or embree, got '" + value + "'";
      },
      "gl|embree");
  cmd.add_option_function<std::string>(
         "--renderer",
         [&backend](const std::string& value) { backend = value == "embree" ? RenderBackend::RayTraced : RenderBackend::Gl; },
         "Who draws the frames: gl (the GL passes, 4x MSAA) or embree (the CPU ray tracer: skinned meshes, props and "
         "ground lit as --quality high, one ray per pixel; much faster for large headless crowds; needs a mesh "
         "--level, not auto or impostor)")
      ->check(gl_or_embree)->default_str(renderer_name(backend));
}

std::string check_renderer_level(RenderBackend backend, const DetailLevel& level, bool skeleton_overlay) {
  if (backend != RenderBackend::RayTraced) return {};
  if (level.is_none() || level.is_automatic() || level.is_impostor())
    return "--renderer embree traces skinned meshes: use --level 0, 1, 2 or S1-S3";
  if (skeleton_overlay) return "--renderer embree draws no skeletons: drop --skeleton-overlay or use --renderer gl";
  return {};
}

std::unique_ptr<CrowdRenderer> make_checked_renderer(GlContext& context, int width, int height, std::string& error) {
  error = check_render_size(context.limits(), width, height);
  if (!error.empty()) return nullptr;
  try {
    return std::make_unique<CrowdRenderer>(width, height);
  } catch (const std::exception& e) {
    error = render_target_error(width, height, context.limits(), e);
    return nullptr;
  }
}

namespace {
std::atomic<int> g_signal{0};

extern "C" void on_interrupt(int sig) {
  int expected = 0;
  if (!g_signal.compare_exchange_strong(expected, sig)) {
    // The second signal: stop now, as the default action would have the first time.
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}
}  // namespace

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // a write interrupted mid-frame resumes; the loop checks the flag between frames
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

int interrupt_signal() { return g_signal.load(std::memory_order_relaxed); }

int interrupted_exit_code() { return 128 + interrupt_signal(); }

bool stderr_is_terminal() { return ::isatty(::fileno(stderr)) != 0; }

ProgressLine::ProgressLine(std::string unit, bool enabled)
    : unit_(std::move(unit)), enabled_(enabled && stderr_is_terminal()) {}

void ProgressLine::update(double done, double total, double rate, std::string_view extra) {
  if (!enabled_) return;
  winsize ws{};
  int columns = 80;
  if (::ioctl(::fileno(stderr), TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) columns = ws.ws_col;
  char counts[96], eta[48] = "";
  std::snprintf(counts, sizeof counts, " %.0f/%.0f %s %.1f/s", done, total, unit_.c_str(), rate);
  if (total > 0 && rate > 0 && done < total) {
    const long seconds = std::lround((total - done) / rate);
    std::snprintf(eta, sizeof eta, " ETA %ld:%02ld", seconds / 60, seconds % 60);
  }
  std::string tail = std::string(counts) + eta;
  if (!extra.empty()) tail.append(" ").append(extra);
  // The bar takes what the numbers leave, at most 30 columns; one column is kept free so the cursor never wraps.
  const int room = columns - 1 - static_cast<int>(tail.size()) - 2;
  std::string line;
  if (total > 0 && room >= 5) {
    const int width = std::min(room, 30);
    const int filled = static_cast<int>(width * std::clamp(done / total, 0.0, 1.0));
    line = "[" + std::string(static_cast<std::size_t>(filled), '#') +
           std::string(static_cast<std::size_t>(width - filled), ' ') + "]";
  }
  line += tail;
  if (static_cast<int>(line.size()) > columns - 1) line.resize(static_cast<std::size_t>(std::max(columns - 1, 0)));
  std::fprintf(stderr, "\r%s\033[K", line.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::finish() {
  if (!drawn_) return;
  std::fputc('\n', stderr);
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace strata::cli
