// Sort-last compositing cost (dist/mpi_world.h MpiWorld::composite): `mpirun -np K strata_bench_composite
// [WIDTH HEIGHT ITERATIONS]` composites a WIDTHxHEIGHT RGBA8 + float depth frame from every rank onto rank 0,
// ITERATIONS times after a barrier each, and rank 0 prints the slowest rank's mean and p95 (ms) and the bytes each
// rank sent per frame as one JSON line. The frames are a crowd frame's make-up (a ground every rank draws the same,
// so that most pixels are depth ties, and each rank's own walkers in front of it).
// Not a Google Benchmark suite: every iteration is a collective, and each rank must time the same iterations.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "dist/mpi_world.h"

int main(int argc, char** argv) {
  const int width = argc > 1 ? std::atoi(argv[1]) : 1280;
  const int height = argc > 2 ? std::atoi(argv[2]) : 720;
  const int iterations = argc > 3 ? std::atoi(argv[3]) : 100;
  if (width <= 0 || height <= 0 || iterations <= 0) {
    std::fprintf(stderr, "usage: mpirun -np K strata_bench_composite [WIDTH HEIGHT ITERATIONS]\n");
    return 2;
  }
  strata::MpiWorld world;
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  // A crowd frame's make-up: the sky (depth 1) above the horizon and the ground below it, the same on every rank
  // (every rank draws the ground), and this rank's walkers: 400 upright rectangles in front of the ground, about
  // a tenth of the frame, their own colours.
  std::mt19937 rng(static_cast<unsigned>(world.rank() + 1));
  std::vector<std::uint8_t> colour(4 * pixels);
  std::vector<float> depth(pixels);
  const int horizon = height / 3;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
      const bool ground = y > horizon;
      depth[i] = ground ? 1.0f - 0.5f * static_cast<float>(y - horizon) / static_cast<float>(height) : 1.0f;
      const auto shade = static_cast<std::uint8_t>(ground ? 60 + (x / 16 + y / 16) % 2 * 10 : 40);
      colour[4 * i] = colour[4 * i + 1] = colour[4 * i + 2] = shade;
      colour[4 * i + 3] = 255;
    }
  std::uniform_int_distribution<int> px(0, width - 1), py(horizon, height - 1), size(4, 40), byte(0, 255);
  for (int w = 0; w < 400; ++w) {
    const int x0 = px(rng), y1 = py(rng), h = size(rng) * 2, wd = std::max(2, h / 4);
    const float d = depth[static_cast<std::size_t>(y1) * static_cast<std::size_t>(width)] - 0.01f;
    const auto c = static_cast<std::uint8_t>(byte(rng));
    for (int y = std::max(0, y1 - h); y <= y1; ++y)
      for (int x = x0; x < std::min(width, x0 + wd); ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
        if (d < depth[i]) depth[i] = d, colour[4 * i] = c, colour[4 * i + 1] = c / 2, colour[4 * i + 2] = 255 - c;
      }
  }
  std::vector<std::uint8_t> out;
  std::vector<double> ms;
  double exchange = 0, fold = 0, gather = 0;
  for (int i = 0; i < iterations + 3; ++i) {
    world.barrier();
    const auto start = std::chrono::steady_clock::now();
    world.composite(colour, depth, width, height, out);
    const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (i >= 3) {  // three warm-up frames (first-touch of the buffers, MPI's connections)
      ms.push_back(t);
      const strata::MpiWorld::CompositeTimes stage = world.last_composite_times();
      exchange += stage.exchange_ms, fold += stage.fold_ms, gather += stage.gather_ms;
    }
  }
  std::sort(ms.begin(), ms.end());
  double mean = 0;
  for (double t : ms) mean += t;
  mean /= static_cast<double>(ms.size());
  const double p95 = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(ms.size())))];
  const std::vector<double> means = world.all_gather(mean), p95s = world.all_gather(p95);
  const std::vector<double> stages = {exchange / iterations, fold / iterations, gather / iterations};
  const std::vector<double> exchange_ms = world.all_gather(stages[0]), fold_ms = world.all_gather(stages[1]),
                            gather_ms = world.all_gather(stages[2]);
  const std::vector<double> bytes =
      world.all_gather(static_cast<double>(world.composite_bytes_sent()) / static_cast<double>(iterations + 3));
  if (world.rank() == 0) {
    std::printf("{\"ranks\":%d,\"width\":%d,\"height\":%d,\"iterations\":%d,\"composite_ms_mean_slowest_rank\":%.3f,"
                "\"composite_ms_p95_slowest_rank\":%.3f,\"bytes_sent_per_frame\":[",
                world.size(), width, height, iterations, *std::max_element(means.begin(), means.end()),
                *std::max_element(p95s.begin(), p95s.end()));
    for (std::size_t r = 0; r < bytes.size(); ++r) std::printf("%s%.0f", r ? "," : "", bytes[r]);
    std::printf("],\"stages_ms_slowest_rank\":{\"exchange\":%.3f,\"fold\":%.3f,\"gather\":%.3f}}\n",
                *std::max_element(exchange_ms.begin(), exchange_ms.end()), *std::max_element(fold_ms.begin(), fold_ms.end()),
                *std::max_element(gather_ms.begin(), gather_ms.end()));
  }
  return 0;
}
