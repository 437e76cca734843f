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
  if (hi.size() != lo.size()) throw std::invalid_argument("MpiWorld::min_max: lo and hi differ in size");
  // One reduction: the maxima as negated minima (negation is exact, so nothing rounds).
  std::vector<float> both(lo.begin(), lo.end());
  for (const float h : hi) both.push_back(-h);
  check(MPI_Allreduce(MPI_IN_PLACE, both.data(), as_count(both.size(), "min_max"), MPI_FLOAT, MPI_MIN, MPI_COMM_WORLD),
        "MPI_Allreduce");
  for (std::size_t i = 0; i < lo.size(); ++i) lo[i] = both[i], hi[i] = -both[lo.size() + i];
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
  composite(pixels, depth, width, height, ImageRect{0, 0, width, height}, out);
}

void MpiWorld::composite(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, int height,
                         ImageRect footprint, std::vector<std::uint8_t>& out) {
  const auto pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (width <= 0 || height <= 0 || pixels.size() != 4 * pixel_count || depth.size() != pixel_count)
    throw std::invalid_argument("MpiWorld::composite: the frame's colour and depth do not match its size");
  const auto ranks = static_cast<std::size_t>(size_);
  const auto mine = static_cast<std::size_t>(rank_);
  using clock = std::chrono::steady_clock;
  const auto ms_since = [](clock::time_point t) {
    return std::chrono::duration<double, std::milli>(clock::now() - t).count();
  };
  auto t = clock::now();
  // Every rank's footprint, so that each knows what it receives (16 bytes a rank).
  footprint = clip_rect(footprint, width, height);
  std::vector<ImageRect> footprints(ranks);
  check(MPI_Allgather(&footprint, 4, MPI_INT, footprints.data(), 4, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  // A footprint as wide as the frame sends straight from the frame (its pieces are runs of whole rows, as the
  // bands); a narrower one is packed row by row first. Colour and depth travel in two exchanges, so neither needs
  // converting.
  const bool whole_rows = footprint.x0 == 0 && footprint.x1 == width;
  std::vector<int> send_px(ranks), send_px_at(ranks), send_d(ranks), send_d_at(ranks);
  send_pixels_.clear();
  send_depth_.clear();
  std::size_t sent = sizeof(ImageRect);
  for (std::size_t k = 0; k < ranks; ++k) {
    const ImageRect piece = k == mine ? ImageRect{} : band_piece(footprint, height, size_, static_cast<int>(k));
    if (whole_rows) {
      send_d_at[k] = as_count(static_cast<std::size_t>(piece.y0) * static_cast<std::size_t>(width), "composite");
    } else {
      send_d_at[k] = as_count(send_depth_.size(), "composite");
      pack_piece(pixels, depth, width, piece, send_pixels_, send_depth_);
    }
    send_d[k] = as_count(piece.area(), "composite");
    send_px[k] = 4 * send_d[k], send_px_at[k] = 4 * send_d_at[k];
    sent += 8 * piece.area();
  }
  std::vector<int> recv_px(ranks), recv_px_at(ranks), recv_d(ranks), recv_d_at(ranks);
  std::size_t received = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    recv_d_at[r] = as_count(received, "composite");
    recv_d[r] = r == mine ? 0 : as_count(band_piece(footprints[r], height, size_, rank_).area(), "composite");
    recv_px[r] = 4 * recv_d[r], recv_px_at[r] = 4 * recv_d_at[r];
    received += static_cast<std::size_t>(recv_d[r]);
  }
  recv_pixels_.resize(4 * received);
  recv_depth_.resize(received);
  check(MPI_Alltoallv(whole_rows ? pixels.data() : send_pixels_.data(), send_px.data(), send_px_at.data(), MPI_BYTE,
                      recv_pixels_.data(), recv_px.data(), recv_px_at.data(), MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Alltoallv");
  check(MPI_Alltoallv(whole_rows ? depth.data() : send_depth_.data(), send_d.data(), send_d_at.data(), MPI_FLOAT,
                      recv_depth_.data(), recv_d.data(), recv_d_at.data(), MPI_FLOAT, MPI_COMM_WORLD),
        "MPI_Alltoallv");
  times_.exchange_ms = ms_since(t);
  t = clock::now();
  // Fold the band: this rank's own rows whole (outside the others' footprints they hold what the others drew
  // too), then the others' pieces in rank order (the rules are order-free; a fixed order anyway).
  const auto [first, last] = band_rows(height, size_, rank_);
  const std::size_t band_at = static_cast<std::size_t>(first) * static_cast<std::size_t>(width);
  const std::size_t band = static_cast<std::size_t>(last - first) * static_cast<std::size_t>(width);
  band_pixels_.assign(pixels.begin() + static_cast<std::ptrdiff_t>(4 * band_at),
                      pixels.begin() + static_cast<std::ptrdiff_t>(4 * (band_at + band)));
  band_depth_.assign(depth.begin() + static_cast<std::ptrdiff_t>(band_at),
                     depth.begin() + static_cast<std::ptrdiff_t>(band_at + band));
  for (std::size_t r = 0; r < ranks; ++r)
    if (r != mine)
      fold_piece(band_pixels_, band_depth_, width, first, band_piece(footprints[r], height, size_, rank_),
                 std::span<const std::uint8_t>(recv_pixels_).subspan(static_cast<std::size_t>(recv_px_at[r]),
                                                                     static_cast<std::size_t>(recv_px[r])),
                 std::span<const float>(recv_depth_).subspan(static_cast<std::size_t>(recv_d_at[r]),
                                                             static_cast<std::size_t>(recv_d[r])));
  times_.fold_ms = ms_since(t);
  t = clock::now();
  // Rank 0 gathers the folded bands, in rank order = row order.
  std::vector<int> band_counts(ranks), band_starts(ranks);
  for (int k = 0; k < size_; ++k) {
    const auto [f, l] = band_rows(height, size_, k);
    band_starts[static_cast<std::size_t>(k)] = as_count(4 * static_cast<std::size_t>(f) * static_cast<std::size_t>(width), "composite");
    band_counts[static_cast<std::size_t>(k)] = as_count(4 * static_cast<std::size_t>(l - f) * static_cast<std::size_t>(width), "composite");
  }
  out.clear();
  if (rank_ == 0) out.resize(4 * pixel_count);
  check(MPI_Gatherv(band_pixels_.data(), as_count(4 * band, "composite"), MPI_BYTE, out.data(), band_counts.data(),
                    band_starts.data(), MPI_BYTE, 0, MPI_COMM_WORLD),
        "MPI_Gatherv");
  times_.gather_ms = ms_since(t);
  if (rank_ != 0) sent += 4 * band;
  footprint_pixels_ += footprint.area();
  composite_bytes_ += sent;
  bytes_sent_ += sent;
}

void MpiWorld::abort(int code) {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);  // MPI_Abort does not return; should it, nothing else may run
}

}  // namespace strata
