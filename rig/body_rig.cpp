#include "rig/body_rig.h"

#include "io/hanim_loader.h"
#include "io/muscle_file.h"
#include "rig/binding.h"
#include "rig/muscle_binding.h"
#include "rig/body_generator.h"

namespace strata {

std::shared_ptr<const Body> bind_body(std::span<const Mesh> levels, const Skeleton& skeleton, BindingMethod method,
                                      const Mesh* cage, const BindingTables* tables) {
  // Looked up only for the three steps: the automatic binder needs no tables, even in a build without them.
  const BindingTables* three_step_tables =
      method == BindingMethod::ThreeStep ? (tables ? tables : &default_binding_tables()) : nullptr;
  auto bind = [&](const Mesh& mesh) {
    BodyLevel level;
    level.mesh = mesh;
    if (level.mesh.normals.size() != level.mesh.positions.size()) compute_normals(level.mesh);
    level.binding = method == BindingMethod::ThreeStep
                        ? bind_three_step(level.mesh, skeleton, *three_step_tables)
                        : bind_automatic(level.mesh, skeleton);
    return level;
  };
  auto body = std::make_shared<Body>();
  for (const Mesh& mesh : levels) body->levels.push_back(bind(mesh));
  if (cage) body->cage = bind(*cage);
  return body;
}

std::shared_ptr<const Body> default_bound_body() {
  // Binding is deterministic, so one copy serves every scene of the process.
  static const std::shared_ptr<const Body> body = bind_body(default_body().levels, load_default_humanoid().skeleton,
                                                                BindingMethod::ThreeStep, &default_body().cage);
  return body;
}

// Declared in rig/muscle_binding.h; defined here, beside the default body it binds, so the muscle binder itself
// (and the muscle loader's fuzz target) does not pull in the body generator.
std::shared_ptr<const MuscleRig> default_muscle_rig() {
  static const std::shared_ptr<const MuscleRig> rig =
      bind_muscle_rig(default_muscles(load_default_humanoid().skeleton), *default_bound_body());
  return rig;
}

}  // namespace strata
