#include "profiling/profiler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/temp_dir.h"

namespace {

using strata::Profiler;
using Clock = Profiler::Clock;
using json = nlohmann::json;
namespace fs = std::filesystem;

const std::vector<std::string> kSystems = {"animation", "fk", "render"};

// A unique scratch directory per test, removed afterwards.
class ProfilerFiles : public ::testing::Test {
 protected:
  const strata::test::TempDir tmp_{"strata_profiler_test"};
  const fs::path& dir_ = tmp_.path();
};

// Spins rather than sleeps: sleep_for on a loaded 2-core machine can overshoot by milliseconds, and these
// scopes only need to be non-empty, not to have any particular length.
void spin_for(std::chrono::microseconds d) {
  const auto until = Clock::now() + d;
  while (Clock::now() < until) {
  }
}

// The fake frame script: a "frame" scope with three systems nested inside it.
void run_script(Profiler& p, int frames) {
  for (int f = 0; f < frames; ++f) {
    p.begin_frame();
    {
      Profiler::ScopedTimer frame_timer(p, p.intern("frame"));
      for (std::size_t s = 0; s < kSystems.size(); ++s) {
        Profiler::ScopedTimer t(p, p.intern(kSystems[s]));
        spin_for(std::chrono::microseconds(2 + static_cast<int>(s)));
      }
    }
    p.end_frame();
  }
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  return json::parse(in);   // throws on malformed JSON, which fails the test
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(cur);
  return out;
}

// Output precision is 3 decimals of a microsecond; the tolerance only absorbs parsing the decimals into doubles.
constexpr double kUsEps = 1e-6;

TEST_F(ProfilerFiles, ChromeTraceIsWellFormedCompleteAndNested) {
  constexpr int kFrames = 200;
  Profiler p;
  run_script(p, kFrames);
  const fs::path path = dir_ / "trace.json";
  p.write_chrome_trace(path);

  const json doc = read_json(path);
  ASSERT_TRUE(doc.is_object());
  ASSERT_TRUE(doc.contains("traceEvents"));
  ASSERT_TRUE(doc["traceEvents"].is_array());
  EXPECT_EQ(doc.value("displayTimeUnit", ""), "ms");
  EXPECT_TRUE(doc["otherData"].is_object());

  bool process_named = false, main_thread_named = false;
  std::map<std::string, std::map<std::int64_t, int>> count_by_name_frame;
  std::map<std::int64_t, json> frame_event_by_frame;
  std::map<std::int64_t, std::vector<json>> x_by_tid;   // in file order
  int frame_markers = 0;
  for (const json& e : doc["traceEvents"]) {
    const std::string ph = e.at("ph");
    if (ph == "M") {
      if (e.at("name") == "process_name") process_named = true;
      if (e.at("name") == "thread_name" && e.at("tid") == 0) main_thread_named = true;
    } else if (ph == "X") {
      EXPECT_EQ(e.at("cat"), "system");
      EXPECT_EQ(e.at("pid"), 1);
      EXPECT_GE(e.at("dur").get<double>(), 0.0);
      const std::string name = e.at("name");
      const std::int64_t frame = e.at("args").at("frame");
      ++count_by_name_frame[name][frame];
      if (name == "frame") frame_event_by_frame[frame] = e;
      x_by_tid[e.at("tid").get<std::int64_t>()].push_back(e);
    } else if (ph == "i") {
      EXPECT_EQ(e.at("s"), "g");
      ++frame_markers;
    }
  }
  EXPECT_TRUE(process_named);
  EXPECT_TRUE(main_thread_named);
  EXPECT_EQ(frame_markers, kFrames);

  // Exactly one complete event per scope per frame, frames 0..199.
  std::vector<std::string> all = kSystems;
  all.push_back("frame");
  ASSERT_EQ(count_by_name_frame.size(), all.size());
  for (const auto& name : all) {
    const auto& per_frame = count_by_name_frame[name];
    ASSERT_EQ(per_frame.size(), static_cast<std::size_t>(kFrames)) << name;
    EXPECT_EQ(per_frame.begin()->first, 0);
    EXPECT_EQ(per_frame.rbegin()->first, kFrames - 1);
    for (const auto& [frame, n] : per_frame) EXPECT_EQ(n, 1) << name << " frame " << frame;
  }

  // Every system event lies inside its own frame's "frame" event, on the same thread.
  ASSERT_EQ(x_by_tid.size(), 1u);
  for (const json& e : x_by_tid.begin()->second) {
    if (e.at("name") == "frame") continue;
    const json& parent = frame_event_by_frame.at(e.at("args").at("frame").get<std::int64_t>());
    EXPECT_EQ(parent.at("tid"), e.at("tid"));
    const double ts = e.at("ts"), end = ts + e.at("dur").get<double>();
    const double pts = parent.at("ts"), pend = pts + parent.at("dur").get<double>();
    EXPECT_GE(ts, pts - kUsEps);
    EXPECT_LE(end, pend + kUsEps);
    EXPECT_EQ(e.at("args").at("depth"), 1);
  }

  // Per thread, file order is by start time and intervals never partially overlap (a stack of open parents).
  for (const auto& [tid, list] : x_by_tid) {
    std::vector<double> open_ends;
    double prev_ts = -1e300;
    for (const json& e : list) {
      const double ts = e.at("ts"), end = ts + e.at("dur").get<double>();
      EXPECT_GE(ts, prev_ts);
      prev_ts = ts;
      while (!open_ends.empty() && open_ends.back() <= ts + kUsEps) open_ends.pop_back();
      if (!open_ends.empty()) {
        EXPECT_LE(end, open_ends.back() + kUsEps) << "partial overlap at ts " << ts;
      }
      open_ends.push_back(end);
    }
  }
}

TEST(Profiler, RollingWindowStatsAreExactOverTheLast120Frames) {
  constexpr int kFrames = 200, kWindow = 120;
  Profiler p(kWindow);
  const auto id = p.intern("sys");
  // Durations in whole microseconds: a scrambled pattern plus a trend, so that which frames are in the window
  // changes every statistic.
  auto duration_of = [](int f) { return std::chrono::microseconds((f * 37) % 101 * 10 + f + 1); };
  Clock::time_point t = Clock::now();
  for (int f = 0; f < kFrames; ++f) {
    p.begin_frame();
    p.record(id, t, t + duration_of(f), 0);
    t += std::chrono::milliseconds(5);
    p.end_frame();
  }
  EXPECT_EQ(p.frame_index(), static_cast<std::uint64_t>(kFrames));

  std::vector<double> expected;
  for (int f = kFrames - kWindow; f < kFrames; ++f)
    expected.push_back(std::chrono::duration<double, std::milli>(duration_of(f)).count());
  const double last = expected.back();
  std::sort(expected.begin(), expected.end());
  double sum = 0;
  for (double v : expected) sum += v;
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * kWindow));   // nearest-rank: 114th of 120

  const auto stats = p.stats();
  ASSERT_EQ(stats.size(), 1u);
  const auto& s = stats[0];
  EXPECT_EQ(s.name, "sys");
  EXPECT_EQ(s.samples, static_cast<std::size_t>(kWindow));
  EXPECT_DOUBLE_EQ(s.last_ms, last);
  EXPECT_DOUBLE_EQ(s.min_ms, expected.front());
  EXPECT_DOUBLE_EQ(s.max_ms, expected.back());
  EXPECT_NEAR(s.mean_ms, sum / kWindow, 1e-12);
  EXPECT_DOUBLE_EQ(s.p95_ms, expected[rank - 1]);
  // The pattern grows with f, so the 200-frame minimum and mean differ from the window's: a profiler that kept
  // every frame would fail the checks above.
  double overall_min = 1e300, overall_sum = 0;
  for (int f = 0; f < kFrames; ++f) {
    const double v = std::chrono::duration<double, std::milli>(duration_of(f)).count();
    overall_min = std::min(overall_min, v);
    overall_sum += v;
  }
  EXPECT_LT(overall_min, expected.front());
  EXPECT_GT(std::abs(overall_sum / kFrames - s.mean_ms), 1e-3);
}

TEST(Profiler, SeveralRunsInOneFrameSumAndAbsentFramesAreNotZeros) {
  Profiler p(4);
  const auto a = p.intern("a");
  const auto b = p.intern("b");
  const Clock::time_point t = Clock::now();
  auto ms = [](int n) { return std::chrono::milliseconds(n); };
  for (int f = 0; f < 6; ++f) {
    // "a" runs twice per frame: 1 ms + f ms. "b" runs on even frames only, for 10 + f ms.
    p.record(a, t, t + ms(1), 0);
    p.record(a, t + ms(2), t + ms(2 + f), 0);
    if (f % 2 == 0) p.record(b, t, t + ms(10 + f), 0);
    p.end_frame();
  }
  const auto stats = p.stats();
  ASSERT_EQ(stats.size(), 2u);
  EXPECT_EQ(stats[0].name, "a");
  EXPECT_EQ(stats[1].name, "b");
  // a: last 4 frames are f = 2..5, samples 1 + f = 3, 4, 5, 6.
  EXPECT_EQ(stats[0].samples, 4u);
  EXPECT_DOUBLE_EQ(stats[0].min_ms, 3.0);
  EXPECT_DOUBLE_EQ(stats[0].max_ms, 6.0);
  EXPECT_DOUBLE_EQ(stats[0].mean_ms, 4.5);
  EXPECT_DOUBLE_EQ(stats[0].last_ms, 6.0);
  // b ran in frames 0, 2, 4 only: 10, 12, 14, all inside its window of 4 runs.
  EXPECT_EQ(stats[1].samples, 3u);
  EXPECT_DOUBLE_EQ(stats[1].min_ms, 10.0);
  EXPECT_DOUBLE_EQ(stats[1].mean_ms, 12.0);
  EXPECT_DOUBLE_EQ(stats[1].last_ms, 14.0);
  EXPECT_DOUBLE_EQ(stats[1].p95_ms, 14.0);   // ceil(0.95 * 3) = 3rd of 3
}

TEST(Profiler, StatsCoverCompletedFramesOnly) {
  Profiler p;
  const auto id = p.intern("x");
  const Clock::time_point t = Clock::now();
  p.record(id, t, t + std::chrono::milliseconds(2), 0);
  EXPECT_TRUE(p.stats().empty());
  ASSERT_EQ(p.events().size(), 1u);
  EXPECT_EQ(p.events()[0].frame, 0u);
  p.end_frame();
  ASSERT_EQ(p.stats().size(), 1u);
  EXPECT_DOUBLE_EQ(p.stats()[0].last_ms, 2.0);
  p.record(id, t, t + std::chrono::milliseconds(3), 0);
  EXPECT_EQ(p.events().back().frame, 1u);
}

TEST(Profiler, KeepTraceFalseKeepsNoEventsButStats) {
  Profiler p(120, false);
  run_script(p, 5);
  EXPECT_TRUE(p.events().empty());
  EXPECT_TRUE(p.frame_marks().empty());
  const auto stats = p.stats();
  ASSERT_EQ(stats.size(), 4u);
  for (const auto& s : stats) {
    EXPECT_EQ(s.samples, 5u);
    EXPECT_GT(s.max_ms, 0.0);
  }
}

TEST(Profiler, InvalidInputsAreRejectedOrClamped) {
  EXPECT_THROW(Profiler(0), std::invalid_argument);
  Profiler p;
  const Clock::time_point t = Clock::now();
  EXPECT_THROW(p.record(7, t, t, 0), std::out_of_range);
  EXPECT_THROW(Profiler::ScopedTimer(p, 3), std::out_of_range);
  const auto id = p.intern("backwards");
  EXPECT_EQ(p.intern("backwards"), id);
  p.record(id, t + std::chrono::milliseconds(1), t, 0);
  ASSERT_EQ(p.events().size(), 1u);
  EXPECT_EQ(p.events()[0].duration_us, 0.0);
}

TEST(Profiler, WorkerThreadsGetDistinctIdsAndTheirOwnDepth) {
  Profiler p;
  const auto outer = p.intern("outer");
  const auto inner = p.intern("inner");
  { Profiler::ScopedTimer main_scope(p, p.intern("main")); }

  // Both workers hold their outer scope open at the same time, so a depth counter shared between threads
  // would give the second inner scope depth 2 or an outer scope depth 1.
  std::barrier sync(2);
  auto worker = [&] {
    for (int i = 0; i < 3; ++i) {
      Profiler::ScopedTimer o(p, outer);
      sync.arrive_and_wait();
      {
        Profiler::ScopedTimer in(p, inner);
        spin_for(std::chrono::microseconds(5));
      }
      sync.arrive_and_wait();
    }
  };
  std::thread t1(worker), t2(worker);
  t1.join();
  t2.join();

  std::map<std::uint32_t, int> per_thread;
  for (const auto& e : p.events()) {
    if (e.name_id == outer) {
      EXPECT_EQ(e.depth, 0);
    }
    if (e.name_id == inner) {
      EXPECT_EQ(e.depth, 1);
    }
    if (e.name_id == outer || e.name_id == inner) {
      EXPECT_NE(e.thread, 0u);
      ++per_thread[e.thread];
    } else {
      EXPECT_EQ(e.thread, 0u);   // the creating thread
      EXPECT_EQ(e.depth, 0);
    }
  }
  ASSERT_EQ(per_thread.size(), 2u);
  EXPECT_EQ(per_thread.begin()->first, 1u);
  EXPECT_EQ(per_thread.rbegin()->first, 2u);
  for (const auto& [tid, n] : per_thread) EXPECT_EQ(n, 6) << "thread " << tid;

  // Each inner scope lies within an outer scope of the same thread.
  for (const auto& e : p.events()) {
    if (e.name_id != inner) continue;
    const bool inside = std::any_of(p.events().begin(), p.events().end(), [&](const strata::TraceEvent& o) {
      return o.name_id == outer && o.thread == e.thread && o.start_us <= e.start_us &&
             e.start_us + e.duration_us <= o.start_us + o.duration_us;
    });
    EXPECT_TRUE(inside);
  }
}

TEST(Profiler, ThreadIdsBelongToEachProfiler) {
  auto record_on_new_thread = [](Profiler& p) {
    std::thread([&] { Profiler::ScopedTimer t(p, p.intern("w")); }).join();
    return p.events().back().thread;
  };
  std::optional<Profiler> p;
  p.emplace();
  EXPECT_EQ(record_on_new_thread(*p), 1u);
  EXPECT_EQ(record_on_new_thread(*p), 2u);
  // Sequential threads stay distinct even though the C library may reuse the first one's thread id, and a new
  // profiler (quite possibly at the same address) numbers threads afresh.
  p.emplace();
  EXPECT_EQ(record_on_new_thread(*p), 1u);
}

TEST_F(ProfilerFiles, WorkerThreadsAppearAsSeparateTraceThreads) {
  Profiler p;
  const auto id = p.intern("job");
  std::thread([&] { Profiler::ScopedTimer t(p, id); }).join();
  { Profiler::ScopedTimer t(p, id); }
  p.end_frame();
  p.write_chrome_trace(dir_ / "threads.json");
  const json doc = read_json(dir_ / "threads.json");
  std::set<std::int64_t> x_tids, named_tids;
  for (const json& e : doc["traceEvents"]) {
    if (e["ph"] == "X") x_tids.insert(e["tid"].get<std::int64_t>());
    if (e["ph"] == "M" && e["name"] == "thread_name") named_tids.insert(e["tid"].get<std::int64_t>());
  }
  EXPECT_EQ(x_tids, (std::set<std::int64_t>{0, 1}));
  EXPECT_EQ(named_tids, x_tids);
}

TEST_F(ProfilerFiles, TraceEscapesNamesIntoValidJson) {
  Profiler p;
  const std::vector<std::string> names = {"quote\"back\\slash", "line\nbreak\ttab", std::string("ctl\x01", 4),
                                          "caf\xC3\xA9"};
  const Clock::time_point t = Clock::now();
  for (const auto& n : names) p.record(p.intern(n), t, t, 0);
  p.record(p.intern("bad\xFFutf8"), t, t, 0);
  p.write_chrome_trace(dir_ / "escape.json");
  const json doc = read_json(dir_ / "escape.json");
  std::set<std::string> seen;
  for (const json& e : doc["traceEvents"])
    if (e["ph"] == "X") seen.insert(e["name"].get<std::string>());
  for (const auto& n : names) EXPECT_TRUE(seen.count(n)) << n;
  EXPECT_TRUE(seen.count("bad\xEF\xBF\xBDutf8"));   // the invalid byte became U+FFFD
}

TEST_F(ProfilerFiles, CsvHasHeaderAndOneParsableRowPerSystem) {
  Profiler p;
  run_script(p, 30);
  const fs::path path = dir_ / "stats.csv";
  p.write_csv(path);
  const auto lines = split(read_text(path), '\n');
  ASSERT_EQ(lines.size(), 1 + kSystems.size() + 1);
  EXPECT_EQ(lines[0], "system,samples,last_ms,min_ms,mean_ms,p95_ms,max_ms");

  const auto stats = p.stats();
  ASSERT_EQ(stats.size(), lines.size() - 1);
  for (std::size_t i = 0; i < stats.size(); ++i) {
    const auto cells = split(lines[i + 1], ',');
    ASSERT_EQ(cells.size(), 7u) << lines[i + 1];
    EXPECT_EQ(cells[0], stats[i].name);
    EXPECT_EQ(std::stoul(cells[1]), 30u);
    const double expected[] = {stats[i].last_ms, stats[i].min_ms, stats[i].mean_ms, stats[i].p95_ms,
                               stats[i].max_ms};
    for (int k = 0; k < 5; ++k) {
      std::size_t used = 0;
      const double v = std::stod(cells[2 + k], &used);
      EXPECT_EQ(used, cells[2 + k].size()) << cells[2 + k];
      EXPECT_NEAR(v, expected[k], 1e-6);
    }
  }
  // Rows follow first-seen order: the enclosing frame scope, then the systems in script order.
  EXPECT_EQ(stats[0].name, "frame");
  for (std::size_t i = 0; i < kSystems.size(); ++i) EXPECT_EQ(stats[i + 1].name, kSystems[i]);
}

TEST_F(ProfilerFiles, CsvQuotesNamesThatNeedIt) {
  Profiler p;
  const Clock::time_point t = Clock::now();
  p.record(p.intern("a,b \"c\""), t, t + std::chrono::milliseconds(1), 0);
  p.end_frame();
  p.write_csv(dir_ / "q.csv");
  const auto lines = split(read_text(dir_ / "q.csv"), '\n');
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1].rfind("\"a,b \"\"c\"\"\",1,", 0), 0u) << lines[1];
}

TEST(Profiler, PrintTableNamesEverySystemInFixedWidthRows) {
  Profiler p(50);
  run_script(p, 60);
  std::ostringstream out;
  p.print_table(out);
  const std::string table = out.str();
  for (const auto& name : kSystems) EXPECT_NE(table.find(name), std::string::npos) << name;
  EXPECT_NE(table.find("50 frames"), std::string::npos) << table;
  EXPECT_NE(table.find("60 frames"), std::string::npos) << table;

  // After the title line, every line (column header, rule, rows) has the same width: numbers right-aligned.
  const auto lines = split(table, '\n');
  ASSERT_EQ(lines.size(), 3 + kSystems.size() + 1);
  for (std::size_t i = 2; i < lines.size(); ++i) EXPECT_EQ(lines[i].size(), lines[1].size()) << lines[i];
  EXPECT_NE(lines[1].find("p95"), std::string::npos);
  // Numbers carry 3 decimals.
  const auto row = split(lines[3], ' ');
  const std::string last_cell = row.back();
  ASSERT_GE(last_cell.size(), 5u);
  EXPECT_EQ(last_cell[last_cell.size() - 4], '.') << last_cell;
}

TEST_F(ProfilerFiles, WritersNameTheUnwritablePath) {
  Profiler p;
  run_script(p, 2);
  for (const fs::path& path : {dir_ / "missing_dir" / "trace.json", dir_ / "missing_dir" / "stats.csv"}) {
    for (int which = 0; which < 2; ++which) {
      try {
        if (which == 0)
          p.write_chrome_trace(path);
        else
          p.write_csv(path);
        ADD_FAILURE() << "no exception for " << path;
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      }
    }
  }
}

TEST(Profiler, ProfileScopeMacroRecordsUnderItsName) {
#if STRATA_PROFILING
  Profiler p;
  {
    STRATA_PROFILE_SCOPE(p, "macro_outer");
    STRATA_PROFILE_SCOPE(p, std::string_view("macro_inner"));
    spin_for(std::chrono::microseconds(3));
  }
  p.end_frame();
  ASSERT_EQ(p.names().size(), 2u);
  EXPECT_EQ(p.names()[0], "macro_outer");
  EXPECT_EQ(p.names()[1], "macro_inner");
  ASSERT_EQ(p.events().size(), 2u);
  for (const auto& e : p.events()) {
    const std::string& name = p.names()[e.name_id];
    EXPECT_EQ(e.depth, name == "macro_outer" ? 0 : 1) << name;
    EXPECT_GT(e.duration_us, 0.0);
  }
  const auto stats = p.stats();
  ASSERT_EQ(stats.size(), 2u);
  EXPECT_EQ(stats[0].name, "macro_outer");
  EXPECT_GE(stats[0].last_ms, stats[1].last_ms);   // the outer scope encloses the inner one
#else
  GTEST_SKIP() << "built with STRATA_PROFILING=0";
#endif
}

}  // namespace
