// The command line under abuse, one row per case: the arguments, the exit code the contract gives (README "Exit
// codes": 0 done, 1 input or run-time error, 2 usage error, 130/143 interrupted), a fragment the message must
// hold, and the files that must (or must not) exist afterwards. Every case runs under `timeout`, so a hang is a
// failure rather than a stuck suite, and a death by signal is told apart from an exit. Each row is its own test
// (ctest runs them in parallel); sizes stay tiny so the whole table takes seconds.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

// Rows leave their trailing fields (signal, setup, checks) to the defaults on purpose: one line per ordinary case.
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

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
#include <thread>
#include <tuple>
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
    std::string bvh =
        "HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nEnd Site\n{\nOFFSET 0 1 0\n"
        "}\n}\nMOTION\nFrames: 20\nFrame Time: 0.1\n";
    for (int f = 0; f < 20; ++f) bvh += "0 0 0\n";
    std::ofstream(d / "walk.BVH") << bvh;
    std::ofstream(d / "walk_named.x3d") << bvh;  // BVH content behind an X3D name
    std::ofstream(d / "cube.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(d / "big.bvh") << bvh << std::string(2 * 1024 * 1024, ' ');
    std::ofstream(d / "a_file") << "not a directory\n";
    fs::copy_file(fs::path(STRATA_TEST_DATA) / ".." / ".." / "fuzz" / "seeds" / "gltf" / "skinned_triangle.glb",
                  d / "MAN.GLB");
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
  int signal = 0;            // sent once `signal_when` exists under {out} (or after 5 s when empty: long enough for a loaded machine to start the run and take a few samples)
  std::string signal_when;
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

Outcome run_strata(const std::string& args, const fs::path& out, int signal = 0, const std::string& when = "") {
  const fs::path log = out.parent_path() / (out.filename().string() + ".stdout");
  const fs::path err = out.parent_path() / (out.filename().string() + ".stderr");
  // `timeout` exits 124 when the limit hits; a signal death shows through the shell as 128 + signal.
  // --foreground: without it timeout makes a process group of its own and, given SIGINT, sends it to the command
  // and then to the whole group, so strata sees it twice and (rightly) takes the second as "stop now".
  std::string cmd = "env -u DISPLAY EGL_LOG_LEVEL=fatal timeout --foreground -s KILL 60 " +
                    std::string(STRATA_BINARY) + " " + args + " >" + log.string() + " 2>" + err.string() + " </dev/null";
  if (signal) {
    // In the background, signalled once it has written `when`; `wait` gives 128 + signal both for an exit with
    // that code and for a death by it, so the rows also check the "interrupted" outputs a death could not write.
    const std::string wait_for = when.empty() ? "sleep 5" :
        "i=0; while [ ! -e " + (out / when).string() + " ] && [ $i -lt 300 ]; do sleep 0.1; i=$((i+1)); done";
    const fs::path script = out.parent_path() / (out.filename().string() + ".sh");
    std::ofstream(script) << cmd << " &\nP=$!\n" << wait_for << "\nkill -" << signal << " $P\nwait $P\n";
    cmd = "sh " + script.string();
  }
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

fs::path case_root() {
  static const fs::path root = [] {
    const fs::path d = fs::temp_directory_path() / ("strata_cli_abuse_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return root;
}

fs::path case_dir(const std::string& name) { return case_root() / name; }

// Removes this process's scratch folders when the tests end.
class Scratch : public testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(case_root(), ec);
    fs::remove_all(inputs(), ec);
  }
};
const testing::Environment* const kScratch = testing::AddGlobalTestEnvironment(new Scratch);

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

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in, nullptr, false);
}

// summary.json's "files" are exactly the files in the directory.
void files_match_manifest(const fs::path& out) {
  const nlohmann::json summary = read_json(out / "summary.json");
  ASSERT_TRUE(summary.is_object()) << "no summary.json";
  std::vector<std::string> listed = summary["files"].get<std::vector<std::string>>(), found;
  for (const fs::directory_entry& e : fs::directory_iterator(out)) found.push_back(e.path().filename().string());
  std::sort(listed.begin(), listed.end());
  std::sort(found.begin(), found.end());
  EXPECT_EQ(listed, found);
}

void earlier_run(const fs::path& out, int frames, const std::string& extra = "") {
  const std::string cmd = "env -u DISPLAY EGL_LOG_LEVEL=fatal " + std::string(STRATA_BINARY) +
                          " crowd --walkers 2 --width 32 --height 24 --no-progress --table1-frames 0 --frames " +
                          std::to_string(frames) + " --out " + out.string() + " " + extra + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
}

std::vector<Case> more_cases() {
  std::vector<Case> rows;
  // ---- Outputs checked before the run ------------------------------------------------------------------------
  rows.push_back({"BenchJsonIsADirectory", "bench --json {in}", 1, "strata bench: --json: ", {}, {}});
  rows.push_back({"GaitJsonUnderAFile", "report gait --json {in}/a_file/g.json", 1, "strata report gait: --json: ", {}, {}});
  rows.push_back({"SoakJsonUnwritableFailsAtOnce", "soak --seconds 3600 --json {in}/a_file/s.json", 1, "strata soak: --json:", {}, {}});
  rows.push_back({"CrowdOutUnderAFile", "crowd --out {in}/a_file/x" + kTiny, 1, "strata crowd: --out: ", {}, {}});
  rows.push_back({"ExportOutIsADirectory", "export --out {in}", 1, "strata export: --out: ", {}, {}});
  rows.push_back({"MuscleImagesUnderAFile", "report muscle --images {in}/a_file/fig", 1, "strata report muscle: --images: ", {}, {}});
  rows.push_back({"CrowdTooLargeForGl", "crowd --walkers 1 --frames 1 --level -1 --width 16384 --height 16384 --no-mp4 --out {out}", 1,
                  "strata crowd: --width/--height: ", {}, {"."}});
  rows.push_back({"BenchRenderTooLargeForGlFailsBeforeTheRun",
                  "bench --render --walkers 1 --frames 2 --width 16384 --height 16384", 1,
                  "strata bench: --width/--height: ", {}, {}});
  rows.push_back({"SoakRenderTooLargeForGlFailsAtOnce",
                  "soak --render --seconds 3600 --walkers 1 --width 16384 --height 16384", 1,
                  "strata soak: --width/--height: ", {}, {}});
  rows.push_back({"CrowdTooLargeForMemory", "crowd --walkers 10000000 --out {out}", 1,
                  "10000000 walkers at --level 0 needs about", {}, {"."}});
  rows.push_back({"CrowdLevelAboveAnImportedBody", "crowd --mesh {in}/MAN.GLB --muscles none --level 1" + kTiny + " --out {out}", 1,
                  "--level 1: the body has 1 level(s)", {}, {"."}});
  rows.push_back({"SkeletonGivenAGlb", "crowd --skeleton {in}/MAN.GLB --muscles none" + kTiny + " --out {out}", 1, "no H-Anim skeleton", {}, {"."}});
  rows.push_back({"InfoUppercaseGlb", "info {in}/MAN.GLB", 0, "glTF 2.0 skinned mesh", {}, {}});
  rows.push_back({"ViewUnknownTab", "view --tab Bogus", 2, "strata view: --tab: Bogus not in", {}, {}});
  // ---- The output directory a run owns ----------------------------------------------------------------------
  {
    Case c{"ShorterRunReplacesTheEarlierOutput", "crowd" + kTiny + " --out {out}", 0, "", {"frame_0000.png", "frame_0001.png", "summary.json"},
           {"frame_0002.png", "frame_0003.png", "crowd.mp4"}};
    c.before = [](const fs::path& out) { earlier_run(out, 4); };
    c.after = files_match_manifest;
    rows.push_back(c);
  }
  {
    Case c{"ForeignDirectoryIsRefused", "crowd" + kTiny + " --out {out}", 2, "is not empty and holds no earlier strata crowd output",
           {"notes.txt"}, {"summary.json", "frame_0000.png"}};
    c.before = [](const fs::path& out) {
      fs::create_directories(out);
      std::ofstream(out / "notes.txt") << "mine\n";
    };
    rows.push_back(c);
  }
  {
    Case c{"KilledRunsTemporariesAndFramesAreCleared", "crowd" + kTiny + " --out {out}", 0, "", {"frame_0001.png"},
           {".frame_0007.png.999999999.3.tmp", "frame_0009.png"}};
    c.before = [](const fs::path& out) {
      fs::create_directories(out);
      // What a SIGKILLed run leaves: its manifest still says running, a frame, a temporary of a dead process.
      std::ofstream(out / "summary.json") << R"({"command": "crowd", "running": true, "files": ["summary.json"]})";
      std::ofstream(out / "frame_0009.png") << "x";
      std::ofstream(out / ".frame_0007.png.999999999.3.tmp") << "x";
    };
    c.after = files_match_manifest;
    rows.push_back(c);
  }
  {
    Case c{"OnlyTemporariesLeftCountsAsEmpty", "crowd" + kTiny + " --out {out}", 0, "", {"summary.json"},
           {".summary.json.999999999.0.tmp"}};
    c.before = [](const fs::path& out) {
      fs::create_directories(out);
      std::ofstream(out / ".summary.json.999999999.0.tmp") << "x";
    };
    rows.push_back(c);
  }
  {
    Case c{"SummaryRecordsInputsAndThreadsThatRan", "crowd --threads 1000 --mesh {in}/MAN.GLB --muscles none" + kTiny + " --out {out}", 0, "",
           {"summary.json"}, {}};
    c.after = [](const fs::path& out) {
      const nlohmann::json s = read_json(out / "summary.json");
      EXPECT_LE(s["threads"].get<int>(), static_cast<int>(std::max(2u, std::thread::hardware_concurrency())));
      EXPECT_NE(s["inputs"]["mesh"].get<std::string>().find("MAN.GLB"), std::string::npos);
      EXPECT_TRUE(s["inputs"]["skeleton"].is_null());
      EXPECT_EQ(s["inputs"]["muscles"], "none");
      EXPECT_FALSE(s["interrupted"].get<bool>());
    };
    rows.push_back(c);
  }
  // ---- Signals ----------------------------------------------------------------------------------------------
  for (const auto& [name, sig, code] : {std::tuple{"CrowdSigint", 2, 130}, std::tuple{"CrowdSigterm", 15, 143}}) {
    Case c{name, "crowd --walkers 2 --frames 100000 --width 32 --height 24 --table1-frames 0 --out {out}", code,
           "strata crowd: interrupted after", {"summary.json", "profile.json", "profile.csv", "frame_0000.png"}, {}};
    c.signal = sig;
    c.signal_when = "frame_0002.png";
    c.after = [](const fs::path& out) {
      const nlohmann::json s = read_json(out / "summary.json");
      EXPECT_TRUE(s["interrupted"].get<bool>());
      EXPECT_GE(s["frames"].get<int>(), 3);
      files_match_manifest(out);
    };
    rows.push_back(c);
  }
  {
    Case c{"SoakSigintKeepsTheSamples", "soak --seconds 600 --warmup 300 --walkers 2 --level -1 --sample-every 0.2 --json {out}/soak.json", 130,
           "strata soak: interrupted after", {}, {}};
    c.before = [](const fs::path& out) { fs::create_directories(out); };
    c.signal = 2;
    c.after = [](const fs::path& out) {
      const nlohmann::json s = read_json(out / "soak.json");
      ASSERT_TRUE(s.is_object()) << "no soak.json";
      EXPECT_TRUE(s["interrupted"].get<bool>());
      EXPECT_TRUE(s["flat"].is_null());
      EXPECT_GE(s["samples_s_kib"].size(), 3u);
    };
    rows.push_back(c);
  }
  return rows;
}

std::vector<Case> all_cases() {
  std::vector<Case> rows = cases();
  for (Case& c : more_cases()) rows.push_back(std::move(c));
  return rows;
}

class CliAbuse : public testing::TestWithParam<Case> {};

TEST_P(CliAbuse, ExitCodeMessageAndFiles) {
  const Case& c = GetParam();
  const fs::path out = case_dir(c.name);
  fs::remove_all(out);
  if (c.before) c.before(out);
  const std::string args = expand(c.args, out);
  SCOPED_TRACE("strata " + args);
  const Outcome o = run_strata(args, out, c.signal, c.signal_when);
  ASSERT_FALSE(o.timed_out) << "hung (killed after 60 s); output: " << o.output;
  ASSERT_NE(o.code, -1) << "killed by a signal; output: " << o.output;
  EXPECT_EQ(o.code, c.exit_code) << o.output;
  if (!c.message.empty()) {
    EXPECT_NE(o.output.find(c.message), std::string::npos) << "no '" << c.message << "' in: " << o.output;
  }
  if (c.exit_code != 0) {
    // A failure is one line on stderr, prefixed with the command.
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "not one line: " << o.err;
    EXPECT_EQ(o.err.rfind("strata", 0), 0u) << o.err;
  }
  for (const std::string& p : c.present) EXPECT_TRUE(fs::exists(out / p)) << p << " missing";
  for (const std::string& p : c.absent) EXPECT_FALSE(fs::exists(out / p)) << p << " present";
  if (c.after) c.after(out);
}

INSTANTIATE_TEST_SUITE_P(Table, CliAbuse, testing::ValuesIn(all_cases()),
                         [](const testing::TestParamInfo<Case>& info) { return info.param.name; });

}  // namespace
