#include "profiling/profiler.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace strata {

// Statistics definitions (also what the table and the CSV report):
//  * A scope's sample for a frame is the SUM of the durations it recorded during that frame: a system that runs
//    in several chunks costs the frame their total. (Taking each run as its own sample would let a system that
//    runs twice look half as expensive.)
//  * The window holds the last `window` COMPLETED frames (end_frame) in which the scope ran; frames in which it
//    did not run are not zeros in its window. A scope recorded in the frame still in progress shows up in stats()
//    only after end_frame, so every reported number is over whole frames.
//  * p95 is the nearest-rank percentile: the ceil(0.95 * n)-th smallest sample (1-based), so it is always one
//    of the measured values; interpolating between ranks was rejected because with n = 20 it would invent a
//    number no frame took.
//  * Scopes are listed in first-seen (intern) order; a name interned but never completed in a frame is left out.

namespace {

double to_us(Profiler::Clock::duration d) {
  return std::chrono::duration<double, std::micro>(d).count();
}

// A process-wide serial per thread, never reused. std::thread::id was the first choice of key, but the C
// library hands a finished thread's id to the next thread it starts, so a worker spawned after another was
// joined would have been merged with it in the trace.
std::uint64_t this_thread_serial() {
  static std::atomic<std::uint64_t> next{0};
  thread_local const std::uint64_t serial = next.fetch_add(1, std::memory_order_relaxed);
  return serial;
}

}  // namespace

struct Profiler::Impl {
  struct ThreadState {
    std::uint32_t id = 0;
    std::uint16_t depth = 0;   // scopes currently open on this thread
  };

  struct Scope {
    std::vector<double> ring;   // per-frame sums in ms; grows to `window`, then overwritten oldest first
    std::size_t next = 0;       // slot the next sample goes to once the ring is full
    double last_ms = 0;
    double pending_ms = 0;      // sum over the frame in progress
    bool pending = false;
  };

  // Transparent hashing lets intern() look a string_view up without building a std::string each scope.
  struct NameHash {
    using is_transparent = void;
    std::size_t operator()(std::string_view s) const noexcept { return std::hash<std::string_view>{}(s); }
  };

  Impl(std::size_t window_frames, bool keep)
      : window(window_frames), keep_trace(keep), origin(Clock::now()) {
    // The creating thread is 0 by contract, whether or not it ever records.
    threads.emplace(this_thread_serial(), ThreadState{0, 0});
  }

  // Small ids live in a map owned by the profiler rather than in a thread_local cache: a thread_local keyed by
  // profiler address goes stale when a profiler dies and a new one is built at the same address.
  ThreadState& thread_state_locked() {
    auto [it, inserted] = threads.try_emplace(this_thread_serial());
    if (inserted) it->second.id = static_cast<std::uint32_t>(threads.size() - 1);
    return it->second;
  }

  void check_id_locked(std::uint32_t name_id) const {
    if (name_id >= names.size())
      throw std::out_of_range("Profiler: scope id " + std::to_string(name_id) + " was not interned");
  }

  void record_locked(std::uint32_t name_id, Clock::time_point start, Clock::time_point end, std::uint16_t depth,
                     std::uint32_t thread) {
    // A reversed interval (only possible through record() with hand-made time points) becomes zero length
    // instead of a throw: record() also runs inside ScopedTimer's destructor.
    if (end < start) end = start;
    Scope& scope = scopes[name_id];
    scope.pending_ms += std::chrono::duration<double, std::milli>(end - start).count();
    if (!scope.pending) {
      scope.pending = true;
      pending_ids.push_back(name_id);
    }
    if (keep_trace)
      events.push_back(TraceEvent{name_id, frame, to_us(start - origin), to_us(end - start), thread, depth});
  }

  mutable std::mutex mutex;
  const std::size_t window;
  const bool keep_trace;
  const Clock::time_point origin;

  std::uint64_t frame = 0;
  std::optional<Clock::time_point> frame_start;

  std::vector<std::string> names;
  std::unordered_map<std::string, std::uint32_t, NameHash, std::equal_to<>> ids;
  std::vector<Scope> scopes;                 // parallel to names
  std::vector<std::uint32_t> pending_ids;    // scopes with a sample in the frame in progress

  std::unordered_map<std::uint64_t, ThreadState> threads;   // keyed by this_thread_serial()
  std::vector<TraceEvent> events;
  std::vector<FrameMark> frames;
};

Profiler::Profiler(std::size_t window, bool keep_trace) {
  if (window == 0) throw std::invalid_argument("Profiler: the statistics window must hold at least one frame");
  impl_ = std::make_shared<Impl>(window, keep_trace);
}

void Profiler::begin_frame() {
  const auto now = Clock::now();
  std::lock_guard lock(impl_->mutex);
  impl_->frame_start = now;
}

void Profiler::end_frame() {
  const auto now = Clock::now();
  Impl& im = *impl_;
  std::lock_guard lock(im.mutex);
  for (std::uint32_t id : im.pending_ids) {
    Impl::Scope& scope = im.scopes[id];
    if (scope.ring.size() < im.window) {
      scope.ring.push_back(scope.pending_ms);
    } else {
      scope.ring[scope.next] = scope.pending_ms;
      scope.next = (scope.next + 1) % im.window;
    }
    scope.last_ms = scope.pending_ms;
    scope.pending_ms = 0;
    scope.pending = false;
  }
  im.pending_ids.clear();
  if (im.keep_trace) {
    FrameMark mark{im.frame, to_us(now - im.origin), 0};
    if (im.frame_start) {
      mark.start_us = to_us(*im.frame_start - im.origin);
      mark.duration_us = to_us(now - *im.frame_start);
    }
    im.frames.push_back(mark);
  }
  im.frame_start.reset();
  ++im.frame;
}

std::uint64_t Profiler::frame_index() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->frame;
}

std::uint32_t Profiler::intern(std::string_view name) {
  Impl& im = *impl_;
  std::lock_guard lock(im.mutex);
  if (auto it = im.ids.find(name); it != im.ids.end()) return it->second;
  const auto id = static_cast<std::uint32_t>(im.names.size());
  im.names.emplace_back(name);
  im.scopes.emplace_back();
  im.ids.emplace(std::string(name), id);
  return id;
}

const std::vector<std::string>& Profiler::names() const { return impl_->names; }

void Profiler::record(std::uint32_t name_id, Clock::time_point start, Clock::time_point end, std::uint16_t depth) {
  Impl& im = *impl_;
  std::lock_guard lock(im.mutex);
  im.check_id_locked(name_id);
  im.record_locked(name_id, start, end, depth, im.thread_state_locked().id);
}

std::vector<SystemStats> Profiler::stats() const {
  const Impl& im = *impl_;
  std::lock_guard lock(im.mutex);
  std::vector<SystemStats> out;
  std::vector<double> sorted;
  for (std::size_t i = 0; i < im.scopes.size(); ++i) {
    const Impl::Scope& scope = im.scopes[i];
    if (scope.ring.empty()) continue;
    sorted.assign(scope.ring.begin(), scope.ring.end());
    std::sort(sorted.begin(), sorted.end());
    const std::size_t n = sorted.size();
    double sum = 0;
    for (double v : sorted) sum += v;
    const std::size_t rank = std::max<std::size_t>(1, (95 * n + 99) / 100);   // ceil(0.95 n) without FP rounding
    SystemStats s;
    s.name = im.names[i];
    s.samples = n;
    s.last_ms = scope.last_ms;
    s.min_ms = sorted.front();
    s.mean_ms = sum / static_cast<double>(n);
    s.p95_ms = sorted[rank - 1];
    s.max_ms = sorted.back();
    out.push_back(std::move(s));
  }
  return out;
}

void Profiler::print_table(std::ostream& out) const {
  const auto rows = stats();
  std::size_t name_width = 6;   // "system"
  for (const auto& r : rows) name_width = std::max(name_width, r.name.size());
  const std::size_t window = impl_->window;
  const std::uint64_t frames = frame_index();

  // snprintf rather than iomanip: it leaves the caller's stream flags alone.
  char line[256];
  std::snprintf(line, sizeof line, "per-system time in ms, rolling window of %zu frames (%llu frames run)\n", window,
                static_cast<unsigned long long>(frames));
  out << line;
  const int w = static_cast<int>(name_width);
  std::snprintf(line, sizeof line, "%-*s %10s %10s %10s %10s %10s\n", w, "system", "last", "min", "mean", "p95",
                "max");
  out << line << std::string(name_width + 5 * 11, '-') << '\n';
  for (const auto& r : rows) {
    std::snprintf(line, sizeof line, " %10.3f %10.3f %10.3f %10.3f %10.3f\n", r.last_ms, r.min_ms, r.mean_ms,
                  r.p95_ms, r.max_ms);
    // The name goes through the stream so that a long one is never cut by the fixed buffer.
    out << r.name << std::string(name_width - r.name.size(), ' ') << line;
  }
  if (rows.empty()) out << "(no completed frames with scopes)\n";
}

const std::vector<TraceEvent>& Profiler::events() const { return impl_->events; }

const std::vector<FrameMark>& Profiler::frame_marks() const { return impl_->frames; }

Profiler::ScopedTimer::ScopedTimer(Profiler& profiler, std::uint32_t name_id)
    : profiler_(profiler), name_id_(name_id), depth_(0) {
  {
    Impl& im = *profiler_.impl_;
    std::lock_guard lock(im.mutex);
    im.check_id_locked(name_id);   // here, where throwing is allowed, not in the destructor
    Impl::ThreadState& t = im.thread_state_locked();
    depth_ = t.depth;
    if (t.depth < std::numeric_limits<std::uint16_t>::max()) ++t.depth;
  }
  // Read the clock after the lock so that lock contention is not charged to the scope.
  start_ = Clock::now();
}

Profiler::ScopedTimer::~ScopedTimer() {
  const auto end = Clock::now();
  Impl& im = *profiler_.impl_;
  std::lock_guard lock(im.mutex);
  Impl::ThreadState& t = im.thread_state_locked();
  if (depth_ < std::numeric_limits<std::uint16_t>::max()) --t.depth;   // undo exactly what the constructor did
  im.record_locked(name_id_, start_, end, depth_, t.id);
}

}  // namespace strata
