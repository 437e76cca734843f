// Writers for the profiler's two file outputs: a Chrome trace-event JSON file and a per-system CSV.
// They use only Profiler's public accessors, so the trace format can change without touching the recorder.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/atomic_file.h"
#include "profiling/profiler.h"

namespace strata {
namespace {

// Buffered writer that fails loudly with the path. The trace is streamed rather than built as one
// nlohmann::json DOM: a bench run keeps frames x scopes events (10^5..10^6), and a DOM costs a heap node per
// value, i.e. several times the file size in memory, just to be serialised once.
class FileSink {
 public:
  // Streams into a temporary sibling renamed over `path` by finish() (io/atomic_file.h): a failed or abandoned
  // write (an exception unwinding past the sink) leaves no truncated trace behind.
  explicit FileSink(const std::filesystem::path& path)
      : path_(path), atomic_(path), file_(atomic_.temp_path(), std::ios::binary | std::ios::trunc) {
    if (!file_) throw std::runtime_error("profiler: cannot open '" + path_.string() + "' for writing");
    buffer_.reserve(kFlushBytes + 1024);
  }

  std::string& buffer() { return buffer_; }

  void maybe_flush() {
    if (buffer_.size() >= kFlushBytes) flush();
  }

  void finish() {
    flush();
    file_.close();
    if (file_.fail()) fail();
    atomic_.commit();
  }

 private:
  static constexpr std::size_t kFlushBytes = 1 << 16;

  void flush() {
    file_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
    if (!file_) fail();
  }

  [[noreturn]] void fail() const { throw std::runtime_error("profiler: error while writing '" + path_.string() + "'"); }

  std::filesystem::path path_;
  AtomicFile atomic_;
  std::ofstream file_;
  std::string buffer_;
};

// Length of the valid UTF-8 sequence starting at s[i], or 0 if the bytes there are not one (overlong forms,
// surrogates and code points past U+10FFFF count as invalid, as JSON parsers reject them).
std::size_t utf8_sequence_length(std::string_view s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t len = 0;
  unsigned char lo = 0x80, hi = 0xBF;   // allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    len = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + len > s.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < len; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return len;
}

// Writes `s` as a JSON string literal. Names are expected to be UTF-8; a stray invalid byte becomes U+FFFD so
// that one odd name cannot make the whole trace unreadable.
void append_json_string(std::string& out, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  out += '"';
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x80) {
      const std::size_t len = utf8_sequence_length(s, i);
      if (len == 0) {
        out += "\\ufffd";
        ++i;
      } else {
        out.append(s.substr(i, len));
        i += len;
      }
      continue;
    }
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          out += "\\u00";
          out += kHex[c >> 4];
          out += kHex[c & 0xF];
        } else {
          out += static_cast<char>(c);
        }
    }
    ++i;
  }
  out += '"';
}

template <class Int>
void append_int(std::string& out, Int v) {
  char tmp[24];
  const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
  out.append(tmp, r.ptr);
}

// Microseconds with exactly 3 decimals, from integer nanoseconds. Working in integers makes the nesting that
// holds for the clock readings hold for the printed numbers too (child ts >= parent ts, child end <= parent
// end), which independent rounding of ts and dur as doubles would not guarantee.
void append_us(std::string& out, long long ns) {
  if (ns < 0) {
    out += '-';
    ns = -ns;
  }
  append_int(out, ns / 1000);
  const auto frac = static_cast<int>(ns % 1000);
  out += '.';
  out += static_cast<char>('0' + frac / 100);
  out += static_cast<char>('0' + frac / 10 % 10);
  out += static_cast<char>('0' + frac % 10);
}

long long us_to_ns(double us) { return std::llround(us * 1000.0); }

void append_double(std::string& out, double v, const char* format) {
  char tmp[64];
  const int n = std::snprintf(tmp, sizeof tmp, format, v);
  out.append(tmp, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof tmp) - 1)));
}

std::string thread_label(std::uint32_t tid) {
  return tid == 0 ? std::string("main") : "worker " + std::to_string(tid);
}

}  // namespace

void Profiler::write_chrome_trace(const std::filesystem::path& path) const {
  const auto& evs = events();
  const auto& marks = frame_marks();
  const auto& scope_names = names();

  struct Row {
    std::uint32_t thread;
    long long ts_ns, end_ns;
    std::uint16_t depth;
    std::size_t index;
  };
  std::vector<Row> rows;
  rows.reserve(evs.size());
  std::set<std::uint32_t> threads{0};
  for (std::size_t i = 0; i < evs.size(); ++i) {
    const TraceEvent& e = evs[i];
    const long long ts = us_to_ns(e.start_us);
    rows.push_back({e.thread, ts, std::max(ts, us_to_ns(e.start_us + e.duration_us)), e.depth, i});
    threads.insert(e.thread);
  }
  // Per thread by start time; on a tie the parent (lower depth, then the longer one) first, which is the order
  // trace viewers need to rebuild the nesting. Stable so that equal events keep their recording order.
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    if (a.thread != b.thread) return a.thread < b.thread;
    if (a.ts_ns != b.ts_ns) return a.ts_ns < b.ts_ns;
    if (a.depth != b.depth) return a.depth < b.depth;
    return a.end_ns > b.end_ns;
  });

  FileSink sink(path);
  std::string& out = sink.buffer();
  out += "{\"traceEvents\":[\n";
  out += R"({"name":"process_name","ph":"M","pid":1,"tid":0,"args":{"name":"strata"}})";
  for (std::uint32_t tid : threads) {
    out += ",\n{\"name\":\"thread_name\",\"ph\":\"M\",\"pid\":1,\"tid\":";
    append_int(out, tid);
    out += ",\"args\":{\"name\":";
    append_json_string(out, thread_label(tid));
    out += "}},\n{\"name\":\"thread_sort_index\",\"ph\":\"M\",\"pid\":1,\"tid\":";
    append_int(out, tid);
    out += ",\"args\":{\"sort_index\":";
    append_int(out, tid);
    out += "}}";
  }

  for (const Row& r : rows) {
    const TraceEvent& e = evs[r.index];
    out += ",\n{\"name\":";
    append_json_string(out, e.name_id < scope_names.size() ? std::string_view(scope_names[e.name_id])
                                                           : std::string_view("?"));
    out += ",\"cat\":\"system\",\"ph\":\"X\",\"ts\":";
    append_us(out, r.ts_ns);
    out += ",\"dur\":";
    append_us(out, r.end_ns - r.ts_ns);
    out += ",\"pid\":1,\"tid\":";
    append_int(out, r.thread);
    out += ",\"args\":{\"frame\":";
    append_int(out, e.frame);
    out += ",\"depth\":";
    append_int(out, e.depth);
    out += "}}";
    sink.maybe_flush();
  }

  // Global instant markers at each frame start: viewers draw them as lines across all threads.
  for (const FrameMark& m : marks) {
    out += ",\n{\"name\":\"frame\",\"cat\":\"frame\",\"ph\":\"i\",\"s\":\"g\",\"ts\":";
    append_us(out, us_to_ns(m.start_us));
    out += ",\"pid\":1,\"tid\":0,\"args\":{\"frame\":";
    append_int(out, m.frame);
    out += ",\"frame_ms\":";
    append_double(out, m.duration_us / 1000.0, "%.6f");
    out += "}}";
    sink.maybe_flush();
  }

  out += "\n],\"displayTimeUnit\":\"ms\",\"otherData\":{\"generator\":\"strata profiler\",\"frames\":";
  append_int(out, frame_index());
  out += ",\"scope_events\":";
  append_int(out, evs.size());
  out += ",\"clock\":\"steady_clock, microseconds since the profiler was created\"}}\n";
  sink.finish();
}

void Profiler::write_csv(const std::filesystem::path& path) const {
  const auto rows = stats();
  FileSink sink(path);
  std::string& out = sink.buffer();
  out += "system,samples,last_ms,min_ms,mean_ms,p95_ms,max_ms\n";
  for (const SystemStats& s : rows) {
    // RFC 4180 quoting, only when the name needs it, so ordinary rows stay plain.
    if (s.name.find_first_of(",\"\r\n") != std::string::npos) {
      out += '"';
      for (char c : s.name) {
        if (c == '"') out += '"';
        out += c;
      }
      out += '"';
    } else {
      out += s.name;
    }
    out += ',';
    append_int(out, s.samples);
    for (double v : {s.last_ms, s.min_ms, s.mean_ms, s.p95_ms, s.max_ms}) {
      out += ',';
      append_double(out, v, "%.6f");
    }
    out += '\n';
    sink.maybe_flush();
  }
  sink.finish();
}

}  // namespace strata
