// libFuzzer target: the muscle file and the per-muscle overrides file (io/muscle_file.h), joined by a NUL byte,
// read against the shipped skeleton; a parsed set is also bound to a tiny mesh so the binder sees what the
// loader lets through.
#include "components/mesh.h"
#include "fuzz/fuzz_common.h"
#include "io/hanim_loader.h"
#include "io/muscle_file.h"
#include "rig/muscle_binding.h"

namespace {

const strata::Skeleton& skeleton() {
  static const strata::Skeleton s = strata::load_default_humanoid().skeleton;
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = strata::fuzz::split_parts(strata::fuzz::as_text(data, size), 2);
  strata::MuscleSet set;
  try {
    set = strata::parse_muscles(parts[0], "fuzz_muscles.json", skeleton());
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz_muscles.json");
    return 0;
  }
  strata::Mesh mesh;
  mesh.part_names = {"lShldr", "rThigh"};
  for (const glm::vec3& c : skeleton().centers) {
    mesh.positions.push_back(c + glm::vec3(0.0f, 0.0f, 0.03f));
    mesh.part.push_back(static_cast<std::uint16_t>(mesh.positions.size() % 2));
  }
  const strata::MuscleBinding binding = strata::bind_muscles(mesh, set);
  (void)strata::muscle_coefficients(set, binding);
  try {
    (void)strata::parse_muscle_overrides(parts[1], "fuzz_overrides.json", set);
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz_overrides.json");
  }
  return 0;
}
