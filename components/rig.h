#pragma once
// Rig: the immutable data every walker of one body shares (stored once, referenced by id from walker tables).
// A skeleton, its animation clips and optionally its body (rest meshes per level with their skin binding) and
// muscle layer (action lines and their binding to each body level); never per walker.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/animation_clip.h"
#include "components/body.h"
#include "components/muscle.h"
#include "components/skeleton.h"

namespace strata {

struct Rig {
  std::string name;
  Skeleton skeleton;
  std::vector<AnimationClip> clips;
  std::shared_ptr<const Body> body;  // null: a skeleton only
  std::shared_ptr<const MuscleRig> muscles;  // null: no muscle layer; else levels match body->levels
};

using RigId = std::uint32_t;

class RigLibrary {
 public:
  RigId add(Rig rig) {
    rigs_.push_back(std::make_shared<const Rig>(std::move(rig)));
    return static_cast<RigId>(rigs_.size() - 1);
  }
  const Rig& get(RigId id) const {
    if (id >= rigs_.size()) throw std::out_of_range("RigLibrary: no rig " + std::to_string(id));
    return *rigs_[id];
  }
  std::shared_ptr<const Rig> share(RigId id) const { return rigs_.at(id); }
  // Swaps rig `id` for `rig` (an edited copy): whoever shares the old one keeps it alive and unchanged.
  void replace(RigId id, Rig rig) {
    if (id >= rigs_.size()) throw std::out_of_range("RigLibrary: no rig " + std::to_string(id));
    rigs_[id] = std::make_shared<const Rig>(std::move(rig));
  }
  std::size_t size() const { return rigs_.size(); }

 private:
  std::vector<std::shared_ptr<const Rig>> rigs_;
};

}  // namespace strata
