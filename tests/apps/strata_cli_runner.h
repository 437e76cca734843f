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
inline CliResult run_strata(const std::string& args, const std::string& env_assignments = "") {
  const std::string cmd = "env -u DISPLAY " + env_assignments + " " + std::string(STRATA_BINARY) + " " + args + " 2>&1";
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

}  // namespace strata::test
