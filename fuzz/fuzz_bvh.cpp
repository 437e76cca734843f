// libFuzzer target: BVH motion capture (io/bvh.h); a loaded capture is also posed at its first and last frame,
// which walks every channel the loader accepted.
#include <glm/gtc/quaternion.hpp>

#include "fuzz/fuzz_common.h"
#include "io/bvh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const strata::BvhMotion m = strata::load_bvh_text(strata::fuzz::as_text(data, size), "fuzz.bvh");
    if (m.frame_count > 0) {
      std::vector<glm::quat> rotations(m.joint_count());
      std::vector<glm::vec3> positions(m.joint_count());
      m.pose(0, rotations, positions);
      m.pose(m.frame_count - 1, rotations, positions);
    }
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz.bvh");
  }
  return 0;
}
