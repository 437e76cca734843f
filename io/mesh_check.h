#pragma once
// The check every mesh loader runs on what it produced, so that no loader hands the engine a half-valid mesh.
// In io/ rather than beside Mesh (components/mesh.h) because it reports LoadError, the loaders' error type:
// components/ holds plain data and depends on nothing but ecs/.
#include <string_view>

#include "components/mesh.h"

namespace strata {

// Checks a mesh a loader produced and throws LoadError "SOURCE: <what>: reason" naming the first problem:
// index out of range, non-finite coordinate, per-vertex arrays of the wrong length, empty mesh, part index out of
// range. `source` names the file (and group) for the message.
void validate_mesh(const Mesh& mesh, std::string_view source);

}  // namespace strata
