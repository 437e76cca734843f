#pragma once
// What a crowd's bodies are drawn with, kept consistent with its rig: the detail level, the muscle layer and its
// gains, and the skin weights (the binding editor's edits). Each call rebuilds the derived per-rig resources the
// skin stage reads (skin layouts per mesh level, the refined cage, muscle coefficients) once, here, so that
// step() never builds anything.
#include <memory>

#include "scene/crowd.h"

namespace strata {

// Asks for a detail level. The level used (crowd.skin.level) is the request clamped to what the rig's body has:
// none without a body, the coarsest mesh level for a higher index, mesh 0 for S levels on a body without a cage.
// When the level used changes, every walker moves to the new level's first table (initial_slot) at once; with a
// camera, the next step() culls and levels them. Cheap to call at run time: a subdivided surface is built once
// per rig.
void set_detail_level(Crowd& crowd, DetailLevel level);
// Muscle layer on or off (on by default when the rig has one). Off skips the muscle stage and skins without
// displacement (the layouts are rebuilt without muscle groups).
void set_muscles_enabled(Crowd& crowd, bool on);
// Picks how joints are blended (linear blending, dual quaternions, centres of rotation) for every level at run
// time. CentresOfRotation installs the body's centres in the layouts in use (computed once per body level on
// first request, cached on disk: rig/cor_centres.h), so the first switch to it may take a moment; later
// switches and level changes reuse them.
void set_skinning_mode(Crowd& crowd, SkinningMode mode);
// Scales every muscle's forces at run time (the paper's users edited force values); only vertices bound to a
// changed muscle move.
void set_muscle_gains(Crowd& crowd, MuscleGains gains);
// Swaps the rig's body for one with the same meshes and new weights (the binding editor's edits): the layouts
// are rebuilt, the muscle binding (which depends on rest positions only) is kept. Throws std::invalid_argument
// when a level's vertex count differs or the crowd has no body. The rig is replaced by an edited copy (rigs are
// immutable and may be shared), so references into crowd.rig() taken before the call dangle.
void set_body(Crowd& crowd, std::shared_ptr<const Body> body);

// The table a walker goes to before any camera has seen it: the finest slot of the level used (the impostor
// table under DetailLevel::impostor, or the skeleton-only table when this crowd cannot have impostors).
DetailSlot initial_slot(const Crowd& crowd);
// The table a new walker is put in: initial_slot, except that a walking crowd under DetailLevel::automatic starts
// its walkers as impostors, so spawning 100,000 of them never holds 100,000 wide rows (tables grow and never
// shrink); the first step() gives the near ones their meshes (all of them, without a camera), restarting their
// walk.
DetailSlot spawn_slot(const Crowd& crowd);
// Impostors show the baked walk, so only a walking crowd with a body has them; clip and capture crowds keep every
// visible walker a mesh (their motion is not the walk the atlas holds).
bool crowd_may_use_impostors(const Crowd& crowd);
// The vertex grouping of the mesh level used (DetailLevel::mesh), or of level 0 under automatic; empty at S
// levels (the cage's is crowd.skin.subdiv->cage_layout) and without a body.
const SkinLayout& current_layout(const Crowd& crowd);
// The skinned storage of the level used (mesh k, or the refined cage at S levels; level 0's under automatic),
// as the last step() left it; for tests and tools that look at one level.
const SkinnedCrowd& current_skinned(const Crowd& crowd);
// The triangles current_skinned() is drawn with: the layout's (its vertex order) or the refined cage's.
const std::vector<std::uint32_t>& current_triangles(const Crowd& crowd);

}  // namespace strata
