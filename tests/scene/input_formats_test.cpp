// The one input-format table (scene/input_formats.h): what each path is, and the messages when a file cannot
// serve the flag it was given to.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <string>

#include "io/load_error.h"
#include "scene/input_formats.h"
#include "scene/scene_setup.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

TEST(InputFormats, IdentifiesByExtensionCaseInsensitivelyAndFoldersAsMakeHuman) {
  EXPECT_EQ(identify_input("a/joe.x3d").id, InputFormatId::HAnim);
  EXPECT_EQ(identify_input("arm.XML").id, InputFormatId::HAnim);
  EXPECT_EQ(identify_input("walk.BVH").id, InputFormatId::Bvh);
  EXPECT_EQ(identify_input("body.Obj").id, InputFormatId::Obj);
  EXPECT_EQ(identify_input("man.glb").id, InputFormatId::Gltf);
  EXPECT_EQ(identify_input("man.gltf").id, InputFormatId::Gltf);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "strata_input_formats_mh";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "base.obj") << "v 0 0 0\n";
  EXPECT_EQ(identify_input(folder).id, InputFormatId::MakeHuman);
  std::filesystem::remove_all(folder);
}

// A folder without base.obj is not taken for MakeHuman.
TEST(InputFormats, AnyOtherFolderIsRefused) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "strata_input_formats_empty";
  std::filesystem::create_directories(folder);
  EXPECT_THROW(identify_input(folder), LoadError);
  std::filesystem::remove_all(folder);
}

// The first bytes win over a wrong extension; files that do not say go by the extension.
TEST(InputFormats, ContentDecidesWhenTheExtensionIsWrong) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "strata_input_formats_sniff";
  fs::create_directories(dir);
  std::ofstream(dir / "walk.x3d") << "HIERARCHY\nROOT hips\n";
  std::ofstream(dir / "body.xml") << "# exported\nv 0 0 0\nf 1 1 1\n";
  std::ofstream(dir / "man.bvh", std::ios::binary) << "glTF\x02\0\0\0";
  std::ofstream(dir / "skel.obj") << "<?xml version='1.0'?><X3D/>";
  std::ofstream(dir / "man.x3d") << "{\"asset\": {\"version\": \"2.0\"}}";
  std::ofstream(dir / "odd.bvh") << "hello";
  EXPECT_EQ(identify_input(dir / "walk.x3d").id, InputFormatId::Bvh);
  EXPECT_EQ(identify_input(dir / "body.xml").id, InputFormatId::Obj);
  EXPECT_EQ(identify_input(dir / "man.bvh").id, InputFormatId::Gltf);
  EXPECT_EQ(identify_input(dir / "skel.obj").id, InputFormatId::HAnim);
  EXPECT_EQ(identify_input(dir / "man.x3d").id, InputFormatId::Gltf);
  EXPECT_EQ(identify_input(dir / "odd.bvh").id, InputFormatId::Bvh);
  fs::remove_all(dir);
}

TEST(InputFormats, DevicesLoopsAndOversizedFilesAreRefusedBeforeReading) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "strata_input_formats_checks";
  fs::remove_all(dir);
  fs::create_directories(dir);
  EXPECT_THROW(identify_input("/dev/zero"), LoadError);
  fs::create_symlink(dir / "b.x3d", dir / "a.x3d");
  fs::create_symlink(dir / "a.x3d", dir / "b.x3d");
  try {
    identify_input(dir / "a.x3d");
    FAIL() << "no error";
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("symbolic link loop"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "big.bvh") << std::string(2048, ' ');
  set_input_size_limit(1024);
  EXPECT_THROW(identify_input(dir / "big.bvh"), LoadError);
  set_input_size_limit(kDefaultInputSizeLimit);
  EXPECT_EQ(identify_input(dir / "big.bvh").id, InputFormatId::Bvh);
  fs::remove_all(dir);
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

// A clip crowd plays each rig at its own size: the grid's default spacing scales with the rig's stature, and an
// explicit --spacing is kept as given.
TEST(SceneSetup, ClipGridSpacingScalesWithTheRigsStature) {
  const test::TempDir dir("strata_spacing");
  std::ifstream in(std::filesystem::path(STRATA_TEST_DATA) / ".." / ".." / "data" / "default_skeleton.x3d");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t humanoid = text.find("<HAnimHumanoid ");
  ASSERT_NE(humanoid, std::string::npos);
  text.insert(humanoid + 15, "scale='2 2 2' ");
  const std::filesystem::path giant = dir / "giant.x3d";
  std::ofstream(giant) << text;

  auto spacing_of = [](const SceneOptions& o) {
    const std::unique_ptr<Crowd> scene = build_scene(o);
    const WalkerLanes lanes = scene->lanes();
    return std::abs(lanes.at(lanes.placement, 0)[1] - lanes.at(lanes.placement, 0)[0]);
  };
  SceneOptions o;
  o.walkers = 2;
  o.rest = true;
  o.level = DetailLevel::none();
  const float person = spacing_of(o);
  EXPECT_NEAR(person, 1.25f, 0.01f);  // the shipped skeleton is 1.75 m
  o.skeleton = giant.string();
  EXPECT_NEAR(spacing_of(o), 2.0f * person, 0.01f);
  o.spacing = 0.8f;
  o.spacing_given = true;
  EXPECT_FLOAT_EQ(spacing_of(o), 0.8f);
}

}  // namespace
}  // namespace strata
