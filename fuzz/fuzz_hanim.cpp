// libFuzzer target: X3D H-Anim and paper-era humanoid XML (io/hanim_loader.h), then the shared rig built from it.
#include "fuzz/fuzz_common.h"
#include "io/hanim_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    strata::Rig rig = strata::to_rig(strata::load_humanoid_text(strata::fuzz::as_text(data, size), "fuzz.x3d"));
    (void)rig;
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz.x3d");
  }
  return 0;
}
