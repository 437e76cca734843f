// The one input-format table (scene/input_formats.h): what each path is, and the messages when a file cannot
// serve the flag it was given to.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "io/load_error.h"
#include "scene/input_formats.h"
#include "scene/scene_setup.h"

namespace strata {
namespace {

TEST(InputFormats, IdentifiesByExtensionCaseInsensitivelyAndFoldersAsMakeHuman) {
  EXPECT_EQ(identify_input("a/joe.x3d").id, InputFormatId::HAnim);
  EXPECT_EQ(identify_input("arm.XML").id, InputFormatId::HAnim);
  EXPECT_EQ(identify_input("walk.BVH").id, InputFormatId::Bvh);
  EXPECT_EQ(identify_input("body.Obj").id, InputFormatId::Obj);
  EXPECT_EQ(identify_input("man.glb").id, InputFormatId::Gltf);
  EXPECT_EQ(identify_input("man.gltf").id, InputFormatId::Gltf);
  EXPECT_EQ(identify_input(std::filesystem::temp_directory_path()).id, InputFormatId::MakeHuman);
}

TEST(InputFormats, EveryExtensionBelongsToOneFormat) {
  std::set<std::string> seen;
  for (const InputFormat& f : input_formats())
    for (std::string_view e : f.extensions) EXPECT_TRUE(seen.insert(std::string(e)).second) << e;
  EXPECT_FALSE(seen.empty());
}

TEST(InputFormats, AnUnknownExtensionNamesThePathAndWhatIsSupported) {
  try {
    identify_input("crowd/notes.txt");
    FAIL() << "no error";
  } catch (const LoadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("crowd/notes.txt"), std::string::npos) << m;
    EXPECT_NE(m.find(".bvh"), std::string::npos) << m;
    EXPECT_NE(m.find(".glb"), std::string::npos) << m;
  }
}

TEST(InputFormats, AFileThatCannotServeTheFlagSaysWhatWould) {
  try {
    require_input("walk.bvh", kGivesSkinnedBody, "--mesh");
    FAIL() << "no error";
  } catch (const LoadError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("--mesh: walk.bvh is BVH motion capture, which has no skinned body", 0), 0u) << m;
    EXPECT_NE(m.find(".glb"), std::string::npos) << m;
  }
  EXPECT_THROW(require_input("man.glb", kGivesSkeleton, "--skeleton"), LoadError);
  EXPECT_THROW(require_input("man.x3d", kGivesMotion, "--motion"), LoadError);
  EXPECT_EQ(require_input("joe.x3d", kGivesSkeleton, "--skeleton").id, InputFormatId::HAnim);
}

// build_scene goes through the table: a capture given as --mesh is refused before anything is read.
TEST(InputFormats, BuildSceneRefusesAMeshFlagOnMotionCapture) {
  SceneOptions o;
  o.mesh = "does_not_exist.bvh";
  try {
    build_scene(o);
    FAIL() << "no error";
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("no skinned body"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
