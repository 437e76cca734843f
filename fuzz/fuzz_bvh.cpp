// libFuzzer target: BVH motion capture (io/bvh.h); a loaded capture is also posed at its first and last frame,
// which walks every channel the loader accepted, and its joints are recognised (motion/bvh_naming.h: by name, else
// by the skeleton's shape), which walks any tree the loader accepts through the shape rules.
#include <stdexcept>

#include <glm/gtc/quaternion.hpp>

#include "fuzz/fuzz_common.h"
#include "io/bvh.h"
#include "motion/bvh_naming.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const strata::BvhMotion m = strata::load_bvh_text(strata::fuzz::as_text(data, size), "fuzz.bvh");
    if (m.frame_count > 0) {
      std::vector<glm::quat> rotations(m.joint_count());
      std::vector<glm::vec3> positions(m.joint_count());
      m.pose(0, rotations, positions);
      m.pose(m.frame_count - 1, rotations, positions);
    }
    try {
      (void)strata::recognise_bvh_naming(m);
    } catch (const std::invalid_argument&) {
      // A capture that cannot be mapped says so in one line; anything else (a crash, UB) is the finding.
    }
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz.bvh");
  }
  return 0;
}
