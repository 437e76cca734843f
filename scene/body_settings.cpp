#include "scene/body_settings.h"

#include <stdexcept>
#include <string>

#include "rig/cor_centres.h"
#include "rig/muscle_binding.h"
#include "rig/subdiv_topology.h"

namespace strata {
namespace {

// The level the rig's body can give for a request.
DetailLevel usable_level(const Crowd& crowd, DetailLevel requested) {
  const Body* body = crowd.rig().body.get();
  if (!body || body->levels.empty() || requested.is_none()) return DetailLevel::none();
  if (requested.is_subdiv()) return body->cage ? requested : DetailLevel::mesh(0);
  if (requested.is_automatic() || requested.is_impostor()) return requested;
  return DetailLevel::mesh(std::min(requested.index(), static_cast<int>(body->levels.size()) - 1));
}

void rebuild_muscle_coefficients(Crowd& crowd) {
  CrowdSkin& skin = crowd.skin;
  if (!crowd.muscles_enabled()) return;
  const MuscleRig& m = *crowd.rig().muscles;
  if (skin.subdiv) {
    if (m.cage)
      skin.cage_muscles =
          make_muscle_displacement_list(skin.subdiv->cage_layout, *m.cage, muscle_coefficients(m.set, *m.cage, skin.gains));
    return;
  }
  for (std::size_t k = 0; k < skin.layouts.size(); ++k)
    if (skin.layouts[k].has_muscles())
      set_muscle_coefficients(skin.layouts[k], muscle_coefficients(m.set, m.levels[k], skin.gains));
}

void rebuild_layouts(Crowd& crowd) {
  CrowdSkin& skin = crowd.skin;
  skin.level = usable_level(crowd, skin.requested);
  skin.subdiv = skin.level.is_subdiv() ? body_subdiv_surface(*crowd.rig().body, skin.level.index()) : nullptr;
  skin.layouts = {};
  skin.cage_muscles = MuscleDisplacementList{};
  if (skin.level.is_none() || skin.level.is_subdiv() || skin.level.is_impostor()) {
    rebuild_muscle_coefficients(crowd);
    return;
  }
  const Body& body = *crowd.rig().body;
  const bool muscles = crowd.muscles_enabled();
  const std::size_t levels = std::min<std::size_t>(body.levels.size(), kMaxMeshLevels);
  for (std::size_t k = 0; k < levels; ++k) {
    const bool used = skin.level.is_automatic() || static_cast<int>(k) == skin.level.index();
    if (!used) continue;
    skin.layouts[k] = make_skin_layout(body.levels[k], muscles ? &crowd.rig().muscles->levels[k] : nullptr);
    if (skin.mode == SkinningMode::CentresOfRotation)
      set_cor_centres(skin.layouts[k], body_cor_centres(body, static_cast<int>(k))->centres);
  }
  rebuild_muscle_coefficients(crowd);
}

}  // namespace

void set_detail_level(Crowd& crowd, DetailLevel level) {
  const DetailLevel before = crowd.skin.level;
  crowd.skin.requested = level;
  rebuild_layouts(crowd);
  if (crowd.skin.level == before) return;
  // Every walker goes to the new level's table at once, so the crowd is consistent between this call and the
  // next step() (a tool may read a walker's rows in between); with a camera, that step's level-of-detail stage
  // then culls and levels them again. A level switch is rare, so moving every walker is cheap enough.
  const std::uint32_t to = crowd.tables[slot_index(initial_slot(crowd))];
  for (const Entity walker : crowd.world.entities())
    if (!crowd.is_remote(walker)) crowd.world.move(walker, to);
}

void set_skinning_mode(Crowd& crowd, SkinningMode mode) {
  if (crowd.skin.mode == mode) return;
  crowd.skin.mode = mode;
  crowd.impostor_atlas = nullptr;  // baked in the old mode
  rebuild_layouts(crowd);
}

void set_muscles_enabled(Crowd& crowd, bool on) {
  if (crowd.skin.muscles_on != on) crowd.impostor_atlas = nullptr;  // baked with or without them
  crowd.skin.muscles_on = on;
  rebuild_layouts(crowd);
}

void set_muscle_gains(Crowd& crowd, MuscleGains gains) {
  crowd.skin.gains = std::move(gains);
  if (!crowd.skin.level.is_none()) rebuild_muscle_coefficients(crowd);
}

void set_body(Crowd& crowd, std::shared_ptr<const Body> body) {
  const Rig& current = crowd.rig();
  if (!current.body || !body || body->levels.size() != current.body->levels.size())
    throw std::invalid_argument("set_body: the new body must have the current body's levels");
  for (std::size_t k = 0; k < body->levels.size(); ++k)
    if (body->levels[k].mesh.vertex_count() != current.body->levels[k].mesh.vertex_count() ||
        body->levels[k].binding.vertex_count() != body->levels[k].mesh.vertex_count())
      throw std::invalid_argument("set_body: level " + std::to_string(k) + " changed its vertex count");
  Rig edited = current;
  edited.body = std::move(body);
  crowd.rigs.replace(crowd.rig_id, std::move(edited));
  crowd.impostor_atlas = nullptr;  // baked from the old weights
  // The mocap rig points at the skeleton, which now lives in the new rig.
  CrowdMotion& m = crowd.motion;
  if (m.mocap) m.mocap_rig = std::make_unique<const MocapRig>(make_mocap_rig(crowd.rig().skeleton, m.mocap->clip, m.mocap->contacts));
  rebuild_layouts(crowd);
}

DetailSlot initial_slot(const Crowd& crowd) {
  const DetailLevel level = crowd.skin.level;
  if (level.is_none()) return DetailSlot::NoBody;
  if (level.is_subdiv()) return DetailSlot::Refined;
  if (level.is_automatic()) return DetailSlot::Mesh0;
  if (level.is_impostor()) return crowd_may_use_impostors(crowd) ? DetailSlot::Impostor : DetailSlot::NoBody;
  return mesh_slot(level.index());
}

DetailSlot spawn_slot(const Crowd& crowd) {
  if (crowd.skin.level.is_automatic() && crowd_may_use_impostors(crowd)) return DetailSlot::Impostor;
  return initial_slot(crowd);
}

bool crowd_may_use_impostors(const Crowd& crowd) {
  const Rig& rig = crowd.rig();
  return crowd.motion.source == MotionSource::Walk && crowd.motion.locomotion != nullptr && rig.body != nullptr &&
         !rig.body->levels.empty();
}

const SkinLayout& current_layout(const Crowd& crowd) {
  static const SkinLayout kEmpty;
  const DetailLevel level = crowd.skin.level;
  if (level.is_mesh()) return crowd.skin.layouts[static_cast<std::size_t>(level.index())];
  if (level.is_automatic()) return crowd.skin.layouts[0];
  return kEmpty;
}

const SkinnedCrowd& current_skinned(const Crowd& crowd) {
  const DetailSlot slot = initial_slot(crowd);
  return crowd.skinned[slot_index(slot == DetailSlot::NoBody ? DetailSlot::Mesh0 : slot)];
}

const std::vector<std::uint32_t>& current_triangles(const Crowd& crowd) {
  if (crowd.skin.subdiv) return crowd.skin.subdiv->triangles;
  return current_layout(crowd).triangles;
}

}  // namespace strata
