#include "rig/body_rig.h"

#include "io/hanim_loader.h"
#include "io/muscle_file.h"
#include "rig/binding.h"
#include "rig/muscle_binding.h"
#include "rig/body_generator.h"
#include "rig/makehuman_body.h"

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

const char* shipped_body_name(ShippedBody body) {
  return body == ShippedBody::MakeHuman ? "makehuman" : "procedural";
}

std::optional<ShippedBody> parse_shipped_body(std::string_view name) {
  if (name == "makehuman") return ShippedBody::MakeHuman;
  if (name == "procedural") return ShippedBody::Procedural;
  return std::nullopt;
}

const BodyLevels& shipped_body_levels(ShippedBody body) {
  return body == ShippedBody::MakeHuman ? makehuman_default_body() : default_body();
}

const BindingTables& shipped_binding_tables(ShippedBody body) {
  return body == ShippedBody::MakeHuman ? makehuman_binding_tables() : default_binding_tables();
}

std::shared_ptr<const Body> default_bound_body(ShippedBody which) {
  // Binding is deterministic, so one copy per body serves every scene of the process.
  auto bind = [](ShippedBody b) {
    const BodyLevels& levels = shipped_body_levels(b);
    return bind_body(levels.levels, load_default_humanoid().skeleton, BindingMethod::ThreeStep, &levels.cage,
                     &shipped_binding_tables(b));
  };
  if (which == ShippedBody::MakeHuman) {
    static const std::shared_ptr<const Body> body = bind(ShippedBody::MakeHuman);
    return body;
  }
  static const std::shared_ptr<const Body> body = bind(ShippedBody::Procedural);
  return body;
}

// Declared in rig/muscle_binding.h; defined here, beside the default body it binds, so the muscle binder itself
// (and the muscle loader's fuzz target) does not pull in the body generator.
std::shared_ptr<const MuscleRig> default_muscle_rig(ShippedBody which) {
  auto bind = [](ShippedBody b) {
    return bind_muscle_rig(default_muscles(load_default_humanoid().skeleton), *default_bound_body(b));
  };
  if (which == ShippedBody::MakeHuman) {
    static const std::shared_ptr<const MuscleRig> rig = bind(ShippedBody::MakeHuman);
    return rig;
  }
  static const std::shared_ptr<const MuscleRig> rig = bind(ShippedBody::Procedural);
  return rig;
}

}  // namespace strata
