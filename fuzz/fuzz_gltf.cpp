// libFuzzer target: glTF 2.0 / GLB skinned bodies (io/gltf.h) from memory.
#include "fuzz/fuzz_common.h"
#include "io/gltf.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)strata::load_gltf_memory({data, size}, "fuzz.glb");
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz.glb");
  }
  return 0;
}
