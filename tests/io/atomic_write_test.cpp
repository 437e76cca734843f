// Every writer (PNG frames, the Chrome trace and CSV, JSON reports, plain files) goes through io/atomic_file.h: a
// write that fails part-way leaves no file, and an existing file untouched. The failure is real, not mocked: a
// file-size limit (RLIMIT_FSIZE) makes the kernel refuse writes past a few hundred bytes with EFBIG.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

using test::TempDir;

std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  return names;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs `write` with files limited to `limit` bytes (SIGXFSZ ignored, so the write fails with EFBIG instead of
// killing the test), then restores the limit. Returns whether `write` threw.
bool throws_under_file_size_limit(rlim_t limit, const std::function<void()>& write) {
  rlimit old{};
  getrlimit(RLIMIT_FSIZE, &old);
  const auto old_handler = signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = limit;
  setrlimit(RLIMIT_FSIZE, &small);
  bool threw = false;
  try {
    write();
  } catch (const std::exception&) {
    threw = true;
  }
  setrlimit(RLIMIT_FSIZE, &old);
  signal(SIGXFSZ, old_handler);
  return threw;
}

std::vector<std::uint8_t> noise(int w, int h) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 4);
  for (auto& p : px) p = static_cast<std::uint8_t>(rng());
  return px;
}

void fill(Profiler& p) {
  for (int f = 0; f < 50; ++f) {
    p.begin_frame();
    { STRATA_PROFILE_SCOPE(p, "a_system_with_a_long_name_to_fill_the_file"); }
    p.end_frame();
  }
}

TEST(AtomicWrite, SuccessLeavesOnlyTheTarget) {
  const TempDir tmp("strata_atomic_ok");
  const fs::path& dir = tmp.path();
  write_file_atomically(dir / "a.json", "{}\n");
  write_image(dir / "f.png", 16, 8, 4, noise(16, 8));
  Profiler p(120, true);
  fill(p);
  p.write_chrome_trace(dir / "profile.json");
  p.write_csv(dir / "profile.csv");
  std::vector<std::string> names = entries(dir);
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"a.json", "f.png", "profile.csv", "profile.json"}));
  EXPECT_EQ(read_text(dir / "a.json"), "{}\n");
  // The PNG is whole: signature first, IEND chunk (and its CRC) last.
  const std::string png = read_text(dir / "f.png");
  ASSERT_GT(png.size(), 20u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png.substr(png.size() - 8), std::string("IEND\xae\x42\x60\x82", 8));
}

TEST(AtomicWrite, FailedWritesLeaveNoFileBehind) {
  const TempDir tmp("strata_atomic_fail");
  const fs::path& dir = tmp.path();
  const std::string big(100000, 'x');
  Profiler p(120, true);
  fill(p);
  // Each writer throws, and the directory stays empty: no truncated target, no temporary file.
  EXPECT_TRUE(throws_under_file_size_limit(512, [&] { write_file_atomically(dir / "report.json", big); }));
  EXPECT_TRUE(throws_under_file_size_limit(512, [&] { write_image(dir / "frame_0000.png", 256, 256, 4, noise(256, 256)); }));
  EXPECT_TRUE(throws_under_file_size_limit(512, [&] { p.write_chrome_trace(dir / "profile.json"); }));
  EXPECT_TRUE(throws_under_file_size_limit(64, [&] { p.write_csv(dir / "profile.csv"); }));
  EXPECT_TRUE(entries(dir).empty()) << entries(dir).size() << " files left, first: " << entries(dir).front();
}

TEST(AtomicWrite, FailedWriteKeepsThePreviousFile) {
  const TempDir tmp("strata_atomic_keep");
  const fs::path& dir = tmp.path();
  write_file_atomically(dir / "summary.json", "old\n");
  EXPECT_TRUE(throws_under_file_size_limit(256, [&] { write_file_atomically(dir / "summary.json", std::string(5000, 'n')); }));
  EXPECT_EQ(read_text(dir / "summary.json"), "old\n");
  EXPECT_EQ(entries(dir), (std::vector<std::string>{"summary.json"}));
}

TEST(AtomicWrite, UncommittedFileIsRemovedAndMissingDirectoryNamesThePath) {
  const TempDir tmp("strata_atomic_abandon");
  const fs::path& dir = tmp.path();
  {
    AtomicFile f(dir / "x.bin");
    std::ofstream(f.temp_path()) << "partial";
    EXPECT_TRUE(fs::exists(f.temp_path()));
    EXPECT_EQ(f.temp_path().parent_path(), dir);  // same directory: the rename cannot cross file systems
  }  // destroyed without commit(), e.g. by an exception
  EXPECT_TRUE(entries(dir).empty());
  try {
    write_file_atomically(dir / "no_such_dir" / "x.json", "{}");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir/x.json"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
