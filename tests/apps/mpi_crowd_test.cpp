// `mpirun -np K strata crowd`: one crowd over K processes (apps/crowd_distributed.h) gives the state hash of one
// process, bit for bit, with walkers crossing borders and the slabs recut during the run; its frames match one
// process's except where walkers of different ranks overlap within a pixel (docs/scale-out.md); it writes one
// trace with a process per rank and the "mpi" summary; a bad input is reported once; a rank that stops making
// progress ends the job instead of hanging it. Oversubscribed on the 2-core machine (--oversubscribe).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/apps/strata_cli_runner.h"
#include "tests/sanitizer_scale.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;
using test::CliResult;

// OpenMPI refuses root without the two variables (CI runs as root); its session directory stays out of the test's
// TMPDIR (tests/CMakeLists.txt checks that nothing is left there); no single-copy shared memory (CMA), which
// containers often forbid.
const std::string kMpiEnv =
    "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_orte_tmpdir_base=/tmp "
    "OMPI_MCA_btl_vader_single_copy_mechanism=none";

// Under the sanitizers, leak checking is off for the ranks: OpenMPI unloads its components (dlopen'ed plug-ins)
// in MPI_Finalize, so LeakSanitizer sees their allocations from "<unknown module>" and no suppression can name
// them. The same crowd code runs leak-checked in one process in the rest of the suite.
const std::string kSanitizerEnv =
    test::kSanitizedBuild ? " ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\"" : "";

CliResult mpirun(int ranks, const std::string& args) {
  const std::string cmd = "env -u DISPLAY " + kMpiEnv + kSanitizerEnv + " timeout 300 " + std::string(STRATA_MPIEXEC) +
                          " --oversubscribe -np " + std::to_string(ranks) + " " + STRATA_BINARY + " " + args + " 2>&1";
  return test::run_strata_once(cmd);
}

nlohmann::json summary_of(const fs::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "summary.json")); }

// RGBA bytes of a PNG through ffmpeg (the tests' only image decoder); empty when ffmpeg cannot run.
std::vector<std::uint8_t> decode(const fs::path& png) {
  std::vector<std::uint8_t> out;
  FILE* pipe = popen(("ffmpeg -v error -i " + png.string() + " -f rawvideo -pix_fmt rgba - 2>/dev/null").c_str(), "r");
  if (!pipe) return out;
  std::uint8_t buf[65536];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) out.insert(out.end(), buf, buf + n);
  pclose(pipe);
  return out;
}

const std::string kCrowd =
    "crowd --walkers 10 --frames 45 --level 0 --quality low --width 320 --height 180 --rebalance-seconds 0.5 "
    "--no-mp4 --no-progress --png-every 44 --table1-frames 0 ";

TEST(MpiCrowd, RanksGiveOneProcesssStateAndFrame) {
  const test::TempDir tmp("strata_mpi_test");
  const CliResult one = test::run_strata(kCrowd + "--out " + (tmp / "one").string());
  ASSERT_EQ(one.status, 0) << one.out;
  const nlohmann::json single = summary_of(tmp / "one");
  const std::vector<std::uint8_t> single_frame = decode(tmp / "one" / "frame_0044.png");
  for (int ranks : {2, 3}) {
    const fs::path dir = tmp / ("np" + std::to_string(ranks));
    const CliResult r = mpirun(ranks, kCrowd + "--out " + dir.string());
    ASSERT_EQ(r.status, 0) << r.out;
    const nlohmann::json s = summary_of(dir);
    EXPECT_EQ(s.at("state_hash"), single.at("state_hash")) << ranks << " ranks";
    const nlohmann::json& m = s.at("mpi");
    EXPECT_EQ(m.at("ranks"), ranks);
    double walkers = 0, migrated = 0;
    for (const auto& w : m.at("walkers_per_rank")) walkers += w.get<double>();
    for (const auto& w : m.at("walkers_migrated_per_rank")) migrated += w.get<double>();
    EXPECT_EQ(walkers, 10.0) << "every walker has exactly one owner";
    EXPECT_GT(migrated, 0.0) << "walkers crossed borders (and the slabs were recut), so the hash tested migration";
    EXPECT_GT(m.at("repartitions").get<int>(), 1);
    EXPECT_GE(m.at("load_imbalance").get<double>(), 1.0);
    for (const auto& b : m.at("composite_bytes_per_frame_per_rank")) EXPECT_GT(b.get<double>(), 0.0);
    // One trace, a process per rank.
    const nlohmann::json trace = nlohmann::json::parse(std::ifstream(dir / "profile.json"));
    std::set<int> pids;
    for (const auto& e : trace.at("traceEvents")) pids.insert(e.at("pid").get<int>());
    EXPECT_EQ(pids.size(), static_cast<std::size_t>(ranks));
    // The frame: rank 0 wrote it; it differs from one process's only at pixels where walkers of two ranks meet.
    const std::vector<std::uint8_t> frame = decode(dir / "frame_0044.png");
    if (single_frame.empty()) GTEST_SKIP() << "ffmpeg cannot decode PNGs here";
    ASSERT_EQ(frame.size(), single_frame.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < frame.size(); i += 4)
      differing += frame[i] != single_frame[i] || frame[i + 1] != single_frame[i + 1] || frame[i + 2] != single_frame[i + 2];
    EXPECT_LT(static_cast<double>(differing) / static_cast<double>(frame.size() / 4), 0.005) << differing << " pixels";
  }
  EXPECT_FALSE(fs::exists(tmp / "np2" / "crowd.mp4"));
}

// Steered agents: each rank steers its slab's agents, with the others' near its borders as ghosts.
TEST(MpiCrowd, SteeredAgentsGiveOneProcesssState) {
  const test::TempDir tmp("strata_mpi_test");
  const std::string args = "crowd --scenario crossing --walkers 48 --frames 60 --level 2 --quality low --width 160 "
                           "--height 90 --rebalance-seconds 1 --no-mp4 --no-progress --no-png --table1-frames 0 ";
  const CliResult one = test::run_strata(args + "--out " + (tmp / "one").string());
  ASSERT_EQ(one.status, 0) << one.out;
  const CliResult r = mpirun(3, args + "--out " + (tmp / "np3").string());
  ASSERT_EQ(r.status, 0) << r.out;
  const nlohmann::json s = summary_of(tmp / "np3");
  EXPECT_EQ(s.at("state_hash"), summary_of(tmp / "one").at("state_hash"));
  const nlohmann::json& m = s.at("mpi");
  double walkers = 0, ghosts = 0;
  for (const auto& w : m.at("walkers_per_rank")) walkers += w.get<double>();
  for (const auto& g : m.at("ghosts_received_mean_per_rank")) ghosts += g.get<double>();
  EXPECT_EQ(walkers, 48.0);
  EXPECT_GT(ghosts, 0.0) << "agents met across borders, so the hash tested the ghosts";
  for (const auto& b : m.at("plan_offer_bytes_per_frame_per_rank")) EXPECT_GT(b.get<double>(), 0.0);

  // `strata report crowd` over the same ranks: each rank observes its own agents with the others' near its borders,
  // rank 0 merges, so the crowd's figures (overlaps across borders included) are one process's; only the costs are
  // per rank.
  const std::string report = "report crowd --scenario crossing --walkers 48 --seconds 4 --json ";
  const CliResult alone = test::run_strata(report + (tmp / "one.json").string());
  ASSERT_EQ(alone.status, 0) << alone.out;
  const CliResult spread = mpirun(3, report + (tmp / "np3.json").string());
  ASSERT_EQ(spread.status, 0) << spread.out;
  EXPECT_EQ(spread.out.find("crowd report:"), spread.out.rfind("crowd report:")) << "printed once: " << spread.out;
  const nlohmann::json a = nlohmann::json::parse(std::ifstream(tmp / "one.json"));
  const nlohmann::json b = nlohmann::json::parse(std::ifstream(tmp / "np3.json"));
  for (const char* key : {"agents", "frames", "overlaps", "min_clearance_m", "reached_goal_pct", "time_to_goal_s",
                          "stuck_agents", "nan_count"})
    EXPECT_EQ(b.at(key), a.at(key)) << key;
  EXPECT_EQ(b.at("mpi").at("ranks"), 3);
  double border = 0;
  for (const auto& v : b.at("mpi").at("report_border_bytes_per_frame_per_rank")) border += v.get<double>();
  EXPECT_GT(border, 0.0) << "agents met across the borders, so the figures tested the border observations";
  EXPECT_LT(b.at("foot_slide_mm_max").get<double>(), a.at("foot_slide_mm_max").get<double>() + 0.5)
      << "each rank follows its walkers' feet; a walker arriving from another rank starts at its next heel strike";
}

TEST(MpiCrowd, BenchTimesEveryRanksSlabAndOtherCommandsAreRefusedOnce) {
  const test::TempDir tmp("strata_mpi_test");
  const fs::path json = tmp / "bench.json";
  const CliResult r =
      mpirun(2, "bench --walkers 10 --frames 8 --level 2 --render --width 160 --height 90 --json " + json.string());
  ASSERT_EQ(r.status, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j.at("walkers"), 10);
  const nlohmann::json& m = j.at("mpi");
  EXPECT_EQ(m.at("ranks"), 2);
  double walkers = 0;
  for (const auto& w : m.at("walkers_per_rank")) walkers += w.get<double>();
  EXPECT_EQ(walkers, 10.0);
  for (const auto& ms : m.at("compute_ms_mean_per_rank")) EXPECT_GT(ms.get<double>(), 0.0);
  // --render: each rank draws its own walkers, and the frames are composited.
  const nlohmann::json& render = j.at("render").at("mpi");
  ASSERT_EQ(render.at("render_ms_per_frame_per_rank").size(), 2u);
  for (const auto& ms : render.at("render_ms_per_frame_per_rank")) EXPECT_GT(ms.get<double>(), 0.0);
  for (const auto& ms : render.at("composite_ms_per_frame_per_rank")) EXPECT_GT(ms.get<double>(), 0.0);
  for (const auto& t : render.at("triangles_per_frame_per_rank")) EXPECT_GT(t.get<double>(), 0.0) << "both ranks draw walkers";
  const CliResult traced = mpirun(2, "bench --walkers 4 --frames 2 --level 2 --render --renderer embree");
  EXPECT_EQ(traced.status, 2) << traced.out;
  EXPECT_EQ(traced.out.find("--renderer embree"), traced.out.rfind("--renderer embree")) << "once: " << traced.out;
  // One line, exit 2, for a command that would run whole in every rank.
  const CliResult refused = mpirun(2, "report gait --json " + (tmp / "gait.json").string());
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_EQ(refused.out.find("strata report gait:"), refused.out.rfind("strata report gait:")) << refused.out;
  EXPECT_NE(refused.out.find("under mpirun"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(tmp / "gait.json"));
}

TEST(MpiCrowd, ABadInputIsReportedOnceByRankZero) {
  const test::TempDir tmp("strata_mpi_test");
  const CliResult r = mpirun(2, "crowd --scenario " + (tmp / "missing.json").string() + " --out " + (tmp / "o").string());
  EXPECT_NE(r.status, 0);
  std::size_t lines = 0;
  for (std::size_t at = r.out.find("strata crowd:"); at != std::string::npos; at = r.out.find("strata crowd:", at + 1))
    ++lines;
  EXPECT_EQ(lines, 1u) << r.out;
  EXPECT_NE(r.out.find("missing.json"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("rank 1"), std::string::npos) << "the same error on every rank is rank 0's to report: " << r.out;
}

TEST(MpiCrowd, ARankWithoutProgressStopsTheJobInsteadOfHangingIt) {
  const test::TempDir tmp("strata_mpi_test");
  // Building the crowd takes longer than 0.05 s, so every rank's watchdog fires before the first frame.
  const CliResult r = mpirun(2, kCrowd + "--mpi-timeout 0.05 --out " + (tmp / "o").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.out.find("no progress"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace strata
