#pragma once
// Ownership: which walkers this process animates, skins and draws when one crowd is spread over several
// processes (dist/, `mpirun -np K strata crowd`). Each process owns the walkers standing in its slab of the ground
// (an interval along x or z, dist/partition.h). The walkers other processes own are not in its walker tables at
// all (dist/migration.h keeps them in the crowd's remote table, and a walker changing owner travels with its
// row), so the tables hold this process's walkers; this job is the culling rule for the rest it still holds:
// a walker with no finite placement, which nobody owns and every process keeps, is decided `culled_slot`, and
// the frame's later stages skip it exactly as they skip a walker behind the camera.
//
// Rejected: the slab as the only mechanism, every process holding and advancing every walker and culling the
// others here. No bytes for walkers crossing a border, but every process stepped and stored the whole crowd
// (about 1.5 GB a rank at 100,000 walkers over 8 ranks), and a walker entering a slab restarted its walk from the
// clock rather than continuing it.
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
