// The command line under abuse, one row per case: the arguments, the exit code the contract gives (README "Exit
// codes": 0 done, 1 input or run-time error, 2 usage error, 130/143 interrupted), a fragment the message must
// hold, and the files that must (or must not) exist afterwards. Every case runs under `timeout`, so a hang is a
// failure rather than a stuck suite, and a death by signal is told apart from an exit. Each row is its own test
// (ctest runs them in parallel); sizes stay tiny so the whole table takes seconds.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// Files every case can name: {in} is this folder.
const fs::path& inputs() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("strata_cli_abuse_in_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    ::mkfifo((d / "pipe.bvh").c_str(), 0644);
    fs::create_symlink(d / "loop_b.x3d", d / "loop_a.x3d");
    fs::create_symlink(d / "loop_a.x3d", d / "loop_b.x3d");
    fs::create_directories(d / "folder.x3d");
    const std::string bvh =
        "HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nEnd Site\n{\nOFFSET 0 1 0\n"
        "}\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0\n0 0 0\n";
    std::ofstream(d / "walk.BVH") << bvh;
    std::ofstream(d / "walk_named.x3d") << bvh;  // BVH content behind an X3D name
    std::ofstream(d / "cube.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(d / "big.bvh") << bvh << std::string(2 * 1024 * 1024, ' ');
    std::ofstream(d / "a_file") << "not a directory\n";
    return d;
  }();
  return dir;
}

struct Case {
  std::string name;  // the test's name
  std::string args;  // {in}: inputs(); {out}: this case's own empty scratch folder
  int exit_code;
  std::string message;                // a fragment of the output (stderr and stdout); empty: anything
  std::vector<std::string> present;   // paths relative to {out} that must exist afterwards
  std::vector<std::string> absent;    // ... and that must not
  std::function<void(const fs::path& out)> before = nullptr;  // prepares {out} (an earlier run, stray files)
  std::function<void(const fs::path& out)> after = nullptr;   // further checks on {out}
};

std::string expand(std::string text, const fs::path& out) {
  for (const auto& [key, value] : {std::pair<std::string, std::string>{"{in}", inputs().string()},
                                   std::pair<std::string, std::string>{"{out}", out.string()}})
    for (std::size_t at; (at = text.find(key)) != std::string::npos;) text.replace(at, key.size(), value);
  return text;
}

struct Outcome {
  int code = -1;        // exit status; -1 when killed by a signal
  bool timed_out = false;
  std::string output;   // stdout and stderr together
  std::string err;      // stderr alone
};

Outcome run_strata(const std::string& args, const fs::path& out) {
  const fs::path log = out.parent_path() / (out.filename().string() + ".stdout");
  const fs::path err = out.parent_path() / (out.filename().string() + ".stderr");
  // `timeout` exits 124 when the limit hits; a signal death shows through the shell as 128 + signal.
  const std::string cmd = "env -u DISPLAY EGL_LOG_LEVEL=fatal timeout -s KILL 60 " + std::string(STRATA_BINARY) +
                          " " + args + " >" + log.string() + " 2>" + err.string() + " </dev/null";
  const int raw = std::system(cmd.c_str());
  Outcome o;
  const int code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  o.timed_out = code == 137 || code == 124;
  o.code = code;
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  o.err = slurp(err);
  o.output = slurp(log) + o.err;
  return o;
}

fs::path case_dir(const std::string& name) {
  static const fs::path root = [] {
    const fs::path d = fs::temp_directory_path() / ("strata_cli_abuse_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return root / name;
}

const std::string kTiny = " --walkers 2 --frames 2 --width 32 --height 24 --no-progress --no-mp4 --table1-frames 0";

std::vector<Case> cases() {
  return {
      // ---- One exit-code contract, one line, `strata <sub>:` ------------------------------------------------
      {"NoCommand", "", 2, "strata: a command is required", {}, {}},
      {"MisspeltCommand", "crwod", 2, "unknown command 'crwod' (did you mean 'crowd'?", {}, {}},
      {"UnknownCommand", "frobnicate", 2, "unknown command 'frobnicate'", {}, {}},
      {"MisspeltReport", "report gaitt", 2, "strata report: unknown command 'gaitt' (did you mean 'gait'?", {}, {}},
      {"ReportWithoutSubcommand", "report", 2, "strata report: a subcommand is required (gait", {}, {}},
      {"UnknownFlag", "crowd --bogus", 2, "strata crowd: The following argument was not expected: --bogus", {}, {}},
      {"MissingFile", "info", 2, "strata info: FILE is required", {}, {}},
      {"Version", "--version", 0, "strata 0.1.0", {}, {}},
      {"Help", "help", 0, "Usage: strata", {}, {}},
      {"HelpOfASubcommand", "help report gait", 0, "Usage: strata report gait", {}, {}},
      {"HelpOfAnUnknownCommand", "help crwod", 2, "strata help: unknown command 'crwod' (did you mean 'crowd'?", {}, {}},
      {"DashDashHelp", "crowd --help", 0, "Usage: strata crowd", {}, {}},
      // ---- Numeric flags: finite, in range, named -------------------------------------------------------------
      {"GaitFpsNan", "report gait --fps nan", 2, "strata report gait: --fps: must be a finite number > 0", {}, {}},
      {"GaitSecondsNan", "report gait --seconds nan", 2, "--seconds: must be a finite number > 0", {}, {}},
      {"BenchFpsNan", "bench --fps nan", 2, "strata bench: --fps: must be a finite number", {}, {}},
      {"SoakFpsNan", "soak --fps nan", 2, "strata soak: --fps: must be a finite number", {}, {}},
      {"SoakSampleEveryTiny", "soak --sample-every 1e-9", 2, "--sample-every: must be a finite number from 0.01", {}, {}},
      {"CrowdMuscleGainNan", "crowd --muscle-gain nan --out {out}", 2, "--muscle-gain: must be a finite number from 0 to 100", {}, {"."}},
      {"CrowdCameraPitchNan", "crowd --camera-pitch nan --out {out}", 2, "--camera-pitch: must be a finite number", {}, {"."}},
      {"CrowdCameraPitchTooSteep", "crowd --camera-pitch 2 --out {out}", 2, "--camera-pitch: must be a finite number from -1.5 to 1.5", {}, {"."}},
      {"CrowdFpsInf", "crowd --fps inf --out {out}", 2, "--fps: must be a finite number > 0 and <= 1000, got 'inf'", {}, {"."}},
      {"CrowdWalkersNotANumber", "crowd --walkers abc --out {out}", 2, "--walkers: must be a whole number from 1 to 10000000, got 'abc'", {}, {"."}},
      {"CrowdWalkersFraction", "crowd --walkers 2.5 --out {out}", 2, "--walkers: must be a whole number", {}, {"."}},
      {"CrowdSeedNegative", "crowd --seed -1 --out {out}", 2, "--seed: must be a whole number from 0", {}, {"."}},
      {"CrowdThreadsNegative", "crowd --threads -3 --out {out}", 2, "--threads: must be a whole number from 0 to 4096", {}, {"."}},
      {"CrowdSpacingZero", "crowd --spacing 0 --out {out}", 2, "--spacing: must be a finite number > 0", {}, {"."}},
      {"CrowdWidthTooLarge", "crowd --width 20000 --out {out}", 2, "--width: must be a whole number from 1 to 16384", {}, {"."}},
      {"ExportFpsNan", "export --fps nan --out {out}/a.glb", 2, "strata export: --fps: must be a finite number", {}, {}},
      {"ExportSeedNegative", "export --seed -1 --out {out}/a.glb", 2, "strata export: --seed:", {}, {}},
      {"ViewFramesNegative", "view --frames -1", 2, "strata view: --frames: must be a whole number", {}, {}},
      {"MaxInputNan", "info {in}/cube.obj --max-input-mb nan", 2, "--max-input-mb: must be a finite number", {}, {}},
      // ---- Inputs that hang or kill a reader -------------------------------------------------------------------
      {"InfoOnADevice", "info /dev/zero", 1, "strata info: /dev/zero: not a regular file (a character device)", {}, {}},
      {"InfoOnAFifo", "info {in}/pipe.bvh", 1, "pipe.bvh: not a regular file (a FIFO)", {}, {}},
      {"InfoOnASymlinkLoop", "info {in}/loop_a.x3d", 1, "loop_a.x3d: symbolic link loop", {}, {}},
      {"InfoOnAFolder", "info {in}/folder.x3d", 1, "folder.x3d: a directory, and not a MakeHuman hm08 folder", {}, {}},
      {"InfoOnAFileAboveTheLimit", "info {in}/big.bvh --max-input-mb 1", 1, "big.bvh: 2.0 MiB is above the input size limit of 1.0 MiB (raise it with --max-input-mb)", {}, {}},
      {"InfoWithTheLimitRaised", "info {in}/big.bvh --max-input-mb 3", 0, "BVH motion capture", {}, {}},
      {"CrowdMotionFromAFifo", "crowd --motion {in}/pipe.bvh" + kTiny + " --out {out}", 1, "strata crowd: --motion: ", {}, {"."}},
      {"CrowdSkeletonLoop", "crowd --skeleton {in}/loop_a.x3d" + kTiny + " --out {out}", 1, "--skeleton: ", {}, {"."}},
      {"SoakMuscleFileDevice", "soak --seconds 2 --warmup 1 --muscles /dev/zero", 1, "strata soak: --muscles: /dev/zero: not a regular file", {}, {}},
      // ---- Formats by content and extension in any case ---------------------------------------------------------
      {"InfoUppercaseBvh", "info {in}/walk.BVH", 0, "BVH motion capture", {}, {}},
      {"InfoBvhBehindAnX3dName", "info {in}/walk_named.x3d", 0, "BVH motion capture", {}, {}},
      {"MeshGivenAnObj", "crowd --mesh {in}/cube.obj" + kTiny + " --out {out}", 1, "--mesh: " , {}, {"."}},
      {"MeshGivenABvh", "crowd --mesh {in}/walk.BVH" + kTiny + " --out {out}", 1, "which has no skinned body", {}, {"."}},
  };
}

class CliAbuse : public testing::TestWithParam<Case> {};

TEST_P(CliAbuse, ExitCodeMessageAndFiles) {
  const Case& c = GetParam();
  const fs::path out = case_dir(c.name);
  fs::remove_all(out);
  if (c.before) c.before(out);
  const std::string args = expand(c.args, out);
  SCOPED_TRACE("strata " + args);
  const Outcome o = run_strata(args, out);
  ASSERT_FALSE(o.timed_out) << "hung (killed after 60 s); output: " << o.output;
  ASSERT_NE(o.code, -1) << "killed by a signal; output: " << o.output;
  EXPECT_EQ(o.code, c.exit_code) << o.output;
  if (!c.message.empty()) EXPECT_NE(o.output.find(c.message), std::string::npos) << "no '" << c.message << "' in: " << o.output;
  if (c.exit_code == 1 || c.exit_code == 2) {
    // A failure is one line on stderr, prefixed with the command.
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "not one line: " << o.err;
    EXPECT_EQ(o.err.rfind("strata", 0), 0u) << o.err;
  }
  for (const std::string& p : c.present) EXPECT_TRUE(fs::exists(out / p)) << p << " missing";
  for (const std::string& p : c.absent) EXPECT_FALSE(fs::exists(out / p)) << p << " present";
  if (c.after) c.after(out);
}

INSTANTIATE_TEST_SUITE_P(Table, CliAbuse, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<Case>& info) { return info.param.name; });

}  // namespace
