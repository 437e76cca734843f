#pragma once
// Running the real `strata` binary from a test (STRATA_BINARY, set by tests/CMakeLists.txt): stdout and stderr
// together, and the exit status (-1 when it did not exit normally, e.g. by a signal). Shared by every test that
// drives the command line.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace strata::test {

struct CliResult {
  int status = -1;
  std::string out;  // stdout and stderr together
};

// `env_assignments` ("NAME=value ...") go before the binary. DISPLAY is unset: headless rendering must not need an
// X server.
inline CliResult run_strata_once(const std::string& cmd) {
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// In the sanitizer build, LeakSanitizer's own stop-the-world tracer sometimes crashes at exit ("Tracer caught
// signal 11" then "LeakSanitizer has encountered a fatal error"; clang 14's runtime, seen about once per suite run
// in a different GL test each time, after the command itself had succeeded). That is the checker failing, not
// the command: such a run is repeated once. A leak LeakSanitizer does report ("detected memory leaks") is not
// retried, nor is any other failure.
inline bool sanitizer_runtime_crashed(const CliResult& r) {
  return r.out.find("LeakSanitizer has encountered a fatal error") != std::string::npos &&
         r.out.find("Tracer caught signal") != std::string::npos;
}

inline CliResult run_strata(const std::string& args, const std::string& env_assignments = "") {
  const std::string cmd = "env -u DISPLAY " + env_assignments + " " + std::string(STRATA_BINARY) + " " + args + " 2>&1";
  CliResult r = run_strata_once(cmd);
  if (sanitizer_runtime_crashed(r)) r = run_strata_once(cmd);
  return r;
}

}  // namespace strata::test
