// Sort-last compositing cost (dist/mpi_world.h MpiWorld::composite): `mpirun -np K strata_bench_composite
// [WIDTH HEIGHT ITERATIONS]` composites a WIDTHxHEIGHT RGBA8 + float depth frame from every rank onto rank 0,
// ITERATIONS times per case after a barrier each, and rank 0 prints one JSON line: per layout of the walkers, the
// slowest rank's mean and p95 (ms) with whole frames and with footprints, their ratio, and the bytes each rank
// sent per frame.
//
// The frames are a crowd frame's make-up: a ground every rank draws the same (so most pixels are depth ties) and
// each rank's own walkers in front of it, 400 upright rectangles a rank. Layouts: `scattered` (each rank's
// walkers anywhere: footprints cover the frame, compositing's worst case), `columns` (slabs across the view: a
// rank's walkers in its own strip of columns, as a camera looking across the partition axis sees them) and `rows`
// (slabs along the view: nearer slabs lower in the frame). A footprint is the rectangle of the rank's walkers.
// Both methods run in the same iterations, alternately, and rank 0 checks that they give the same image (exit
// status 1 if not).
// Not a Google Benchmark suite: every iteration is a collective, and each rank must time the same iterations.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "dist/mpi_world.h"

namespace {

enum class Layout { Scattered, Columns, Rows };

struct Frame {
  std::vector<std::uint8_t> colour;
  std::vector<float> depth;
  strata::ImageRect footprint;  // the box of this rank's walkers
};

Frame make_frame(int width, int height, int rank, int ranks, Layout layout) {
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  Frame f;
  f.colour.resize(4 * pixels);
  f.depth.resize(pixels);
  // The sky (depth 1) above the horizon and the ground below it, the same on every rank.
  const int horizon = height / 3;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
      const bool ground = y > horizon;
      f.depth[i] = ground ? 1.0f - 0.5f * static_cast<float>(y - horizon) / static_cast<float>(height) : 1.0f;
      const auto shade = static_cast<std::uint8_t>(ground ? 60 + (x / 16 + y / 16) % 2 * 10 : 40);
      f.colour[4 * i] = f.colour[4 * i + 1] = f.colour[4 * i + 2] = shade;
      f.colour[4 * i + 3] = 255;
    }
  // Where this rank's walkers stand: anywhere, in its strip of columns, or in its strip of ground rows (rank 0
  // nearest, lowest), each strip overlapping its neighbours by a walker's width as slabs' borders do on screen.
  int x_lo = 0, x_hi = width - 1, y_lo = horizon, y_hi = height - 1;
  const int overlap = width / 40;
  if (layout == Layout::Columns) {
    x_lo = std::max(0, rank * width / ranks - overlap);
    x_hi = std::min(width - 1, (rank + 1) * width / ranks + overlap);
  } else if (layout == Layout::Rows) {
    const int ground = height - 1 - horizon;
    y_hi = std::min(height - 1, height - 1 - rank * ground / ranks + overlap);
    y_lo = std::max(horizon, height - 1 - (rank + 1) * ground / ranks);
  }
  std::mt19937 rng(static_cast<unsigned>(rank + 1));
  std::uniform_int_distribution<int> px(x_lo, x_hi), py(y_lo, y_hi), size(4, 40), byte(0, 255);
  f.footprint = {width, height, 0, 0};
  for (int w = 0; w < 400; ++w) {
    const int x0 = px(rng), y1 = py(rng), h = size(rng) * 2, wd = std::max(2, h / 4);
    const float d = f.depth[static_cast<std::size_t>(y1) * static_cast<std::size_t>(width)] - 0.01f;
    const auto c = static_cast<std::uint8_t>(byte(rng));
    const int top = std::max(0, y1 - h), right = std::min(width, x0 + wd);
    f.footprint = {std::min(f.footprint.x0, x0), std::min(f.footprint.y0, top), std::max(f.footprint.x1, right),
                   std::max(f.footprint.y1, y1 + 1)};
    for (int y = top; y <= y1; ++y)
      for (int x = x0; x < right; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
        if (d < f.depth[i]) f.depth[i] = d, f.colour[4 * i] = c, f.colour[4 * i + 1] = c / 2, f.colour[4 * i + 2] = 255 - c;
      }
  }
  return f;
}

struct Timing {
  std::vector<double> ms;
  double bytes = 0;
};

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double p95_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 1280;
  const int height = argc > 2 ? std::atoi(argv[2]) : 720;
  const int iterations = argc > 3 ? std::atoi(argv[3]) : 100;
  if (width <= 0 || height <= 0 || iterations <= 0) {
    std::fprintf(stderr, "usage: mpirun -np K strata_bench_composite [WIDTH HEIGHT ITERATIONS]\n");
    return 2;
  }
  strata::MpiWorld world;
  bool same = true;
  std::string json = "{\"ranks\":" + std::to_string(world.size()) + ",\"width\":" + std::to_string(width) +
                     ",\"height\":" + std::to_string(height) + ",\"iterations\":" + std::to_string(iterations) +
                     ",\"layouts\":{";
  const std::pair<Layout, const char*> layouts[] = {
      {Layout::Scattered, "scattered"}, {Layout::Columns, "columns"}, {Layout::Rows, "rows"}};
  for (const auto& [layout, name] : layouts) {
    const Frame frame = make_frame(width, height, world.rank(), world.size(), layout);
    Timing whole, footprint;
    std::vector<std::uint8_t> out_whole, out_footprint;
    for (int i = 0; i < 2 * (iterations + 3); ++i) {
      const bool with_footprint = i % 2 == 1;
      Timing& t = with_footprint ? footprint : whole;
      const std::size_t bytes_before = world.composite_bytes_sent();
      world.barrier();
      const auto start = std::chrono::steady_clock::now();
      if (with_footprint)
        world.composite(frame.colour, frame.depth, width, height, frame.footprint, out_footprint);
      else
        world.composite(frame.colour, frame.depth, width, height, out_whole);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      if (i >= 6) t.ms.push_back(ms);  // three warm-up frames each (first touch of the buffers, MPI's connections)
      t.bytes = static_cast<double>(world.composite_bytes_sent() - bytes_before);
    }
    if (world.rank() == 0 && out_whole != out_footprint) same = false;
    const auto slowest = [&](double v) {
      const std::vector<double> all = world.all_gather(v);
      return *std::max_element(all.begin(), all.end());
    };
    const double whole_mean = slowest(mean_of(whole.ms)), whole_p95 = slowest(p95_of(whole.ms));
    const double fp_mean = slowest(mean_of(footprint.ms)), fp_p95 = slowest(p95_of(footprint.ms));
    const std::vector<double> whole_bytes = world.all_gather(whole.bytes), fp_bytes = world.all_gather(footprint.bytes);
    const std::vector<double> area = world.all_gather(100.0 * static_cast<double>(frame.footprint.area()) /
                                                      (static_cast<double>(width) * static_cast<double>(height)));
    if (world.rank() != 0) continue;
    const auto list = [](const std::vector<double>& v, const char* format) {
      std::string s = "[";
      char buf[64];
      for (std::size_t r = 0; r < v.size(); ++r) {
        std::snprintf(buf, sizeof buf, format, v[r]);
        if (r) s += ',';
        s += buf;
      }
      return s + "]";
    };
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "%s\"%s\":{\"whole_frame_ms_mean\":%.3f,\"whole_frame_ms_p95\":%.3f,\"footprint_ms_mean\":%.3f,"
                  "\"footprint_ms_p95\":%.3f,\"speedup\":%.2f,",
                  layout == Layout::Scattered ? "" : ",", name, whole_mean, whole_p95, fp_mean, fp_p95,
                  fp_mean > 0 ? whole_mean / fp_mean : 0.0);
    json += buf;
    json += "\"footprint_pct_per_rank\":" + list(area, "%.1f") + ",\"whole_frame_bytes_per_rank\":" +
            list(whole_bytes, "%.0f") + ",\"footprint_bytes_per_rank\":" + list(fp_bytes, "%.0f") + "}";
  }
  if (world.rank() == 0) {
    json += "},\"same_image\":" + std::string(same ? "true" : "false") + "}";
    std::printf("%s\n", json.c_str());
  }
  return same ? 0 : 1;
}
