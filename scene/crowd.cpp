#include "scene/crowd.h"

#include "scene/crowd_agents.h"

#include <algorithm>
#include <stdexcept>

#include "components/humanoid_shape.h"
#include "scene/body_settings.h"

namespace strata {

const char* slot_name(DetailSlot slot) {
  switch (slot) {
    case DetailSlot::Mesh0: return "level0";
    case DetailSlot::Mesh1: return "level1";
    case DetailSlot::Mesh2: return "level2";
    case DetailSlot::Refined: return "refined";
    case DetailSlot::Culled: return "culled";
    case DetailSlot::NoBody: return "no_body";
    case DetailSlot::Impostor: return "impostor";
  }
  return "?";
}

bool slot_is_light(DetailSlot slot, MotionSource source) {
  if (slot == DetailSlot::Impostor) return true;
  return slot == DetailSlot::Culled && source == MotionSource::Walk;
}

Crowd::~Crowd() = default;

void Crowd::make_tables(bool agent_fields) {
  const Rig& r = rig();
  const auto joints = static_cast<std::uint32_t>(r.skeleton.joint_count());
  const std::string name = r.name.empty() ? std::string("walkers") : r.name;
  const std::uint32_t muscle_points = r.muscles ? r.muscles->set.point_count : 0;
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const std::string table_name = name + "." + slot_name(static_cast<DetailSlot>(s));
    tables[s] = world.add_table(static_cast<DetailSlot>(s) == DetailSlot::Impostor
                                    ? make_light_walker_table(table_name, agent_fields)
                                    : make_walker_table(table_name, joints, muscle_points, agent_fields));
  }
  remote_table = world.add_table(make_light_walker_table(name + ".remote", agent_fields));
}

void Crowd::widen_for_agents() {
  if (walker_count() != 0) throw std::logic_error("Crowd::widen_for_agents: the crowd already has walkers");
  if (world.table(tables[0]).fields()[kWalkerAgent].width == kAgentFloats) return;
  // The narrow tables stay in the world, empty; nothing iterates the world's tables except through `tables`.
  make_tables(true);
}

Crowd::Crowd(Rig r) {
  if (r.muscles && (!r.body || r.muscles->levels.size() != r.body->levels.size()))
    throw std::invalid_argument("Crowd: the muscle layer is bound to " + std::to_string(r.muscles->levels.size()) +
                                " body levels, the body has " + std::to_string(r.body ? r.body->levels.size() : 0));
  rig_id = rigs.add(std::move(r));
  // One table per slot, identical fields, so World::move copies every field and a walker keeps its whole state
  // whatever table it moves to; except the impostors' table, which keeps only what a far walker needs. The culled
  // table stays wide although a walking crowd's culled walkers are light too: clip and capture crowds run their
  // culled walkers whole, and a walker leaving the view keeps its pose rows for the frame it comes back.
  make_tables(false);
  try {
    motion.locomotion = std::make_unique<const LocomotionRig>(make_locomotion_rig(rig().skeleton));
  } catch (const std::exception& e) {
    // Said in the rig's terms, not the limb builder's: which joints the walk needs that the rig lacks, and why
    // neither the families' names nor the shape rules (components/humanoid_shape.h) found them.
    const Skeleton& s = rig().skeleton;
    std::string missing;
    for (const char* joint : {"l_hip", "l_knee", "l_ankle", "r_hip", "r_knee", "r_ankle", "l_shoulder", "l_elbow",
                              "l_wrist", "r_shoulder", "r_elbow", "r_wrist"})
      if (s.find_joint(joint) < 0) missing += std::string(missing.empty() ? "" : ", ") + joint;
    if (missing.empty()) {
      motion.walk_error = "'" + rig().name + "' cannot walk: " + e.what();
    } else {
      HumanoidShape shape;
      const std::string why = find_humanoid_by_shape(s.parents, s.centers, {}, shape);
      motion.walk_error = "'" + rig().name + "' cannot walk: it has no " + missing +
                          (why.empty() ? std::string() : " (its joint names are no known family's, and by shape: " + why + ")");
    }
  }
  // Rest height for projected sizes: the body's, else the skeleton's joint span plus a head's worth.
  const Rig& rr = rig();
  if (rr.body && !rr.body->levels.empty() && !rr.body->levels[0].mesh.positions.empty()) {
    float lo = 1e30f, hi = -1e30f;
    for (const glm::vec3& p : rr.body->levels[0].mesh.positions) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    skin.body_height = hi - lo;
  } else if (!rr.skeleton.centers.empty()) {
    float lo = 1e30f, hi = -1e30f;
    for (const glm::vec3& c : rr.skeleton.centers) lo = std::min(lo, c.y), hi = std::max(hi, c.y);
    skin.body_height = hi - lo + 0.15f;
  }
  set_detail_level(*this, DetailLevel::mesh(0));
}

DetailSlot Crowd::slot_of(Entity walker) const {
  const std::uint32_t table_id = world.location(walker).table;
  for (std::size_t s = 0; s < kDetailSlots; ++s)
    if (tables[s] == table_id) return static_cast<DetailSlot>(s);
  throw std::logic_error("Crowd::slot_of: walker in a table that is not a walker table");
}

WalkerLanes Crowd::lanes() {
  std::size_t holding = kDetailSlots, non_empty = 0;
  for (std::size_t s = 0; s < kDetailSlots; ++s)
    if (world.table(tables[s]).size() > 0) holding = s, ++non_empty;
  if (non_empty > 1)
    throw std::logic_error("Crowd::lanes: the walkers are spread over " + std::to_string(non_empty) +
                           " tables (culling or levels of detail); read each table with lanes(slot)");
  return lanes(holding == kDetailSlots ? initial_slot(*this) : static_cast<DetailSlot>(holding));
}

const std::vector<LimbChain>& Crowd::limbs() const {
  static const std::vector<LimbChain> kNone;
  return motion.locomotion ? motion.locomotion->limbs : kNone;
}

}  // namespace strata
