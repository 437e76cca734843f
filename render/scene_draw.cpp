#include "components/fnv_hasher.h"
#include "render/props_pass.h"
#include "scene/crowd_agents.h"
#include "render/scene_draw.h"

#include <cmath>
#include <limits>
#include <span>

#include <glm/common.hpp>

#include "render/impostor_bake.h"
#include "render/impostor_pass.h"
#include "rig/subdiv_topology.h"
#include "rig/surface_material.h"
#include "rig/vertex_occlusion.h"
#include "systems/pose_gather.h"

namespace strata {
namespace {

const std::vector<std::uint32_t>* triangles_of(const Crowd& crowd, std::size_t slot) {
  if (slot == slot_index(DetailSlot::Refined)) return crowd.skin.subdiv ? &crowd.skin.subdiv->triangles : nullptr;
  if (slot < static_cast<std::size_t>(kMaxMeshLevels)) return &crowd.skin.layouts[slot].triangles;
  return nullptr;
}

}  // namespace

std::vector<BodyDrawInput> body_draw_inputs(const Crowd& crowd) {
  std::vector<BodyDrawInput> inputs;
  for (std::size_t slot = 0; slot < kDetailSlots; ++slot) {
    const SkinnedCrowd& s = crowd.skinned[slot];
    const std::vector<std::uint32_t>* triangles = triangles_of(crowd, slot);
    if (s.walkers == 0 || s.vertex_count == 0 || triangles == nullptr) continue;
    BodyDrawInput input;
    input.triangles = *triangles;
    input.px = s.px.data(), input.py = s.py.data(), input.pz = s.pz.data();
    input.nx = s.nx.data(), input.ny = s.ny.data(), input.nz = s.nz.data();
    input.stride = s.stride;
    input.vertex_count = s.vertex_count;
    input.walker_count = s.walkers;
    inputs.push_back(input);
  }
  return inputs;
}

std::vector<BodyDrawInput> body_draw_inputs(const Crowd& crowd, RenderScratch& scratch) {
  std::vector<BodyDrawInput> inputs = body_draw_inputs(crowd);
  const Body* body = crowd.rig().body.get();
  std::size_t k = 0;
  for (std::size_t slot = 0; slot < kDetailSlots && k < inputs.size(); ++slot) {
    const SkinnedCrowd& s = crowd.skinned[slot];
    if (s.walkers == 0 || s.vertex_count == 0 || triangles_of(crowd, slot) == nullptr) continue;
    BodyDrawInput& input = inputs[k++];
    // Keys: the entity slot of each block's walker, which stays with the walker across tables.
    const SoaTable& table = crowd.table(static_cast<DetailSlot>(slot));
    std::vector<std::uint32_t>& keys = scratch.walker_keys[slot];
    keys.resize(s.walkers);
    for (std::size_t w = 0; w < s.walkers; ++w) {
      const std::size_t row = s.walker_ids.empty() ? w : s.walker_ids[w];
      keys[w] = row < table.size() ? table.owner(static_cast<std::uint32_t>(row)).index : static_cast<std::uint32_t>(w);
    }
    input.walker_keys = keys.data();
    if (!body) continue;
    const bool refined = slot == slot_index(DetailSlot::Refined);
    // What the classes depend on: the refined surface (immutable, shared), or the layout's vertex order, which a
    // binding edit can regroup in place; hashing it costs microseconds a frame.
    std::uint64_t source = reinterpret_cast<std::uintptr_t>(crowd.skin.subdiv.get());
    if (!refined) {
      FnvHasher h;
      const std::vector<std::uint32_t>& original = crowd.skin.layouts[slot].original;
      h.bytes(original.data(), original.size() * sizeof(std::uint32_t));
      h.value(reinterpret_cast<std::uintptr_t>(body));
      source = h.h;
    }
    if (scratch.materials_of[slot] != source) {
      SurfaceClasses& materials = scratch.materials[slot];
      std::vector<float>& occlusion = scratch.occlusion[slot];
      materials = {}, occlusion.clear();
      if (refined && crowd.skin.subdiv && body->cage) {
        materials = refined_materials(body->cage->mesh, *crowd.skin.subdiv);
        occlusion = refined_occlusion(body_vertex_occlusion(*body, -1)->open, *crowd.skin.subdiv);
      } else if (!refined && slot < body->levels.size()) {
        const SkinLayout& layout = crowd.skin.layouts[slot];
        materials = layout_materials(body->levels[slot].mesh, layout);
        // The first high-quality frame of a level bakes its occlusion (once per body; Body::occlusion).
        const std::vector<float>& open = body_vertex_occlusion(*body, static_cast<int>(slot))->open;
        occlusion.assign(layout.vertex_count, 1.0f);
        for (std::size_t v = 0; v < layout.vertex_count && v < layout.original.size(); ++v)
          if (layout.original[v] < open.size()) occlusion[v] = open[layout.original[v]];
      }
      scratch.materials_of[slot] = source;
    }
    if (scratch.materials[slot].size() >= s.vertex_count) {
      input.materials = scratch.materials[slot].classes;
      input.material_cut = scratch.materials[slot].cut;
    }
    if (scratch.occlusion[slot].size() >= s.vertex_count) input.ambient_occlusion = scratch.occlusion[slot];
  }
  return inputs;
}

ImpostorBatch impostor_batch(const Crowd& crowd, std::vector<float>* standing_phase,
                             std::vector<std::uint32_t>* walker_keys) {
  ImpostorBatch batch;
  const SoaTable& t = crowd.table(DetailSlot::Impostor);
  if (t.size() == 0 || !crowd.impostor_atlas) return batch;
  batch.atlas = crowd.impostor_atlas.get();
  const float* placement = t.f32_base(kWalkerPlacement);
  batch.x = placement;
  batch.y = placement + t.stride();
  batch.z = placement + 2 * t.stride();
  batch.heading = placement + 3 * t.stride();
  batch.scale = placement + 4 * t.stride();
  batch.phase = t.f32(kWalkerGait, kGaitPhase).data();
  if (standing_phase && crowd.agents) {
    const std::span<const float> phase = t.f32(kWalkerGait, kGaitPhase), idle = t.f32(kWalkerGait, kGaitIdle);
    standing_phase->resize(t.size());
    for (std::size_t w = 0; w < t.size(); ++w) (*standing_phase)[w] = idle[w] > 0.5f ? 0.3f : phase[w];
    batch.phase = standing_phase->data();
  }
  batch.walker_count = t.size();
  if (walker_keys) {
    walker_keys->resize(t.size());
    for (std::size_t w = 0; w < t.size(); ++w) (*walker_keys)[w] = t.owner(static_cast<std::uint32_t>(w)).index;
    batch.walker_keys = walker_keys->data();
  }
  return batch;
}

void impostor_feet(const Crowd& crowd, std::vector<glm::vec3>& out) {
  const SoaTable& t = crowd.table(DetailSlot::Impostor);
  out.resize(t.size());
  for (std::size_t w = 0; w < t.size(); ++w)
    out[w] = {t.f32(kWalkerPlacement, 0)[w], t.f32(kWalkerPlacement, 1)[w], t.f32(kWalkerPlacement, 2)[w]};
}

bool body_bounds(const Crowd& crowd, glm::vec3& lo, glm::vec3& hi) {
  bool any = false;
  auto add = [&](const glm::vec3& a, const glm::vec3& b) {
    lo = any ? glm::min(lo, a) : a;
    hi = any ? glm::max(hi, b) : b;
    any = true;
  };
  for (std::size_t slot = 0; slot < kDetailSlots; ++slot) {
    glm::vec3 a, b;
    if (crowd.skinned[slot].walkers == 0 || !crowd.skinned[slot].bounds(a, b)) continue;
    add(a, b);
  }
  // Impostors: their feet, up to their stature.
  const SoaTable& t = crowd.table(DetailSlot::Impostor);
  for (std::size_t w = 0; w < t.size(); ++w) {
    const glm::vec3 foot(t.f32(kWalkerPlacement, 0)[w], t.f32(kWalkerPlacement, 1)[w], t.f32(kWalkerPlacement, 2)[w]);
    const float height = crowd.skin.body_height * t.f32(kWalkerPlacement, 4)[w];
    add(foot - glm::vec3(0.3f * height, 0.0f, 0.3f * height), foot + glm::vec3(0.3f * height, height, 0.3f * height));
  }
  return any;
}

std::size_t gather_crowd_joints(const Crowd& crowd, std::vector<glm::vec3>& out, bool include_culled) {
  const std::size_t joints = crowd.joint_count();
  const std::size_t culled = include_culled ? 0 : crowd.table(DetailSlot::Culled).size();
  out.resize((crowd.walker_count() - crowd.table(DetailSlot::Impostor).size() - culled) * joints);
  std::size_t at = 0;
  std::vector<glm::vec3> table_joints;
  for (std::size_t slot = 0; slot < kDetailSlots; ++slot) {
    // walker_lanes wants a mutable table; gathering only reads it.
    SoaTable& t = const_cast<SoaTable&>(crowd.world.table(crowd.tables[slot]));
    // Culled walkers are not drawn, and a walking crowd's culled walkers keep a stale pose (only their gait clock
    // runs): their joints would fit the ground and the shadow frustum to where they were when last seen, and
    // under mpirun to where they were when last this rank's (dist/).
    if (t.size() == 0 || is_light_walker_table(t) || (!include_culled && slot == slot_index(DetailSlot::Culled)))
      continue;
    gather_joint_positions(walker_lanes(t, crowd.joint_count()), table_joints);
    std::copy(table_joints.begin(), table_joints.end(), out.begin() + static_cast<std::ptrdiff_t>(at));
    at += table_joints.size();
  }
  return joints == 0 ? 0 : at / joints;
}

LodView lod_view(const OrbitCamera& camera, float aspect, int viewport_height) {
  LodView v;
  v.view_projection = camera.projection(aspect) * camera.view();
  v.eye = camera.eye();
  v.focal_px = static_cast<float>(viewport_height) / (2.0f * std::tan(0.5f * camera.fov_y));
  return v;
}

void set_crowd_camera(Crowd& crowd, const OrbitCamera& camera, float aspect, int viewport_height) {
  crowd.lod.view = lod_view(camera, aspect, viewport_height);
}

bool crowd_frame_bounds(const Crowd& crowd, RenderScratch& scratch, glm::vec3& lo, glm::vec3& hi) {
  if (!crowd.skin.level.is_none() && body_bounds(crowd, lo, hi)) return true;
  gather_crowd_joints(crowd, scratch.joints);
  return joint_bounds(scratch.joints, lo, hi);
}

bool frame_crowd(const Crowd& crowd, OrbitCamera& camera, float aspect, RenderScratch& scratch) {
  glm::vec3 lo, hi;
  const bool any = crowd_frame_bounds(crowd, scratch, lo, hi);
  if (any) camera.frame_box_tight(lo, hi, aspect);
  return any;
}

std::size_t render_frame(Crowd& crowd, CrowdRenderer& renderer, const OrbitCamera& camera, float aspect,
                         int viewport_height, RenderScratch& scratch, const RenderFrameOptions& options) {
  const std::size_t with_joints = gather_crowd_joints(crowd, scratch.joints);
  std::vector<BodyDrawInput> bodies = renderer.options().quality == RenderQuality::High
                                          ? body_draw_inputs(crowd, scratch)
                                          : body_draw_inputs(crowd);
  if (options.recolour) options.recolour(bodies);
  renderer.options().draw_skeleton = crowd.skin.level.is_none() || options.skeleton_overlay;
  // A scenario's obstacles and goals, built once per scenario (keyed by its name, source and seed).
  if (crowd.agents) {
    const Scenario& sc = crowd.agents->scenario;
    FnvHasher h;
    h.bytes(sc.name.data(), sc.name.size());
    h.bytes(sc.source.data(), sc.source.size());
    h.value(sc.seed);
    h.value(sc.obstacles.size());
    const std::uint64_t key = h.h | 1u;
    if (renderer.props_key() != key) {
      const std::vector<PropVertex> props = scenario_props(sc);
      renderer.set_props(key, props);
    }
  } else if (renderer.props_key() != 0) {
    renderer.set_props(0, {});
  }
  SkeletonDrawInput skeletons{&crowd.rig().skeleton, scratch.joints, with_joints};
  const bool impostors = crowd.table(DetailSlot::Impostor).size() > 0;
  if (impostors) {
    // The first frame with impostors bakes (or loads) the rig's atlas: seconds once, then cached on disk.
    ensure_impostor_atlas(crowd);
    impostor_feet(crowd, scratch.impostor_feet);
    skeletons.ground_points = scratch.impostor_feet;
  }
  if (impostors) {
    scratch.batches.assign(bodies.begin(), bodies.end());
    scratch.batches.emplace_back(impostor_batch(crowd, &scratch.impostor_phase, &scratch.impostor_keys));
  }
  if (options.share_bounds) {
    // The ground and the shadow frustum are fitted to boxes of their points (render/ground_pass.h ground_extent,
    // render/shadow_pass.h): this process's points plus the two corners of every process's box give every
    // process that box. The shadow frustum's box holds the impostors' quads too (they cast shadows).
    const std::size_t joints = with_joints * crowd.rig().skeleton.joint_count();
    glm::vec3 lo, hi, feet_lo, feet_hi;
    joint_bounds(std::span<const glm::vec3>(scratch.joints.data(), std::min(joints, scratch.joints.size())), lo, hi);
    glm::vec3 joints_lo = lo, joints_hi = hi;
    if (impostors) grow_by_impostors(std::get<ImpostorBatch>(scratch.batches.back()), joints_lo, joints_hi);
    options.share_bounds(joints_lo, joints_hi);
    scratch.shared_joints.clear();
    if (joints_lo.x <= joints_hi.x) scratch.shared_joints = {joints_lo, joints_hi};
    skeletons.shadow_fit_points = scratch.shared_joints;
    if (impostors && joint_bounds(scratch.impostor_feet, feet_lo, feet_hi))
      lo = glm::min(lo, feet_lo), hi = glm::max(hi, feet_hi);
    options.share_bounds(lo, hi);
    scratch.shared_ground.clear();
    if (lo.x <= hi.x) scratch.shared_ground = {lo, hi};
    skeletons.ground_points = scratch.shared_ground;
  }
  if (impostors) {
    renderer.render(skeletons, camera.view(), camera.projection(aspect), BodyBatches(scratch.batches));
  } else {
    renderer.render(skeletons, camera.view(), camera.projection(aspect), bodies);
  }
  set_crowd_camera(crowd, camera, aspect, viewport_height);
  return renderer.triangles_drawn();
}

}  // namespace strata
