#pragma once
// Walkers changing process: when a walker's owner changes (it crossed a border, or the slabs were recut), the
// old owner sends its whole row — every field of its walker table, in the slot (level-of-detail table) it sits
// in — and the new owner moves the walker into that slot and overwrites its row. The walker then continues
// exactly as one process would have continued it, bit for bit (tests/dist/distribution_test.cpp).
//
// A process keeps the walkers others own only as handles, in the crowd's remote table, which no stage reads: it
// spends nothing on them, and their rows live only with their owners (about 270 bytes a remote walker instead of
// a full row's kilobytes).
//
// Rejected: every process advancing every walker's gait clock and letting a new owner restart the walk from it
// (what a walker coming back into the camera's view does). It costs no bytes, but a restarted walk is a settled
// pose, not the continuing one: its feet and pelvis differ from the continuous walk's by millimetres, and the
// single-process and distributed runs then diverge; and every process would pay for, and store, the whole crowd.
//
// Bytes: per walker 12 bytes of header and the row (3.3 KB for a 25-joint walker at a mesh level; 124 bytes for
// an impostor), only for walkers that change owner: bytes grow with the traffic across borders, not with the
// crowd.
#include <cstdint>
#include <span>
#include <vector>

#include "dist/partition.h"
#include "scene/crowd.h"

namespace strata {

// Appends to `out` each of `walkers` (alive in `crowd`): its handle, its slot, and its row.
void pack_walkers(const Crowd& crowd, std::span<const Entity> walkers, std::vector<std::uint8_t>& out);
// Applies what pack_walkers wrote (several packs may be concatenated): each walker moved (from the remote table,
// or wherever it is) into its sender's slot and its row overwritten. Returns the walkers received. Throws
// std::runtime_error on malformed bytes or a walker this crowd does not have (the processes' crowds must be built
// from the same inputs), before changing anything.
std::size_t unpack_walkers(Crowd& crowd, std::span<const std::uint8_t> bytes);

// Held walkers: those of `crowd` not in its remote table (scene/crowd.h), the ones this process steps.
//
// The start of a distributed run, where every process built the same crowd: the walkers whose owner under
// `partition` is another rank move into the remote table. A walker nobody owns (no finite placement) stays held
// everywhere, culled by the ownership rule. Returns the walkers this rank owns.
std::size_t keep_owned(Crowd& crowd, const CrowdPartition& partition, int rank);
// Each step after: per rank, the packed rows of the held walkers that `partition` now gives to that rank, which
// move into the remote table here. `leaving` counts them.
std::vector<std::vector<std::uint8_t>> pack_leaving(Crowd& crowd, const CrowdPartition& partition, int rank,
                                                    std::size_t& leaving);
// Appends the placements (x, z) of the held walkers to xs and zs, table by table: what a recut counts
// (dist/partition.h).
void held_placements(const Crowd& crowd, std::vector<float>& xs, std::vector<float>& zs);

}  // namespace strata
