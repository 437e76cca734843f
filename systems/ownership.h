#pragma once
// Ownership: which walkers this process animates, skins and draws when one crowd is spread over several
// processes (dist/, `mpirun -np K strata crowd`). Each process owns the walkers standing in its slab of the ground
// (an interval along x or z, dist/partition.h); the rest it keeps as culled walkers, which in a walking crowd
// only advance their gait clock along their path (simulation level of detail, scene/crowd.h). So ownership is
// one more culling rule applied after the camera's: a walker outside the slab is decided `culled_slot`, and the
// frame's later stages skip it exactly as they skip a walker behind the camera. A walker that crosses into the
// slab leaves the culled table and its walk restarts from the phase and path distance its clock kept, as a
// walker coming back into view does (scene/step.cpp restart_walks).
//
// Rejected: exchanging walkers' rows between processes when they cross a border (migration). A walking walker's
// whole state is its clock and path position, which every process advances anyway for a few nanoseconds a
// walker, so a crossing costs no bytes; the rows (kilobytes a walker) would.
//
// Reads: placement (x and z, components 0 and 2) of `walkers` rows, `stride` apart. Writes: decided[w] =
// culled_slot for every walker outside [lo, hi) along `axis`; leaves the others' decisions as they are.
#include <cstddef>
#include <cstdint>
#include <span>

namespace strata {

struct OwnershipRegion {
  int axis = 0;       // 0: x, 2: z (the placement component that is cut)
  float lo = 0.0f;    // owned: lo <= coordinate < hi; -infinity and +infinity open the end slabs
  float hi = 0.0f;
  bool owns(float x, float z) const {
    const float c = axis == 0 ? x : z;
    return c >= lo && c < hi;
  }
};

struct OwnershipJob {
  const OwnershipRegion* region = nullptr;
  std::uint8_t culled_slot = 4;
  std::size_t walkers = 0;
  std::size_t stride = 0;
  const float* placement = nullptr;
  std::span<std::uint8_t> decided;

  // region set with axis 0 or 2 and lo <= hi (not NaN); placement set for a non-empty table; stride >= walkers;
  // decided.size() == walkers.
  bool validate() const;
  bool run() const;
};

}  // namespace strata
