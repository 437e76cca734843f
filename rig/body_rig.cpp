#include "rig/body_rig.h"

#include <mutex>

#include "rig/binding.h"
#include "rig/body_generator.h"

namespace strata {

std::shared_ptr<const Body> bind_body(std::span<const Mesh> levels, const Skeleton& skeleton, BindingMethod method) {
  auto body = std::make_shared<Body>();
  for (const Mesh& mesh : levels) {
    BodyLevel level;
    level.mesh = mesh;
    if (level.mesh.normals.size() != level.mesh.positions.size()) compute_normals(level.mesh);
    level.binding = method == BindingMethod::ThreeStep
                        ? bind_three_step(level.mesh, skeleton, default_binding_tables())
                        : bind_automatic(level.mesh, skeleton);
    body->levels.push_back(std::move(level));
  }
  return body;
}

std::shared_ptr<const Body> default_bound_body(const Skeleton& skeleton) {
  // The default body is generated from the default skeleton; binding it is deterministic, so one copy serves
  // every scene of the process.
  static std::once_flag once;
  static std::shared_ptr<const Body> body;
  std::call_once(once, [&] {
    const BodyLevels& levels = default_body();
    body = bind_body(levels.levels, skeleton);
  });
  return body;
}

}  // namespace strata
