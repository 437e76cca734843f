#pragma once
// Building a rig's Body: binding every resolution level of a mesh set to the skeleton, once.
#include <memory>
#include <span>

#include "components/body.h"
#include "components/skeleton.h"

namespace strata {

enum class BindingMethod { ThreeStep, Automatic };

struct BindingTables;  // rig/binding.h

// Binds each mesh (finest first) with the paper's three steps and `tables` (nullptr: the shipped tables,
// rig/binding.h default_binding_tables), or with the automatic bone-heat weights (tables unused); `cage`, when
// given, is bound the same way into Body::cage.
std::shared_ptr<const Body> bind_body(std::span<const Mesh> levels, const Skeleton& skeleton,
                                      BindingMethod method = BindingMethod::ThreeStep, const Mesh* cage = nullptr,
                                      const BindingTables* tables = nullptr);

// The shipped default body (rig/body_generator.h), its three levels and its subdivision cage, bound to the
// shipped default skeleton, built once per process.
// It fits that skeleton only, so the function takes none: a caller cannot pair it with another by mistake.
std::shared_ptr<const Body> default_bound_body();

}  // namespace strata
