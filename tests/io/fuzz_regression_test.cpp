// Every crash, hang or leak fuzzing found (docs/reliability.md) stays fixed: each reproducer lives in
// tests/data/fuzz_regressions/<target>/ and goes through the same entry point as its fuzz target (fuzz/). The only
// acceptable outcomes are a successful load or a one-line LoadError naming the source; the sanitizer build
// (scripts/strata.sh sanitize) runs this too, so a memory error on a reproducer fails there as well.
// The files are small hand-made equivalents of what the fuzzer found (its own finds were mutated copies of
// ../shared/data files, which must not be copied into the repository).
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "fuzz/fuzz_common.h"
#include "io/bvh.h"
#include "io/gltf.h"
#include "io/hanim_loader.h"
#include "io/muscle_file.h"
#include "io/makehuman.h"
#include "io/obj.h"
#include "io/scenario_file.h"
#include "rig/binding.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

const fs::path kDir = fs::path(STRATA_TEST_DATA) / "fuzz_regressions";

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const std::map<std::string, std::function<void(const std::string&, const std::string&)>>& targets() {
  static const std::map<std::string, std::function<void(const std::string&, const std::string&)>> t = {
      {"hanim", [](const std::string& b, const std::string& name) { (void)to_rig(load_humanoid_text(b, name)); }},
      {"obj", [](const std::string& b, const std::string& name) { (void)load_obj_text(b, name); }},
      {"bvh",
       [](const std::string& b, const std::string& name) {
         const BvhMotion m = load_bvh_text(b, name);
         if (m.frame_count == 0) return;
         std::vector<glm::quat> r(m.joint_count());
         std::vector<glm::vec3> p(m.joint_count());
         m.pose(m.frame_count - 1, r, p);
       }},
      {"gltf",
       [](const std::string& b, const std::string& name) {
         (void)load_gltf_memory({reinterpret_cast<const std::uint8_t*>(b.data()), b.size()}, name);
       }},
      {"makehuman",
       [](const std::string& b, const std::string& name) {
         const auto parts = fuzz::split_parts(b, 3);
         (void)load_makehuman_text(parts[0], parts[1], parts[2], name);
       }},
      {"binding",
       [](const std::string& b, const std::string& name) {
         const auto parts = fuzz::split_parts(b, 2);
         (void)load_binding_tables(parts[0], parts[1], name, name);
       }},
      {"muscle",
       [](const std::string& b, const std::string& name) {
         static const Skeleton skeleton = load_default_humanoid().skeleton;
         const auto parts = fuzz::split_parts(b, 2);
         const MuscleSet set = parse_muscles(parts[0], name, skeleton);
         (void)parse_muscle_overrides(parts[1], name, set);
       }},
      {"scenario", [](const std::string& b, const std::string& name) { (void)parse_scenario(b, name); }},
  };
  return t;
}

TEST(FuzzRegressions, EveryReproducerLoadsOrFailsWithOneLine) {
  ASSERT_TRUE(fs::is_directory(kDir)) << kDir;
  std::size_t files = 0;
  for (const auto& dir : fs::directory_iterator(kDir)) {
    const std::string target = dir.path().filename().string();
    const auto it = targets().find(target);
    ASSERT_NE(it, targets().end()) << "no fuzz target named " << target;
    for (const auto& file : fs::directory_iterator(dir.path())) {
      const std::string name = file.path().filename().string();
      SCOPED_TRACE(target + "/" + name);
      ++files;
      try {
        it->second(read_text(file.path()), name);
      } catch (const LoadError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find(name), std::string::npos) << m;
      }
    }
  }
  EXPECT_GT(files, 0u);
}

// The specific findings, each with the error it must now produce.
TEST(FuzzRegressions, GltfNodeNamingAMissingMesh) {
  for (const char* file : {"node_mesh_out_of_range.gltf", "node_mesh_without_meshes.gltf"}) {
    const std::string bytes = read_text(kDir / "gltf" / file);
    try {
      (void)load_gltf_memory({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, file);
      ADD_FAILURE() << file << ": loaded";
    } catch (const LoadError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(file) + ": node 0: mesh"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
  }
}

TEST(FuzzRegressions, NamesWithNewlinesStillGiveOneLine) {
  // A JSON "\n" escape or a newline inside an XML attribute puts a line break into a quoted name.
  try {
    (void)load_binding_tables(read_text(kDir / "binding" / "joint_name_with_newline.bin"), "", "nl.json");
    ADD_FAILURE() << "loaded";
  } catch (const LoadError& e) {
    EXPECT_EQ(std::string(e.what()), "nl.json: parts.rFoot: unknown joint 'r_\\nkle'");
  }
  try {
    (void)load_humanoid_text(read_text(kDir / "hanim" / "joint_name_with_newline.x3d"), "nl.x3d");
    ADD_FAILURE() << "loaded";
  } catch (const LoadError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_NE(m.find("nl.x3d:2:"), std::string::npos) << m;
    EXPECT_NE(m.find("a\\nb"), std::string::npos) << m;
  }
  EXPECT_EQ(LoadError::one_line("a\tb\r\x01"), "a\tb\\r\\x01");
}

TEST(FuzzRegressions, JsonNumberOverflowIsALoadError) {
  // nlohmann throws out_of_range, not parse_error, for a number beyond double: both loaders' JSON must say so in
  // a LoadError naming the file.
  const std::string bytes = read_text(kDir / "binding" / "number_overflow.bin");
  try {
    (void)load_binding_tables(bytes, "", "number_overflow.bin");
    ADD_FAILURE() << "loaded";
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("number_overflow.bin: invalid JSON"), std::string::npos) << e.what();
  }
  try {
    (void)load_makehuman_text("v 0 0 0\nv 1 0 0\nv 0 1 0\ng body\nf 1 2 3\n", "{\"bones\": 1e400}", "{}", "mh");
    ADD_FAILURE() << "loaded";
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("mh/default.mhskel: invalid JSON"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
