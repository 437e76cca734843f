#pragma once
// Body: the skin of a rig at one or more resolution levels, each a rest mesh with its skin binding. Immutable
// rig data shared by every walker of the rig (components/rig.h); level 0 is the finest.
#include <memory>
#include <vector>

#include "components/mesh.h"

namespace strata {

struct BodyLevel {
  Mesh mesh;
  SkinBinding binding;
};

struct Body {
  std::vector<BodyLevel> levels;
};

}  // namespace strata
