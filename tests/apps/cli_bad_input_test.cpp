// The CLI's side of the bad-input contract, on the real binary: every `strata` subcommand given a bad file exits
// with a non-zero status (never by a signal), writes exactly one line to stderr naming the file, and leaves no
// output file behind.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/temp_dir.h"

namespace {

namespace fs = std::filesystem;

struct Outcome {
  bool signalled = false;
  int status = -1;
  std::string err;  // stderr only
};

// One scratch directory for the test program (CTest runs each test in a program of its own), removed when it exits.
const fs::path& scratch() {
  static const strata::test::TempDir dir("strata_cli_bad");
  return dir.path();
}

Outcome run(const std::string& args) {
  const fs::path err = scratch() / "stderr.txt";
  const std::string cmd = "env -u DISPLAY EGL_LOG_LEVEL=fatal " + std::string(STRATA_BINARY) + " " + args +
                          " >/dev/null 2>" + err.string();
  // system() runs through sh; a child killed by a signal shows as 128 + signal from the shell.
  const int raw = std::system(cmd.c_str());
  Outcome o;
  const int code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  o.signalled = WIFSIGNALED(raw) || code > 128;
  o.status = code;
  std::ifstream in(err);
  o.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return o;
}

void expect_one_line_failure(const std::string& args, const std::string& names) {
  SCOPED_TRACE(args);
  const Outcome o = run(args);
  EXPECT_FALSE(o.signalled) << "killed by a signal; stderr: " << o.err;
  EXPECT_NE(o.status, 0) << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "not one line on stderr: " << o.err;
  EXPECT_NE(o.err.find(names), std::string::npos) << "does not name " << names << ": " << o.err;
}

struct BadFiles {
  fs::path x3d, bvh, obj, glb, mh_dir, missing;
};

const BadFiles& bad_files() {
  static const BadFiles files = [] {
    BadFiles f;
    const fs::path d = scratch();
    f.x3d = d / "nan_centre.x3d";
    std::ofstream(f.x3d) << "<X3D><Scene><HAnimHumanoid name='h'>\n<HAnimJoint name='humanoid_root' center='0 nan 0'/>\n"
                            "</HAnimHumanoid></Scene></X3D>\n";
    f.bvh = d / "channels.bvh";
    std::ofstream(f.bvh) << "HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
                            "MOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0\n0 0\n";
    f.obj = d / "range.obj";
    std::ofstream(f.obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
    // A GLB cut in the middle of its JSON chunk.
    const fs::path seed = fs::path(STRATA_TEST_DATA) / ".." / ".." / "fuzz" / "seeds" / "gltf" / "skinned_triangle.glb";
    std::ifstream in(seed, std::ios::binary);
    std::vector<char> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    bytes.resize(bytes.size() / 2);
    f.glb = d / "cut.glb";
    std::ofstream(f.glb, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.mh_dir = d / "mh";
    fs::create_directories(f.mh_dir);
    std::ofstream(f.mh_dir / "base.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\ng body\nf 1 2 3\n";
    std::ofstream(f.mh_dir / "default.mhskel") << "{\"bones\": {\"root\": {\"parent\": null}}, \"joints\": {";
    std::ofstream(f.mh_dir / "default_weights.mhw") << "{\"weights\": {}}";
    f.missing = d / "does_not_exist.x3d";
    return f;
  }();
  return files;
}

TEST(CliBadInput, InfoOnEveryBadFormat) {
  const BadFiles& f = bad_files();
  expect_one_line_failure("info " + f.x3d.string(), "nan_centre.x3d:2:");
  expect_one_line_failure("info " + f.bvh.string(), "channels.bvh:11: frame 1 has 2 values, expected 3");
  expect_one_line_failure("info " + f.obj.string(), "range.obj:4: f: v index 4 out of range");
  expect_one_line_failure("info " + f.glb.string(), "cut.glb: byte 8:");
  expect_one_line_failure("info " + f.mh_dir.string(), "default.mhskel: invalid JSON");
  expect_one_line_failure("info " + f.missing.string(), "does_not_exist.x3d");
}

TEST(CliBadInput, EverySceneCommandOnABadSkeletonMeshOrCapture) {
  const BadFiles& f = bad_files();
  const fs::path out = scratch() / "out";
  const std::string small = " --walkers 2 --frames 2 --width 32 --height 24 --no-progress --out " + out.string();
  expect_one_line_failure("crowd --skeleton " + f.x3d.string() + small, "nan_centre.x3d:2:");
  expect_one_line_failure("crowd --mesh " + f.glb.string() + small, "cut.glb: byte 8:");
  expect_one_line_failure("crowd --mesh " + f.mh_dir.string() + small, "default.mhskel");
  expect_one_line_failure("crowd --motion " + f.bvh.string() + small, "channels.bvh:11:");
  expect_one_line_failure("crowd --skeleton " + f.missing.string() + small, "does_not_exist.x3d");
  EXPECT_FALSE(fs::exists(out)) << "a failed crowd run created its output directory";
  expect_one_line_failure("bench --frames 2 --skeleton " + f.x3d.string(), "nan_centre.x3d:2:");
  expect_one_line_failure("bench --frames 2 --mesh " + f.glb.string(), "cut.glb");
  expect_one_line_failure("report gait --seconds 1 --skeleton " + f.x3d.string(), "nan_centre.x3d:2:");
  expect_one_line_failure("soak --seconds 2 --warmup 1 --skeleton " + f.x3d.string(), "nan_centre.x3d:2:");
  expect_one_line_failure("soak --seconds 2 --warmup 1 --motion " + f.bvh.string(), "channels.bvh:11:");
  // view needs a display; given a bad file it must still fail with one line (whichever error comes first).
  const Outcome v = run("view --frames 1 --skeleton " + f.x3d.string());
  EXPECT_FALSE(v.signalled) << v.err;
  EXPECT_NE(v.status, 0);
  EXPECT_EQ(std::count(v.err.begin(), v.err.end(), '\n'), 1) << v.err;
}

TEST(CliBadInput, UnwritableOutputIsOneLineAndLeavesNothing) {
  // The JSON goes to a directory that does not exist: one line naming it, and no stray temporary file.
  const fs::path dir = scratch() / "reports";
  fs::create_directories(dir);
  expect_one_line_failure("bench --walkers 1 --frames 1 --level -1 --json " + (dir / "missing" / "b.json").string(),
                          "missing/b.json");
  expect_one_line_failure("report gait --walkers 1 --seconds 0.5 --json " + (dir / "missing" / "g.json").string(),
                          "missing/g.json");
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
