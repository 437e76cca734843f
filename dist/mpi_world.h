#pragma once
// The one process group a distributed run is (OpenMPI's MPI_COMM_WORLD), and the few collectives the crowd needs:
// agreeing on bounds and on failure, gathering reports to rank 0, and compositing the frame (dist/composite.h) by
// direct send: the image is cut into one band of rows per rank, every rank sends the part of each band inside its
// footprint (the pixels its walkers and their shadows touch) to the rank that owns the band (one MPI_Alltoallv),
// each rank folds those pieces into its own frame's band, and rank 0 gathers the bands.
//
// Why direct send (radix-k with a single round of k = ranks) rather than IceT or binary swap: IceT ships on Debian
// only inside ParaView's VTK (libvtkIceTCore/libvtkIceTMPI and paraview-dev's headers, a few hundred MB of
// packages for one compositor, and its MPI layer built against ParaView's), and binary swap needs a power of two
// ranks and log2 K rounds of messages where direct send has one; at the rank counts of one machine to a few nodes
// the bytes each rank sends are the same ((K-1)/K of its frame), and on one machine the exchange is a memory copy.
// docs/scale-out.md has the measured times.
//
// Every MPI call's error is returned (MPI_ERRORS_RETURN) and thrown as std::runtime_error naming the call, so a
// failure ends in the command's one error line rather than MPI's default abort text.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "dist/composite.h"

namespace strata {

class MpiWorld {
 public:
  // True when this process was started by mpirun / mpiexec (OpenMPI's or a PMI launcher's environment).
  static bool launched();
  // MPI_Init (only the calling thread makes MPI calls). Throws std::runtime_error when it fails.
  MpiWorld();
  ~MpiWorld();
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  std::string processor_name() const;

  // True on every rank when `ok` is true on every rank.
  bool all_ok(bool ok);
  // Element-wise: lo becomes the minimum over ranks, hi the maximum.
  void min_max(std::span<float> lo, std::span<float> hi);
  // Element-wise sum over ranks, in place.
  void sum(std::span<std::uint32_t> values);
  // The values of every rank, in rank order, on every rank.
  std::vector<double> all_gather(double value);
  // Rank 0 receives every rank's bytes concatenated in rank order and each rank's size; the others get empties.
  std::vector<std::uint8_t> gather_to_root(std::span<const std::uint8_t> bytes, std::vector<std::size_t>& sizes);
  void barrier();
  // Sends to_rank[r] to rank r (every rank at once; empty buffers allowed) and returns what every rank sent this
  // one, concatenated in rank order. to_rank must have one buffer per rank.
  std::vector<std::uint8_t> exchange(const std::vector<std::vector<std::uint8_t>>& to_rank);

  // Composites every rank's `pixels` (RGBA8, rows top to bottom) and `depth` (one float a pixel, same rows) into
  // `out` on rank 0 (the others' `out` is left empty). Counts the bytes this rank sent. With a `footprint`, the
  // pixels outside it must be the scene every rank draws alike (dist/composite.h): only the footprint's part of
  // each band is sent. Without, the whole frame is.
  void composite(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, int height,
                 ImageRect footprint, std::vector<std::uint8_t>& out);
  void composite(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, int height,
                 std::vector<std::uint8_t>& out);

  // The last composite()'s stages on this rank (ms): the exchange of bands, the fold of this rank's band, the
  // gather onto rank 0.
  struct CompositeTimes {
    double exchange_ms = 0, fold_ms = 0, gather_ms = 0;
  };
  CompositeTimes last_composite_times() const { return times_; }
  // Bytes this rank has sent since construction (compositing, gathers, reductions), and those of compositing.
  std::size_t bytes_sent() const { return bytes_sent_; }
  std::size_t composite_bytes_sent() const { return composite_bytes_; }
  // The pixels of this rank's footprints summed over every composite() since construction.
  std::size_t footprint_pixels() const { return footprint_pixels_; }

  // Ends every rank of the job now (MPI_Abort) with exit status `code`.
  [[noreturn]] void abort(int code);

 private:
  int rank_ = 0, size_ = 1;
  std::size_t bytes_sent_ = 0, composite_bytes_ = 0, footprint_pixels_ = 0;
  CompositeTimes times_;
  // Compositing scratch, grown, never shrunk.
  std::vector<std::uint8_t> send_pixels_, recv_pixels_, band_pixels_;
  std::vector<float> send_depth_, recv_depth_, band_depth_;
};

}  // namespace strata
