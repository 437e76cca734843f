#pragma once
// Per-system timing: a scoped timer around each system of the frame script feeds
//   1. rolling per-system statistics over the last `window` frames (min, mean, p95, max), printed as a table and
//      written as CSV, and
//   2. a Chrome trace-event JSON file (opens in Perfetto and chrome://tracing).
// STRATA_PROFILE_SCOPE compiles to nothing when STRATA_PROFILING is 0, so a release build without timers pays
// nothing. Profiler methods stay callable either way (they then see no samples).
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace strata {

struct SystemStats {
  std::string name;
  std::size_t samples = 0;   // frames in the window that ran this scope
  double last_ms = 0, min_ms = 0, mean_ms = 0, p95_ms = 0, max_ms = 0;
};

// One completed scope, as it goes into the trace.
struct TraceEvent {
  std::uint32_t name_id = 0;     // index into Profiler::names()
  std::uint64_t frame = 0;       // frame index it belongs to
  double start_us = 0;           // microseconds since the profiler was created
  double duration_us = 0;
  std::uint32_t thread = 0;      // small per-thread id (0 = the thread that created the profiler)
  std::uint16_t depth = 0;       // nesting depth on its thread (0 = outermost)
};

// One completed frame (begin_frame .. end_frame), for the trace's frame markers.
struct FrameMark {
  std::uint64_t frame = 0;
  double start_us = 0;           // begin_frame time (end_frame time if begin_frame was not called)
  double duration_us = 0;        // 0 if begin_frame was not called
};

class Profiler {
 public:
  using Clock = std::chrono::steady_clock;

  // `window`: frames kept for the rolling statistics. `keep_trace`: also keep every event for export
  // (memory grows with frames x scopes; bench runs of many frames may turn it off).
  explicit Profiler(std::size_t window = 120, bool keep_trace = true);

  // Frame brackets. A scope outside begin/end frame is recorded against the current frame index anyway.
  void begin_frame();
  void end_frame();
  std::uint64_t frame_index() const;

  // Interns a scope name; ids are stable for the profiler's life. Thread-safe.
  std::uint32_t intern(std::string_view name);
  const std::vector<std::string>& names() const;

  // Records a finished scope (called by ScopedTimer). Thread-safe.
  void record(std::uint32_t name_id, Clock::time_point start, Clock::time_point end, std::uint16_t depth);

  // Rolling statistics, one entry per scope name in first-seen order (the frame script's order). Only completed
  // frames (end_frame) count; a scope's sample for a frame is the sum of its runs in that frame; the window is
  // the last `window` frames in which the scope ran; p95 is nearest-rank (the ceil(0.95 n)-th smallest).
  std::vector<SystemStats> stats() const;
  // Fixed-width table: system, last, min, mean, p95, max (ms) and the window length.
  void print_table(std::ostream& out) const;
  // Trace events kept so far (empty when keep_trace is false).
  const std::vector<TraceEvent>& events() const;
  // Completed frames, one per end_frame (empty when keep_trace is false).
  // events(), frame_marks() and names() hand out references without locking, and so do the writers that use
  // them: call them while no other thread is recording or interning.
  const std::vector<FrameMark>& frame_marks() const;

  // Writers; throw std::runtime_error naming the path if it cannot be written.
  void write_chrome_trace(const std::filesystem::path& path) const;
  void write_csv(const std::filesystem::path& path) const;

  // RAII timer: records [construction, destruction) under `name_id`, tracking nesting depth per thread.
  class ScopedTimer {
   public:
    ScopedTimer(Profiler& profiler, std::uint32_t name_id);
    ~ScopedTimer();
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

   private:
    Profiler& profiler_;
    std::uint32_t name_id_;
    std::uint16_t depth_;
    Clock::time_point start_;
  };

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace strata

#define STRATA_PROFILE_CONCAT_INNER(a, b) a##b
#define STRATA_PROFILE_CONCAT(a, b) STRATA_PROFILE_CONCAT_INNER(a, b)
#if STRATA_PROFILING
// Times the rest of the enclosing block under `name` (a string literal or std::string_view). Interning is a
// hashed lookup per scope: a system scope runs a few times per frame, so we keep it simple rather than cache
// ids in function-local statics (which would go stale when a new Profiler reuses an old one's address).
#define STRATA_PROFILE_SCOPE(profiler, name) \
  ::strata::Profiler::ScopedTimer STRATA_PROFILE_CONCAT(strata_prof_timer_, __LINE__)((profiler), (profiler).intern(name))
#else
#define STRATA_PROFILE_SCOPE(profiler, name) ((void)0)
#endif
