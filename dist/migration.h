#pragma once
// Walkers changing process: when a walker's owner changes (it crossed a border, or the slabs were recut), the
// old owner sends its whole row — every field of its walker table, in the slot (level-of-detail table) it sits
// in — and the new owner moves the walker into that slot and overwrites its row. The walker then continues
// exactly as one process would have continued it, bit for bit (tests/dist/distribution_test.cpp).
//
// Rejected: letting the new owner restart the walk from the gait clock, which every process keeps for every
// walker (what a walker coming back into the camera's view does). It costs no bytes, but a restarted walk is a
// settled pose, not the continuing one: its feet and pelvis differ from the continuous walk's by millimetres,
// and the single-process and distributed runs then diverge.
//
// Bytes: per walker 12 bytes of header and the row (3.3 KB for a 25-joint walker at a mesh level; 124 bytes for
// an impostor), only for walkers that change owner: bytes grow with the traffic across borders, not with the
// crowd.
#include <cstdint>
#include <span>
#include <vector>

#include "scene/crowd.h"

namespace strata {

// Appends to `out` each of `walkers` (alive in `crowd`): its handle, its slot, and its row.
void pack_walkers(const Crowd& crowd, std::span<const Entity> walkers, std::vector<std::uint8_t>& out);
// Applies what pack_walkers wrote (several packs may be concatenated): each walker moved into its sender's slot
// and its row overwritten. Returns the walkers received. Throws std::runtime_error on malformed bytes or a walker
// this crowd does not have (the processes' crowds must be built from the same inputs), before changing anything.
std::size_t unpack_walkers(Crowd& crowd, std::span<const std::uint8_t> bytes);

}  // namespace strata
