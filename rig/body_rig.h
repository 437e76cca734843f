#pragma once
// Building a rig's Body: binding every resolution level of a mesh set to the skeleton, once.
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <span>

#include "components/body.h"
#include "components/skeleton.h"
#include "rig/body_generator.h"

namespace strata {

enum class BindingMethod { ThreeStep, Automatic };

struct BindingTables;  // rig/binding.h

// Binds each mesh (finest first) with the paper's three steps and `tables` (nullptr: the shipped tables,
// rig/binding.h default_binding_tables), or with the automatic bone-heat weights (tables unused); `cage`, when
// given, is bound the same way into Body::cage.
std::shared_ptr<const Body> bind_body(std::span<const Mesh> levels, const Skeleton& skeleton,
                                      BindingMethod method = BindingMethod::ThreeStep, const Mesh* cage = nullptr,
                                      const BindingTables* tables = nullptr);

// The two shipped bodies, both fitted to the shipped default skeleton at the paper's three levels plus a cage:
// the MakeHuman-derived one (rig/makehuman_body.h) and the procedural one (rig/body_generator.h).
enum class ShippedBody : std::uint8_t { MakeHuman, Procedural };
inline constexpr ShippedBody kDefaultShippedBody = ShippedBody::MakeHuman;
const char* shipped_body_name(ShippedBody body);  // "makehuman", "procedural"
std::optional<ShippedBody> parse_shipped_body(std::string_view name);
const BodyLevels& shipped_body_levels(ShippedBody body = kDefaultShippedBody);
// The binding tables each is bound with (rig/binding.h): the shipped ones, plus the MakeHuman body's own knee
// step-2 radii (data/makehuman_binding_overrides.json).
const BindingTables& shipped_binding_tables(ShippedBody body = kDefaultShippedBody);

// A shipped body, its three levels and its subdivision cage, bound to the shipped default skeleton, built once
// per process. It fits that skeleton only, so the function takes none: a caller cannot pair it with another by
// mistake.
std::shared_ptr<const Body> default_bound_body(ShippedBody body = kDefaultShippedBody);

}  // namespace strata
