#pragma once
// Steered agents over several processes (scene/crowd_agents.h AgentExchange): each process steers, plans and
// moves only the agents it owns, and two decisions read other processes' agents.
//
//   avoidance  an agent's new velocity depends on its neighbours within neighbor_distance, and (second pass) on
//              those neighbours' first answers, which depend on theirs: so each process receives, as ghosts, every
//              agent within two neighbour distances (plus a margin) of its slab. Ghosts are solved beside the own
//              agents, in entity order, and dropped: the own agents' answers are one process's, bit for bit.
//   planning   the step's budget of path plans goes to the whole crowd's most urgent requests: each process
//              offers its own most urgent (a budget's worth), every process picks the same best of all offers.
//
// Bytes per step and process: 36 per ghost (the agents within a band of a border: they grow with the border's
// length, not the crowd) and 8 per plan offer (the budget, 24 by default, per process).
//
// Rejected: every process steering every agent (what the first distributed version did). Exact with no
// messages, but each process then pays for the whole crowd's navigation and avoidance: at 100,000 agents about
// ten times the 10,000-agent avoidance step on every rank, which no number of ranks divides.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "dist/partition.h"
#include "scene/crowd_agents.h"
#include "scene/crowd_metrics.h"

namespace strata {

// How far from its slab a process must see other processes' agents: two neighbour distances (a neighbour's
// first-pass answer enters the second pass) plus 1 m, more than an agent moves between the slab cut (made from
// the walkers' placements at the step's start) and avoidance (after steering).
float ghost_reach(const AvoidanceParameters& params);

// Per rank, the bytes of those of `mine` within `reach` of that rank's slab (nothing for `rank` itself).
std::vector<std::vector<std::uint8_t>> pack_ghosts(std::span<const AgentSnapshot> mine,
                                                   const CrowdPartition& partition, int rank, float reach);
// Appends the agents in `bytes` (several packs may be concatenated) to `out`. Throws std::runtime_error for a
// length that is not whole agents or a value avoidance would refuse (non-finite, radius <= 0), appending nothing.
void unpack_ghosts(std::span<const std::uint8_t> bytes, std::vector<AgentSnapshot>& out);

// `strata report crowd`: per rank, the bytes of those of `mine` within `reach` of that rank's slab (nothing for
// `rank` itself), 16 bytes each (entity index, position, radius: what a pair's clearance needs). Agents with a
// non-finite position or radius are not sent (the metrics leave them out of pairs anyway).
std::vector<std::vector<std::uint8_t>> pack_border_observations(std::span<const AgentObservation> mine,
                                                                const CrowdPartition& partition, int rank, float reach);
// Appends the observations in `bytes` to `out` (index, position and radius; the rest zero). Throws
// std::runtime_error for a length that is not whole observations or a non-finite value, appending nothing.
void unpack_border_observations(std::span<const std::uint8_t> bytes, std::vector<AgentObservation>& out);

// A process's plan offers: urgency and entity index of each candidate.
std::vector<std::uint8_t> pack_plan_offers(std::span<const PlanCandidate> mine);
// Keeps in `mine` the candidates that are among the `take` most urgent of every process's offers (`offers`, the
// packs of every process concatenated, this one's included). Throws std::runtime_error on malformed bytes.
void keep_most_urgent(std::vector<PlanCandidate>& mine, std::span<const std::uint8_t> offers, std::size_t take);

}  // namespace strata
