#include "dist/mpi_world.h"

#include <chrono>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include <mpi.h>

#include "dist/composite.h"

namespace strata {
namespace {

void check(int rc, const char* call) {
  if (rc == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(rc, text, &length);
  throw std::runtime_error(std::string(call) + " failed: " + std::string(text, static_cast<std::size_t>(length)));
}

int as_count(std::size_t n, const char* what) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error(std::string(what) + ": more than 2^31 elements in one message");
  return static_cast<int>(n);
}

}  // namespace

bool MpiWorld::launched() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(var)) return true;
  return false;
}

MpiWorld::MpiWorld() {
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

MpiWorld::~MpiWorld() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

std::string MpiWorld::processor_name() const {
  char name[MPI_MAX_PROCESSOR_NAME];
  int length = 0;
  MPI_Get_processor_name(name, &length);
  return std::string(name, static_cast<std::size_t>(length));
}

bool MpiWorld::all_ok(bool ok) {
  int mine = ok ? 1 : 0, all = 0;
  check(MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  bytes_sent_ += sizeof(int);
  return all == 1;
}

void MpiWorld::min_max(std::span<float> lo, std::span<float> hi) {
  const int n = as_count(lo.size(), "min_max");
  if (hi.size() != lo.size()) throw std::invalid_argument("MpiWorld::min_max: lo and hi differ in size");
  check(MPI_Allreduce(MPI_IN_PLACE, lo.data(), n, MPI_FLOAT, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  check(MPI_Allreduce(MPI_IN_PLACE, hi.data(), n, MPI_FLOAT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  bytes_sent_ += 2 * lo.size() * sizeof(float);
}

void MpiWorld::sum(std::span<std::uint32_t> values) {
  check(MPI_Allreduce(MPI_IN_PLACE, values.data(), as_count(values.size(), "sum"), MPI_UINT32_T, MPI_SUM, MPI_COMM_WORLD),
        "MPI_Allreduce");
  bytes_sent_ += values.size() * sizeof(std::uint32_t);
}

std::vector<double> MpiWorld::all_gather(double value) {
  std::vector<double> all(static_cast<std::size_t>(size_));
  check(MPI_Allgather(&value, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD), "MPI_Allgather");
  bytes_sent_ += sizeof(double);
  return all;
}

std::vector<std::uint8_t> MpiWorld::gather_to_root(std::span<const std::uint8_t> bytes,
                                                   std::vector<std::size_t>& sizes) {
  const int mine = as_count(bytes.size(), "gather_to_root");
  std::vector<int> counts(rank_ == 0 ? static_cast<std::size_t>(size_) : 0);
  check(MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  std::vector<int> displs(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    displs[r] = as_count(total, "gather_to_root");
    total += static_cast<std::size_t>(counts[r]);
  }
  std::vector<std::uint8_t> all(total);
  check(MPI_Gatherv(bytes.data(), mine, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0, MPI_COMM_WORLD),
        "MPI_Gatherv");
  bytes_sent_ += rank_ == 0 ? 0 : bytes.size() + sizeof(int);
  sizes.assign(counts.begin(), counts.end());
  return all;
}

void MpiWorld::barrier() { check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier"); }

std::vector<std::uint8_t> MpiWorld::exchange(const std::vector<std::vector<std::uint8_t>>& to_rank) {
  const auto ranks = static_cast<std::size_t>(size_);
  if (to_rank.size() != ranks) throw std::invalid_argument("MpiWorld::exchange: one buffer per rank expected");
  std::vector<int> send_counts(ranks), send_at(ranks), recv_counts(ranks), recv_at(ranks);
  std::vector<std::uint8_t> send;
  for (std::size_t r = 0; r < ranks; ++r) {
    send_at[r] = as_count(send.size(), "exchange");
    send_counts[r] = as_count(to_rank[r].size(), "exchange");
    send.insert(send.end(), to_rank[r].begin(), to_rank[r].end());
    if (r != static_cast<std::size_t>(rank_)) bytes_sent_ += to_rank[r].size() + sizeof(int);
  }
  check(MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Alltoall");
  std::size_t total = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    recv_at[r] = as_count(total, "exchange");
    total += static_cast<std::size_t>(recv_counts[r]);
  }
  std::vector<std::uint8_t> received(total);
  check(MPI_Alltoallv(send.data(), send_counts.data(), send_at.data(), MPI_BYTE, received.data(), recv_counts.data(),
                      recv_at.data(), MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Alltoallv");
  return received;
}

void MpiWorld::composite(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, int height,
                         std::vector<std::uint8_t>& out) {
  const auto pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (width <= 0 || height <= 0 || pixels.size() != 4 * pixel_count || depth.size() != pixel_count)
    throw std::invalid_argument("MpiWorld::composite: the frame's colour and depth do not match its size");
  const auto ranks = static_cast<std::size_t>(size_);
  // Bands are contiguous rows in rank order, so the frame itself is the send buffer: band k starts where band
  // k-1 ends.
  std::vector<int> send_px(ranks), send_px_at(ranks), send_d(ranks), send_d_at(ranks);
  for (int k = 0; k < size_; ++k) {
    const auto [first, last] = band_rows(height, size_, k);
    const auto uk = static_cast<std::size_t>(k);
    send_d_at[uk] = as_count(static_cast<std::size_t>(first) * static_cast<std::size_t>(width), "composite");
    send_d[uk] = as_count(static_cast<std::size_t>(last - first) * static_cast<std::size_t>(width), "composite");
    send_px_at[uk] = 4 * send_d_at[uk];
    send_px[uk] = 4 * send_d[uk];
  }
  const auto mine = static_cast<std::size_t>(rank_);
  const std::size_t band = static_cast<std::size_t>(send_d[mine]);
  recv_pixels_.resize(4 * band * ranks);
  recv_depth_.resize(band * ranks);
  std::vector<int> recv_px(ranks, static_cast<int>(4 * band)), recv_px_at(ranks), recv_d(ranks, static_cast<int>(band)),
      recv_d_at(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    recv_d_at[r] = as_count(r * band, "composite");
    recv_px_at[r] = as_count(4 * r * band, "composite");
  }
  using clock = std::chrono::steady_clock;
  const auto ms_since = [](clock::time_point t) {
    return std::chrono::duration<double, std::milli>(clock::now() - t).count();
  };
  auto t = clock::now();
  check(MPI_Alltoallv(pixels.data(), send_px.data(), send_px_at.data(), MPI_BYTE, recv_pixels_.data(), recv_px.data(),
                      recv_px_at.data(), MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Alltoallv");
  check(MPI_Alltoallv(depth.data(), send_d.data(), send_d_at.data(), MPI_FLOAT, recv_depth_.data(), recv_d.data(),
                      recv_d_at.data(), MPI_FLOAT, MPI_COMM_WORLD),
        "MPI_Alltoallv");
  std::size_t sent = 0;
  for (std::size_t r = 0; r < ranks; ++r)
    if (r != mine) sent += static_cast<std::size_t>(send_px[r]) + 4 * static_cast<std::size_t>(send_d[r]);
  times_.exchange_ms = ms_since(t);
  t = clock::now();
  // Fold the band: rank 0's piece first, then the others (the rules are order-free; a fixed order anyway).
  band_pixels_.assign(recv_pixels_.begin(), recv_pixels_.begin() + static_cast<std::ptrdiff_t>(4 * band));
  band_depth_.assign(recv_depth_.begin(), recv_depth_.begin() + static_cast<std::ptrdiff_t>(band));
  for (std::size_t r = 1; r < ranks; ++r)
    composite_nearest(band_pixels_, band_depth_,
                      std::span<const std::uint8_t>(recv_pixels_.data() + 4 * r * band, 4 * band),
                      std::span<const float>(recv_depth_.data() + r * band, band));
  times_.fold_ms = ms_since(t);
  t = clock::now();
  // Rank 0 gathers the folded bands, in rank order = row order.
  out.clear();
  if (rank_ == 0) out.resize(4 * pixel_count);
  check(MPI_Gatherv(band_pixels_.data(), static_cast<int>(4 * band), MPI_BYTE, out.data(), send_px.data(),
                    send_px_at.data(), MPI_BYTE, 0, MPI_COMM_WORLD),
        "MPI_Gatherv");
  times_.gather_ms = ms_since(t);
  if (rank_ != 0) sent += 4 * band;
  composite_bytes_ += sent;
  bytes_sent_ += sent;
}

void MpiWorld::abort(int code) {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);  // MPI_Abort does not return; should it, nothing else may run
}

}  // namespace strata
