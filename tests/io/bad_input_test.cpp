// The bad-input contract of every loader (docs/reliability.md): a LoadError whose message is one line naming
// the file and the line, element or byte offset at fault; never a crash, a hang, another exception type, or a
// half-loaded result. The per-format suites (hanim_loader_test, bvh_test, mesh_import_test, binding_test) cover
// ordinary mistakes; this file holds the cases the issue names and the hostile inputs fuzzing turned up.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "io/bvh.h"
#include "io/gltf.h"
#include "io/hanim_loader.h"
#include "io/makehuman.h"
#include "io/obj.h"
#include "rig/binding.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

const fs::path kSeeds = fs::path(STRATA_TEST_DATA) / ".." / ".." / "fuzz" / "seeds";

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The message of the LoadError `f` throws; fails the test when it throws nothing or something else, or when the
// message is not one line naming `source`.
std::string error_of(const std::function<void()>& f, const std::string& source) {
  try {
    f();
  } catch (const LoadError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << "not one line: " << m;
    EXPECT_NE(m.find(source), std::string::npos) << "does not name " << source << ": " << m;
    return m;
  }
  ADD_FAILURE() << "no LoadError";
  return {};
}

bool contains(const std::string& haystack, const std::string& needle) { return haystack.find(needle) != std::string::npos; }

// ---- the four cases the issue names ----------------------------------------------------------------------------

TEST(BadInput, TruncatedBinaryGltfNamesTheByteOffset) {
  const std::vector<std::uint8_t> glb = read_bytes(kSeeds / "gltf" / "skinned_triangle.glb");
  ASSERT_GT(glb.size(), 100u);
  ASSERT_NO_THROW((void)load_gltf_memory(glb, "whole.glb"));  // the untruncated file is valid
  // Every cut, from an empty file to one byte short: header, JSON chunk, BIN chunk.
  for (std::size_t n = 0; n < glb.size(); ++n) {
    const std::string m =
        error_of([&] { (void)load_gltf_memory(std::span(glb.data(), n), "cut.glb"); }, "cut.glb");
    // Under 4 bytes the "glTF" magic is incomplete and the bytes are read (and refused) as glTF JSON.
    if (n >= 4) {
      EXPECT_TRUE(contains(m, "cut.glb: byte ")) << n << ": " << m;
    }
    if (n >= 12) {
      EXPECT_TRUE(contains(m, "byte 8: GLB header gives a length of")) << n << ": " << m;
    }
  }
  // The same through the file loader, with a consistent header but a chunk cut short.
  std::vector<std::uint8_t> cut(glb.begin(), glb.end() - 40);
  const std::uint32_t length = static_cast<std::uint32_t>(cut.size());
  std::memcpy(cut.data() + 8, &length, 4);
  const test::TempDir tmp("strata_bad_input");
  const fs::path file = tmp / "cut.glb";
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(cut.data()), static_cast<std::streamsize>(cut.size()));
  const std::string m = error_of([&] { (void)load_gltf(file); }, file.string());
  EXPECT_TRUE(contains(m, "runs past the end of the file")) << m;
  EXPECT_TRUE(contains(m, "truncated")) << m;
}

TEST(BadInput, BvhChannelCountsDisagreeWithFrameData) {
  // The hierarchy declares 6 + 3 = 9 channels; the second frame line carries 8 values, the third 10.
  const std::string head =
      "HIERARCHY\nROOT hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
      "Yrotation\n JOINT knee\n {\n  OFFSET 0 -10 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n"
      "   OFFSET 0 -5 0\n  }\n }\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n0 1 2 3 4 5 6 7 8\n";  // lines 1-19
  EXPECT_EQ(error_of([&] { (void)load_bvh_text(head + "0 1 2 3 4 5 6 7\n0 1 2 3 4 5 6 7 8\n", "c.bvh"); }, "c.bvh"),
            "c.bvh:20: frame 1 has 8 values, expected 9");
  EXPECT_EQ(error_of([&] { (void)load_bvh_text(head + "0 1 2 3 4 5 6 7 8\n0 1 2 3 4 5 6 7 8 9\n", "c.bvh"); }, "c.bvh"),
            "c.bvh:21: frame 2 has 10 values, expected 9");
  // A joint declaring fewer channels than the frames carry: the frame lines are then too long.
  std::string fewer = head;
  fewer.replace(fewer.find("CHANNELS 3 Zrotation Xrotation Yrotation"), 40, "CHANNELS 2 Zrotation Xrotation");
  fewer += "0 1 2 3 4 5 6 7 8\n0 1 2 3 4 5 6 7 8\n";
  EXPECT_EQ(error_of([&] { (void)load_bvh_text(fewer, "c.bvh"); }, "c.bvh"), "c.bvh:19: frame 0 has 9 values, expected 8");
}

TEST(BadInput, X3dHumanoidWithNanCentre) {
  for (const char* centre : {"0 nan 0", "NaN 0 0", "0 0 -nan", "inf 0 0", "0 1e39 0"}) {
    const std::string text = std::string("<X3D><Scene>\n<HAnimHumanoid name='h'>\n<HAnimJoint name='humanoid_root' center='") +
                             centre + "'/>\n</HAnimHumanoid></Scene></X3D>\n";
    const std::string m = error_of([&] { (void)load_humanoid_text(text, "nan.x3d"); }, "nan.x3d");
    EXPECT_TRUE(contains(m, "nan.x3d:3:")) << m;
    EXPECT_TRUE(contains(m, "humanoid_root")) << m;
    EXPECT_TRUE(contains(m, "center")) << m;
  }
  // The paper-era XML says the same.
  const std::string m = error_of(
      [] { (void)load_humanoid_text("<Humanoid>\n<Joint name='root' center='0 nan 0'/></Humanoid>", "nan.xml"); },
      "nan.xml");
  EXPECT_TRUE(contains(m, "nan.xml:2:")) << m;
}

TEST(BadInput, ObjIndicesOutOfRange) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";  // lines 1-5
  EXPECT_TRUE(contains(error_of([&] { (void)load_obj_text(tri + "f 1 2 9\n", "o.obj"); }, "o.obj"),
                       "o.obj:6: f: v index 9 out of range (3 v defined so far)"));
  EXPECT_TRUE(contains(error_of([&] { (void)load_obj_text(tri + "f 1/2 2/1 3/1\n", "o.obj"); }, "o.obj"),
                       "o.obj:6: f: vt index 2 out of range"));
  EXPECT_TRUE(contains(error_of([&] { (void)load_obj_text(tri + "f 1//1 2//1 3//-2\n", "o.obj"); }, "o.obj"),
                       "o.obj:6: f: vn index -2 out of range"));
  // A face may only reference vertices defined before it.
  EXPECT_TRUE(contains(error_of([] { (void)load_obj_text("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n", "o.obj"); }, "o.obj"),
                       "o.obj:2: f: v index 2 out of range"));
  // Indices too large for any integer type are malformed, not wrapped into range.
  for (const char* huge : {"99999999999999999999", "-99999999999999999999", "4294967298"}) {
    const std::string m = error_of([&] { (void)load_obj_text(tri + "f 1 2 " + huge + "\n", "o.obj"); }, "o.obj");
    EXPECT_TRUE(contains(m, "o.obj:6: f: ")) << m;
  }
}

// ---- glTF: hostile structure ----------------------------------------------------------------------------------

std::string gltf_text() {
  const std::vector<std::uint8_t> b = read_bytes(kSeeds / "gltf" / "skinned_triangle.gltf");
  return std::string(b.begin(), b.end());
}

ImportedBody load_text(const std::string& text, const char* name) {
  return load_gltf_memory({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}, name);
}

TEST(BadInput, GltfAccessorCountsThatWouldWrapAreOutOfRange) {
  std::string text = gltf_text();
  ASSERT_NO_THROW((void)load_text(text, "ok.gltf"));
  // POSITION's count 3 -> 2^62 + 1: (count - 1) * 12 wraps size_t to a small number that a naive check accepts.
  const std::size_t at = text.find("\"count\": 3, \"type\": \"VEC3\"");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 10, "\"count\": 4611686018427387905");
  const std::string m = error_of([&] { (void)load_text(text, "wrap.gltf"); }, "wrap.gltf");
  EXPECT_TRUE(contains(m, "wrap.gltf: accessor 0 (POSITION)")) << m;
  EXPECT_TRUE(contains(m, "out of range")) << m;
}

TEST(BadInput, GltfFromMemoryRefusesExternalFiles) {
  std::string text = gltf_text();
  const std::size_t uri = text.find("data:application/octet-stream;base64,");
  ASSERT_NE(uri, std::string::npos);
  text.replace(uri, text.find('"', uri) - uri, "/etc/passwd");
  const std::string m = error_of([&] { (void)load_text(text, "ext.gltf"); }, "ext.gltf");
  EXPECT_TRUE(contains(m, "not a readable glTF")) << m;
}

TEST(BadInput, GltfDeepNodeChainDoesNotOverflowTheStack) {
  // 50,000 nodes, each the only child of the previous one, the skinned mesh and its joint at the bottom: a
  // recursive walk of the node tree overflows the stack long before.
  std::string text = gltf_text();
  constexpr int kDepth = 50000;
  auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t p = text.find(from);
    ASSERT_NE(p, std::string::npos) << from;
    text.replace(p, from.size(), to);
  };
  // The original nodes (mesh, hip, knee) move to kDepth, kDepth + 1, kDepth + 2; node i < kDepth has child i + 1.
  replace("\"scenes\": [{\"nodes\": [0, 1]}]", "\"scenes\": [{\"nodes\": [0, " + std::to_string(kDepth + 1) + "]}]");
  replace("\"joints\": [1, 2]", "\"joints\": [" + std::to_string(kDepth + 1) + ", " + std::to_string(kDepth + 2) + "]");
  replace("\"children\": [2]}", "\"children\": [" + std::to_string(kDepth + 2) + "]}");
  replace("\"node\": 2,", "\"node\": " + std::to_string(kDepth + 2) + ",");
  std::string chain;
  for (int i = 0; i < kDepth; ++i) chain += "{\"children\": [" + std::to_string(i + 1) + "]}, ";
  replace("\"nodes\": [{\"mesh\": 0", "\"nodes\": [" + chain + "{\"mesh\": 0");
  const ImportedBody body = load_text(text, "deep.gltf");
  EXPECT_EQ(body.skeleton.joint_count(), 2u);
  EXPECT_EQ(body.mesh.vertex_count(), 3u);
}

TEST(BadInput, GltfSingularNodeScaleBakesNoNan) {
  // A zero scale on an animated joint makes its default global matrix singular: the bake would divide by zero.
  std::string text = gltf_text();
  const std::string from = "\"rotation\": [0, 0, 0, 1], \"translation\": [0, -0.5, 0]";
  const std::size_t p = text.find(from);
  ASSERT_NE(p, std::string::npos);
  text.replace(p, from.size(), from + ", \"scale\": [0, 0, 0]");
  try {
    const ImportedBody body = load_text(text, "zero.gltf");
    for (const AnimationClip& clip : body.clips)
      for (const RotationTrack& t : clip.rotations)
        for (const glm::quat& q : t.values)
          EXPECT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w));
    for (const glm::vec3& v : body.mesh.positions) EXPECT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("zero.gltf"), std::string::npos) << e.what();
  }
}

// ---- BVH and XML: hostile sizes and nesting ---------------------------------------------------------------------

TEST(BadInput, BvhHugeFrameCountIsRefusedBeforeAllocating) {
  const std::string text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
                           "MOTION\nFrames: 1e30\nFrame Time: 0.1\n0 0 0\n";
  const std::string m = error_of([&] { (void)load_bvh_text(text, "big.bvh"); }, "big.bvh");
  EXPECT_TRUE(contains(m, "big.bvh:10: 'Frames: 1e30' but 1 motion lines")) << m;
}

TEST(BadInput, BvhDeepNestingIsAnErrorNotAStackOverflow) {
  std::string text = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 0\n";
  for (int i = 1; i < 100000; ++i) text += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 1 0\nCHANNELS 0\n";
  const std::string m = error_of([&] { (void)load_bvh_text(text, "deep.bvh"); }, "deep.bvh");
  EXPECT_TRUE(contains(m, "nested deeper than")) << m;
}

TEST(BadInput, XmlDeepNestingIsAnErrorNotAStackOverflow) {
  std::string text = "<X3D><Scene>\n<HAnimHumanoid name='h'>\n";
  for (int i = 0; i < 100000; ++i) text += "<HAnimJoint name='j" + std::to_string(i) + "' center='0 0 0'>";
  const std::string m = error_of([&] { (void)load_humanoid_text(text, "deep.x3d"); }, "deep.x3d");
  // pugixml may reject the unclosed document first; either way it is a one-line error, not a crash.
  EXPECT_TRUE(contains(m, "deep.x3d:")) << m;
  std::string closed = text;
  for (int i = 0; i < 100000; ++i) closed += "</HAnimJoint>";
  closed += "</HAnimHumanoid></Scene></X3D>";
  const std::string m2 = error_of([&] { (void)load_humanoid_text(closed, "deep.x3d"); }, "deep.x3d");
  EXPECT_TRUE(contains(m2, "nested deeper than 256 levels")) << m2;
}

// ---- MakeHuman ------------------------------------------------------------------------------------------------------

struct MakeHumanTrio {
  std::string obj, skel, weights;
};

MakeHumanTrio tiny_makehuman() {
  const std::vector<std::uint8_t> b = read_bytes(kSeeds / "makehuman" / "tiny.mh");
  const std::string all(b.begin(), b.end());
  const std::size_t a = all.find('\0'), c = all.find('\0', a + 1);
  return {all.substr(0, a), all.substr(a + 1, c - a - 1), all.substr(c + 1)};
}

TEST(BadInput, MakeHumanFilesNameTheFileAndTheEntry) {
  const MakeHumanTrio ok = tiny_makehuman();
  const ImportedBody body = load_makehuman_text(ok.obj, ok.skel, ok.weights, "mh");
  EXPECT_EQ(body.skeleton.joint_count(), 25u);
  EXPECT_EQ(body.mesh.vertex_count(), 4u);  // the "body" group only

  auto err = [&](const std::string& obj, const std::string& skel, const std::string& weights) {
    return error_of([&] { (void)load_makehuman_text(obj, skel, weights, "mh"); }, "mh/");
  };
  // Broken JSON: nlohmann's message carries the line and column.
  std::string m = err(ok.obj, ok.skel.substr(0, ok.skel.size() / 2), ok.weights);
  EXPECT_TRUE(contains(m, "mh/default.mhskel: invalid JSON")) << m;
  EXPECT_TRUE(contains(m, "line 1, column")) << m;
  // A parent that is not a name, a parent cycle, a weight for a vertex the OBJ does not have.
  std::string skel = ok.skel;
  skel.replace(skel.find("\"parent\": \"root\""), 16, "\"parent\": 7");
  EXPECT_TRUE(contains(err(ok.obj, skel, ok.weights), "mh/default.mhskel: bone 'spine05': 'parent' must be"));
  skel = ok.skel;
  skel.replace(skel.find("\"root\": {\"parent\": null}"), 24, "\"root\": {\"parent\": \"spine05\"}");
  EXPECT_TRUE(contains(err(ok.obj, skel, ok.weights), "parent chain has a cycle"));
  std::string weights = ok.weights;
  weights.replace(weights.find("[[3, 1]"), 7, "[[99, 1]");
  EXPECT_TRUE(contains(err(ok.obj, ok.skel, weights), "mh/default_weights.mhw: bone 'upperleg01.L': vertex 99 out of range"));
  // A deeply nested value in the weights is described, not serialised whole.
  weights = ok.weights;
  weights.replace(weights.find("[[3, 1]"), 7, "[" + std::string(100000, '[') + std::string(100000, ']'));
  m = err(ok.obj, ok.skel, weights);
  EXPECT_TRUE(contains(m, "expected [vertex, weight] pairs, got a JSON array")) << m.substr(0, 200);
  // The OBJ's errors name base.obj and the line.
  EXPECT_TRUE(contains(err(ok.obj + "f 1 2 77\n", ok.skel, ok.weights), "mh/base.obj:11: f: v index 77 out of range"));
}

// ---- binding tables ---------------------------------------------------------------------------------------------

TEST(BadInput, BindingTableJsonErrorsNameLineAndColumn) {
  const std::string m = error_of([] { (void)load_binding_tables("{\"parts\": {\n\"hip\": \"HumanoidRoot\",,\n}}", "", "p.json"); },
                                 "p.json");
  EXPECT_TRUE(contains(m, "p.json: invalid JSON")) << m;
  EXPECT_TRUE(contains(m, "line 2, column")) << m;
}

}  // namespace
}  // namespace strata
