#pragma once
// A scratch directory for tests: created empty, with a unique name (mkdtemp), under
// std::filesystem::temp_directory_path() (so $TMPDIR is honoured), and removed with everything in it when the
// object goes out of scope, whether the test passed or failed (a failed ASSERT_* returns, an exception unwinds).
// Every test that writes files writes them inside one of these; nothing is left in the temporary directory.
//
//   const strata::test::TempDir tmp("strata_cli_test");
//   run("crowd --out " + (tmp / "crowd").string());
#include <stdlib.h>  // mkdtemp, setenv, unsetenv

#include <cstdlib>

#include <cerrno>
#include <filesystem>
#include <string>
#include <system_error>

namespace strata::test {

class TempDir {
 public:
  // The directory is <temp>/<prefix>_XXXXXX; the prefix says which test made it, should one survive a crash.
  explicit TempDir(const std::string& prefix = "strata_test") {
    std::string name = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    if (!::mkdtemp(name.data())) throw std::system_error(errno, std::generic_category(), "mkdtemp " + name);
    path_ = name;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Points the body cache (rig/body_cache.h body_cache_directory) at `dir` for the object's life, with the cache on
// whatever STRATA_NO_BODY_CACHE said; both variables are restored afterwards.
class ScopedBodyCacheDir {
 public:
  explicit ScopedBodyCacheDir(const std::filesystem::path& dir) {
    const char* xdg = std::getenv("XDG_CACHE_HOME");
    const char* off = std::getenv("STRATA_NO_BODY_CACHE");
    had_xdg_ = xdg != nullptr, had_off_ = off != nullptr;
    xdg_ = xdg ? xdg : "", off_ = off ? off : "";
    ::setenv("XDG_CACHE_HOME", dir.c_str(), 1);
    ::unsetenv("STRATA_NO_BODY_CACHE");
  }
  ~ScopedBodyCacheDir() {
    if (had_xdg_) ::setenv("XDG_CACHE_HOME", xdg_.c_str(), 1); else ::unsetenv("XDG_CACHE_HOME");
    if (had_off_) ::setenv("STRATA_NO_BODY_CACHE", off_.c_str(), 1);
  }
  ScopedBodyCacheDir(const ScopedBodyCacheDir&) = delete;
  ScopedBodyCacheDir& operator=(const ScopedBodyCacheDir&) = delete;

 private:
  bool had_xdg_ = false, had_off_ = false;
  std::string xdg_, off_;
};

}  // namespace strata::test
