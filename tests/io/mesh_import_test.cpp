// Mesh importers: OBJ (groups, index forms, compaction, errors), the MakeHuman CC0 base mesh fitted to H-Anim,
// and glTF 2.0 skinned meshes with their animation baked into H-Anim local rotations.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/mesh_check.h"
#include "components/mesh.h"
#include "io/gltf.h"
#include "io/makehuman.h"
#include "io/obj.h"
#include "systems/animation_sample.h"
#include "reference/fk_reference.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

const std::filesystem::path kData = STRATA_SHARED_DATA;
const std::filesystem::path kMakeHuman = kData / "makehuman_hm08";
const std::filesystem::path kCesium = kData / "gltf_khronos_samples" / "CesiumMan.glb";
const std::filesystem::path kRigged = kData / "gltf_khronos_samples" / "RiggedSimple.glb";

#define SKIP_WITHOUT(path) \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "test data absent: " << (path)

std::string load_error_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const LoadError& e) {
    return e.what();
  }
  return "<no LoadError>";
}

// ---------------------------------------------------------------------------------------------------------------
// OBJ
// ---------------------------------------------------------------------------------------------------------------

TEST(Obj, IndexFormsFansAndGroups) {
  const char* text =
      "# a square, a pentagon and a triangle\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 3 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "vn 0 0 2\n"
      "g quad\n"
      "f 1/1 2/2 3/3 4/4\n"
      "g poly\n"
      "f 2//1 5//1 6//1 7//1 3//1\n"
      "g quad\n"
      "f -7/1/1 -6/2/1 -5/3/1\n";  // relative: vertices 1, 2, 3
  const Mesh m = load_obj_text(text, "mem.obj");
  EXPECT_EQ(m.vertex_count(), 7u);
  // quad -> 2 fan triangles, pentagon -> 3, triangle -> 1
  ASSERT_EQ(m.triangle_count(), 6u);
  EXPECT_EQ(std::vector<std::uint32_t>(m.triangles.begin(), m.triangles.begin() + 6),
            (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(std::vector<std::uint32_t>(m.triangles.begin() + 6, m.triangles.begin() + 15),
            (std::vector<std::uint32_t>{1, 4, 5, 1, 5, 6, 1, 6, 2}));
  EXPECT_EQ(std::vector<std::uint32_t>(m.triangles.begin() + 15, m.triangles.end()),
            (std::vector<std::uint32_t>{0, 1, 2}));
  // "quad" seen twice is one part; parts numbered by first appearance.
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"quad", "poly"}));
  EXPECT_EQ(m.part[0], 0);
  EXPECT_EQ(m.part[4], 1);
  EXPECT_EQ(m.part[1], 0);  // first face that uses vertex 2 is the quad
  // vertices 5-7 never got a vt: one vertex without a consistent uv drops them all.
  EXPECT_TRUE(m.uvs.empty());
  ASSERT_EQ(m.normals.size(), 7u);
  EXPECT_NO_THROW(validate_mesh(m, "mem.obj"));
}

TEST(Obj, ConsistentUvsAndNormalsAreKept) {
  const char* text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
      "vt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nvt 0.7 0.8\nvt 0.1 0.2\n"
      "vn 0 0 3\n"
      "f 1/1/1 2/2/1 3/3/1\n"
      "f 2/2/1 4/4/1 3/5/1\n";
  // Vertex 3 is given vt 3 (0.5 0.6) then vt 5 (0.1 0.2): a seam, so per-vertex uvs are dropped; the corners keep
  // theirs.
  const Mesh seam = load_obj_text(text, "seam.obj");
  EXPECT_TRUE(seam.uvs.empty());
  ASSERT_EQ(seam.corner_uvs.size(), 6u);
  EXPECT_EQ(seam.corner_uvs[2], glm::vec2(0.5f, 0.6f));
  EXPECT_EQ(seam.corner_uvs[5], glm::vec2(0.1f, 0.2f));
  // Split where the seam is: vertex 3 (index 2) carries two values, every other vertex one, in first-use order.
  const CornerUvValues split = corner_uv_values(seam);
  EXPECT_EQ(split.uvs.size(), 5u);
  EXPECT_EQ(split.vertex, (std::vector<std::uint32_t>{0, 1, 2, 3, 2}));
  EXPECT_EQ(split.of_corner, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 4}));
  for (std::size_t c = 0; c < 6; ++c) {
    EXPECT_EQ(split.uvs[split.of_corner[c]], seam.corner_uvs[c]) << c;
    EXPECT_EQ(split.vertex[split.of_corner[c]], seam.triangles[c]) << c;
  }
  // A face without texture coordinates leaves the mesh without corner uvs rather than half of them.
  EXPECT_TRUE(load_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 2 4 3\n", "half.obj")
                  .corner_uvs.empty());
  const char* consistent =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
      "vt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nvt 0.7 0.8\nvt 0.5 0.6\n"
      "vn 0 0 3\n"
      "f 1/1/1 2/2/1 3/3/1\n"
      "f 2/2/1 4/4/1 3/5/1\n";  // a different vt index with the same value is no seam
  const Mesh m = load_obj_text(consistent, "ok.obj");
  ASSERT_EQ(m.uvs.size(), 4u);
  EXPECT_EQ(m.uvs[2], glm::vec2(0.5f, 0.6f));
  EXPECT_EQ(m.uvs[3], glm::vec2(0.7f, 0.8f));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_NEAR(m.normals[3].z, 1.0f, 1e-6f);  // stored normals are normalised
}

TEST(Obj, GroupFilterCompactsAndScales) {
  const char* text =
      "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 50 50 50\nv 10 10 0\nv 20 0 0\n"
      "g skip\nf 1 2 3\n"
      "g empty\n"
      "g keep\nf 2 6 5\nf 2 5 3\n"
      "g skip\nf 4 5 6\n";
  ObjSource source;
  const Mesh m = load_obj_text(text, "mem.obj", ObjOptions{{"keep"}, 0.1f}, &source);
  // keep uses file vertices 2, 3, 5, 6 (1-based) -> 4 vertices renumbered in file order.
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(source.file_vertex, (std::vector<std::uint32_t>{1, 2, 4, 5}));
  EXPECT_EQ(source.file_positions.size(), 6u);
  EXPECT_EQ(m.positions[0], glm::vec3(1.0f, 0.0f, 0.0f));
  EXPECT_EQ(m.positions[3], glm::vec3(2.0f, 0.0f, 0.0f));
  EXPECT_EQ(m.triangles, (std::vector<std::uint32_t>{0, 3, 2, 0, 2, 1}));
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"keep"}));
  // An empty group is fine until someone asks for it.
  EXPECT_NO_THROW(load_obj_text(text, "mem.obj"));
  EXPECT_NE(load_error_message([&] { load_obj_text(text, "mem.obj", ObjOptions{{"empty"}}); })
                .find("mem.obj: group 'empty': requested but has no faces"),
            std::string::npos);
  EXPECT_NE(load_error_message([&] { load_obj_text(text, "mem.obj", ObjOptions{{"nope"}}); }).find("'nope'"),
            std::string::npos);
  // o starts a group too, and faces before any group go to "default".
  const Mesh o = load_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no thing\nf 3 2 1\n", "o.obj");
  EXPECT_EQ(o.part_names, (std::vector<std::string>{"default", "thing"}));
}

TEST(Obj, ErrorsNameFileAndLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  auto message = [](const std::string& text) { return load_error_message([&] { load_obj_text(text, "bad.obj"); }); };
  EXPECT_NE(message(tri + "f 1 2 4\n").find("bad.obj:4: f: v index 4 out of range"), std::string::npos)
      << message(tri + "f 1 2 4\n");
  EXPECT_NE(message(tri + "f 0 1 2\n").find("bad.obj:4: f: v index 0"), std::string::npos);
  EXPECT_NE(message(tri + "f -4 1 2\n").find("bad.obj:4: f: v index -4 out of range"), std::string::npos);
  EXPECT_NE(message(tri + "f 1/2 2 3\n").find("bad.obj:4: f: vt index 2 out of range"), std::string::npos);
  EXPECT_NE(message(tri + "f 1 2\n").find("bad.obj:4: f: a face needs at least 3 vertices"), std::string::npos);
  EXPECT_NE(message("v 0 0 0\nv 1 nan 0\n").find("bad.obj:2: v: non-finite coordinate"), std::string::npos);
  EXPECT_NE(message("v 0 0 0\nv 1 inf 0\n").find("bad.obj:2: v: non-finite"), std::string::npos);
  EXPECT_NE(message("v 0 0 0\nv 1 0.5x 0\n").find("bad.obj:2: v: malformed number '0.5x'"), std::string::npos);
  EXPECT_NE(message("v 0 0\n").find("bad.obj:1: v: expected 3 coordinates"), std::string::npos);
  EXPECT_NE(message(tri + "f 1 2 a\n").find("bad.obj:4: f: malformed v index 'a'"), std::string::npos);
  EXPECT_NE(message(tri).find("no vertices or no faces"), std::string::npos);  // validate_mesh
  EXPECT_NE(load_error_message([] { load_obj_file("/nonexistent/x.obj"); }).find("cannot open"), std::string::npos);
  // CRLF, comments, '+' signs and exponents are fine.
  EXPECT_EQ(load_obj_text("v +1e0 0 0 # c\r\nv 0 1 0\r\nv 0 0 1\r\nf 1 2 3\r\n", "crlf.obj").positions[0].x, 1.0f);
}

TEST(Obj, MakeHumanBaseObj) {
  SKIP_WITHOUT(kMakeHuman / "base.obj");
  const Mesh all = load_obj_file(kMakeHuman / "base.obj");
  EXPECT_EQ(all.part_names.size(), 139u);  // 172 g lines, 139 distinct names (data-README)
  const Mesh body = load_obj_file(kMakeHuman / "base.obj", ObjOptions{{"body"}, 0.1f});
  EXPECT_EQ(body.vertex_count(), 13380u);
  EXPECT_EQ(body.triangle_count(), 26756u);  // 13,378 quads
  EXPECT_TRUE(body.uvs.empty());             // 14,517 distinct uvs on 13,380 vertices: seams, dropped
  EXPECT_EQ(body.corner_uvs.size(), 3u * body.triangle_count());  // kept per corner
  EXPECT_EQ(body.normals.size(), body.vertex_count());
  float lo = 1e9f, hi = -1e9f;
  for (const glm::vec3& p : body.positions) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  EXPECT_NEAR(lo, -0.8168f, 1e-3f);
  EXPECT_NEAR(hi, 0.8491f, 1e-3f);
}

// ---------------------------------------------------------------------------------------------------------------
// MakeHuman
// ---------------------------------------------------------------------------------------------------------------

class MakeHumanTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (std::filesystem::exists(kMakeHuman / "base.obj")) body_ = new ImportedBody(load_makehuman(kMakeHuman));
  }
  static void TearDownTestSuite() {
    delete body_;
    body_ = nullptr;
  }
  void SetUp() override {
    if (!body_) GTEST_SKIP() << "test data absent: " << kMakeHuman;
  }
  static ImportedBody* body_;
};
ImportedBody* MakeHumanTest::body_ = nullptr;

TEST_F(MakeHumanTest, ShapeAndBinding) {
  const ImportedBody& b = *body_;
  EXPECT_EQ(b.skeleton.joint_count(), 25u);
  EXPECT_EQ(b.mesh.vertex_count(), 13380u);
  EXPECT_EQ(b.mesh.part_names, paper_part_names());
  ASSERT_EQ(b.skin.vertex_count(), b.mesh.vertex_count());
  EXPECT_NO_THROW(validate_mesh(b.mesh, "makehuman"));
  for (std::size_t j = 1; j < b.skeleton.joint_count(); ++j) EXPECT_LT(b.skeleton.parents[j], (int)j);
  std::size_t four = 0;
  for (std::size_t v = 0; v < b.skin.vertex_count(); ++v) {
    float sum = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k) {
      ASSERT_GE(b.skin.joints[v][k], 0);
      ASSERT_LT(b.skin.joints[v][k], 25);
      if (b.skin.weights[v][k] == 0.0f) { EXPECT_EQ(b.skin.joints[v][k], 0); }
      sum += b.skin.weights[v][k];
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f);
    four += b.skin.influence_count(v) == 4;
  }
  EXPECT_GT(four, 0u);
}

TEST_F(MakeHumanTest, StandsOnTheFloorLeftIsPlusX) {
  const ImportedBody& b = *body_;
  glm::vec3 lo(1e9f), hi(-1e9f);
  for (const glm::vec3& p : b.mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  EXPECT_NEAR(lo.y, 0.0f, 1e-6f);
  // The hm08 base mesh is 16.66 dm from sole to crown (data-README bounds); metres, not decimetres.
  std::cout << "[ info ] MakeHuman body height " << hi.y - lo.y << " m\n";
  EXPECT_GT(hi.y - lo.y, 1.6f);
  EXPECT_LT(hi.y - lo.y, 1.8f);
  const Skeleton& s = b.skeleton;
  for (std::size_t j = 0; j < s.joint_count(); ++j) {
    const std::string& n = s.joint_names[j];
    if (n.starts_with("l_")) { EXPECT_GT(s.centers[j].x, 0.02f) << n; }
    if (n.starts_with("r_")) {
      EXPECT_LT(s.centers[j].x, -0.02f) << n;
      // Symmetric base mesh: the right joint mirrors the left one.
      const glm::vec3 l = s.centers[s.find_joint("l_" + n.substr(2))];
      EXPECT_NEAR(s.centers[j].x, -l.x, 2e-3f) << n;
      EXPECT_NEAR(s.centers[j].y, l.y, 2e-3f) << n;
    }
  }
  // Anatomical order along Y.
  auto y = [&](const char* name) { return s.centers[s.find_joint(name)].y; };
  EXPECT_LT(y("l_ankle"), y("l_knee"));
  EXPECT_LT(y("l_knee"), y("l_hip"));
  EXPECT_LT(y("HumanoidRoot"), y("sacroiliac"));
  EXPECT_LT(y("vl5"), y("vt6"));
  EXPECT_LT(y("vt6"), y("vt1"));
  EXPECT_LT(y("vt1"), y("vc4"));
  EXPECT_LT(y("vc4"), y("skullbase"));
  EXPECT_LT(y("l_wrist"), y("l_elbow"));
  EXPECT_LT(y("l_elbow"), y("l_shoulder"));
  // A-pose kept as rest: the wrist is well outside the shoulder (arms-down would put it right below).
  EXPECT_GT(s.centers[s.find_joint("l_wrist")].x - s.centers[s.find_joint("l_shoulder")].x, 0.15f);
  // Parts follow sides too.
  const auto& parts = b.mesh.part_names;
  const auto part_id = [&](const char* name) { return std::find(parts.begin(), parts.end(), name) - parts.begin(); };
  for (std::size_t v = 0; v < b.mesh.vertex_count(); ++v) {
    if (b.mesh.part[v] == part_id("lHand")) { ASSERT_GT(b.mesh.positions[v].x, 0.2f); }
    if (b.mesh.part[v] == part_id("rFoot")) { ASSERT_LT(b.mesh.positions[v].x, 0.0f); }
  }
}

TEST_F(MakeHumanTest, JointsLieInsideTheirSkinRegion) {
  const ImportedBody& b = *body_;
  const Skeleton& s = b.skeleton;
  const std::size_t nj = s.joint_count();
  // Region of joint j: vertices whose strongest H-Anim influence is j, its parent or one of its children (a
  // joint sits where its parent's segment meets its own).
  std::vector<int> dominant(b.mesh.vertex_count());
  for (std::size_t v = 0; v < dominant.size(); ++v)
    dominant[v] = b.skin.joints[v][std::max_element(b.skin.weights[v].begin(), b.skin.weights[v].end()) -
                                   b.skin.weights[v].begin()];
  for (std::size_t j = 0; j < nj; ++j) {
    glm::vec3 lo(1e9f), hi(-1e9f);
    std::size_t count = 0;
    for (std::size_t v = 0; v < dominant.size(); ++v) {
      const int d = dominant[v];
      if (d == (int)j || d == s.parents[j] || s.parents[d] == (int)j) {
        lo = glm::min(lo, b.mesh.positions[v]);
        hi = glm::max(hi, b.mesh.positions[v]);
        ++count;
      }
    }
    ASSERT_GT(count, 0u) << s.joint_names[j];
    const glm::vec3 c = s.centers[j];
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(c[a], lo[a] - 0.005f) << s.joint_names[j] << " axis " << a;
      EXPECT_LE(c[a], hi[a] + 0.005f) << s.joint_names[j] << " axis " << a;
    }
  }
}

TEST_F(MakeHumanTest, EveryBodyBoneIsMapped) {
  std::ifstream in(kMakeHuman / "default_weights.mhw");
  const nlohmann::json w = nlohmann::json::parse(in)["weights"];
  std::set<std::string> body_bones, parts_used;
  for (const auto& [bone, list] : w.items())
    for (const auto& pair : list)
      if (pair[0].get<int>() < 13380) body_bones.insert(bone);  // body = vertices 0..13379 (data-README)
  EXPECT_EQ(body_bones.size(), 124u);
  for (const std::string& bone : body_bones) {
    EXPECT_FALSE(makehuman_bone_part(bone).empty()) << bone;
    EXPECT_FALSE(makehuman_bone_joint(bone).empty()) << bone;
  }
  EXPECT_EQ(makehuman_bone_part("finger1-2.R"), "rThumb2");
  EXPECT_EQ(makehuman_bone_part("finger5-3.L"), "lPinky3");
  EXPECT_EQ(makehuman_bone_part("upperarm02.L"), "lShldr");
  EXPECT_EQ(makehuman_bone_part("oris03.R"), "head");
  EXPECT_EQ(makehuman_bone_joint("lowerarm01.L"), "l_elbow");
  EXPECT_EQ(makehuman_bone_joint("toe3-2.L"), "l_midtarsal");
  EXPECT_TRUE(makehuman_bone_part("no_such_bone").empty());
  // Parts in use: all 53 of the paper's. The eyeballs are helper geometry outside the "body" group; the eyes'
  // parts are the lids the eye bones weigh (never most, so only that rule gives them any vertex).
  for (std::uint16_t p : body_->mesh.part) parts_used.insert(body_->mesh.part_names[p]);
  EXPECT_EQ(parts_used.size(), 53u);
  for (const char* p : {"hip", "abdomen", "chest", "neck", "head", "lEye", "rEye", "lThumb3", "rPinky1", "lToe", "rCollar"})
    EXPECT_TRUE(parts_used.count(p)) << p;
}

TEST_F(MakeHumanTest, SkinFollowsTheRightJoints) {
  const ImportedBody& b = *body_;
  const Skeleton& s = b.skeleton;
  std::vector<glm::quat> rot(s.joint_count(), glm::quat(1, 0, 0, 0));
  rot[s.find_joint("l_elbow")] = glm::angleAxis(1.2f, glm::vec3(1, 0, 0));
  const ReferencePose pose = fk_reference(s, rot, glm::vec3(0.0f));
  const auto& parts = b.mesh.part_names;
  const auto part_id = [&](const char* name) { return std::find(parts.begin(), parts.end(), name) - parts.begin(); };
  float hand_min = 1e9f, foot_max = 0.0f;
  for (std::size_t v = 0; v < b.mesh.vertex_count(); ++v) {
    glm::vec4 p(0.0f);
    for (int k = 0; k < kMaxInfluences; ++k)
      p += b.skin.weights[v][k] * (pose.skinning[b.skin.joints[v][k]] * glm::vec4(b.mesh.positions[v], 1.0f));
    const float moved = glm::length(glm::vec3(p) - b.mesh.positions[v]);
    if (b.mesh.part[v] == part_id("lHand")) hand_min = std::min(hand_min, moved);
    if (b.mesh.part[v] == part_id("rFoot") || b.mesh.part[v] == part_id("rHand")) foot_max = std::max(foot_max, moved);
  }
  EXPECT_GT(hand_min, 0.1f);
  EXPECT_LT(foot_max, 1e-5f);  // float noise only: nothing on the right side follows the left elbow
}

TEST(MakeHuman, MissingDirectory) {
  EXPECT_NE(load_error_message([] { load_makehuman("/nonexistent/mh"); }).find("/nonexistent/mh/base.obj"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------------
// glTF: an independent evaluator of the GLB (JSON + BIN chunks), LINEAR channels only, for comparison
// ---------------------------------------------------------------------------------------------------------------

struct Glb {
  nlohmann::json json;
  std::vector<unsigned char> bin;

  explicit Glb(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto u32 = [&](std::size_t at) {
      std::uint32_t x;
      std::memcpy(&x, bytes.data() + at, 4);
      return x;
    };
    const std::uint32_t json_len = u32(12);
    json = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_len);
    const std::size_t bin_at = 20 + json_len;
    bin.assign(bytes.begin() + bin_at + 8, bytes.begin() + bin_at + 8 + u32(bin_at));
  }
  template <class T>
  std::vector<T> read(int accessor) const {
    const auto& a = json["accessors"][accessor];
    const auto& bv = json["bufferViews"][a["bufferView"].get<int>()];
    const std::size_t width = std::map<std::string, int>{{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}}.at(a["type"]);
    const std::size_t count = a["count"];
    const std::size_t stride = bv.value("byteStride", 0) ? bv["byteStride"].get<std::size_t>() : width * sizeof(T);
    const std::size_t at = bv.value("byteOffset", 0) + a.value("byteOffset", 0);
    std::vector<T> out(count * width);
    for (std::size_t i = 0; i < count; ++i) std::memcpy(&out[i * width], bin.data() + at + i * stride, width * sizeof(T));
    return out;
  }
  glm::mat4 local(int node, float t) const {
    const auto& n = json["nodes"][node];
    if (n.contains("matrix")) {
      glm::mat4 m;
      for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = n["matrix"][i].get<float>();
      return m;
    }
    glm::vec3 tr(0.0f), sc(1.0f);
    glm::quat r(1, 0, 0, 0);
    if (n.contains("translation")) tr = glm::vec3(n["translation"][0], n["translation"][1], n["translation"][2]);
    if (n.contains("scale")) sc = glm::vec3(n["scale"][0], n["scale"][1], n["scale"][2]);
    if (n.contains("rotation")) r = glm::quat(n["rotation"][3], n["rotation"][0], n["rotation"][1], n["rotation"][2]);
    if (t >= 0.0f) {
      const auto& anim = json["animations"][0];
      for (const auto& ch : anim["channels"]) {
        if (ch["target"]["node"] != node) continue;
        const auto& smp = anim["samplers"][ch["sampler"].get<int>()];
        const std::vector<float> times = read<float>(smp["input"]), vals = read<float>(smp["output"]);
        std::size_t k = 0;
        float u = 0.0f;
        if (t >= times.back()) k = times.size() - 1;
        else if (t > times.front()) {
          while (times[k + 1] <= t) ++k;
          u = (t - times[k]) / (times[k + 1] - times[k]);
        }
        const std::size_t k1 = std::min(k + 1, times.size() - 1);
        const std::string path = ch["target"]["path"];
        if (path == "rotation") {
          const glm::quat a(vals[4 * k + 3], vals[4 * k], vals[4 * k + 1], vals[4 * k + 2]);
          const glm::quat b(vals[4 * k1 + 3], vals[4 * k1], vals[4 * k1 + 1], vals[4 * k1 + 2]);
          r = glm::slerp(a, b, u);
        } else {
          const glm::vec3 a(vals[3 * k], vals[3 * k + 1], vals[3 * k + 2]);
          const glm::vec3 b(vals[3 * k1], vals[3 * k1 + 1], vals[3 * k1 + 2]);
          (path == "translation" ? tr : sc) = glm::mix(a, b, u);
        }
      }
    }
    return glm::translate(glm::mat4(1.0f), tr) * glm::mat4_cast(glm::normalize(r)) * glm::scale(glm::mat4(1.0f), sc);
  }
  glm::mat4 global(int node, float t) const {
    for (std::size_t p = 0; p < json["nodes"].size(); ++p)
      if (json["nodes"][p].contains("children"))
        for (const auto& c : json["nodes"][p]["children"])
          if (c == node) return global(static_cast<int>(p), t) * local(node, t);
    return local(node, t);
  }
};

// Max distance between the glTF's own skinning at time t and Strata's (rest mesh + baked clip + fk_reference).
float skinning_error(const Glb& glb, const ImportedBody& body, float t) {
  const auto& prim = glb.json["meshes"][0]["primitives"][0];
  const std::vector<float> pos = glb.read<float>(prim["attributes"]["POSITION"]);
  const std::vector<std::uint16_t> js = glb.read<std::uint16_t>(prim["attributes"]["JOINTS_0"]);
  const std::vector<float> ws = glb.read<float>(prim["attributes"]["WEIGHTS_0"]);
  const auto& skin = glb.json["skins"][0];
  const std::vector<float> ibm = glb.read<float>(skin["inverseBindMatrices"]);
  std::vector<glm::mat4> joint_matrix;
  for (std::size_t k = 0; k < skin["joints"].size(); ++k)
    joint_matrix.push_back(glb.global(skin["joints"][k], t) * glm::make_mat4(ibm.data() + 16 * k));

  std::vector<glm::quat> rotations(body.skeleton.joint_count());
  glm::vec3 root(0.0f);
  sample_clip(body.clips.at(0), t, rotations, root);
  const ReferencePose pose = fk_reference(body.skeleton, rotations, root);

  float worst = 0.0f;
  for (std::size_t v = 0; v < pos.size() / 3; ++v) {
    glm::vec4 expected(0.0f), got(0.0f);
    float sum = 0.0f;
    for (int c = 0; c < 4; ++c) sum += ws[4 * v + c];
    for (int c = 0; c < 4; ++c)
      expected += ws[4 * v + c] / sum * (joint_matrix[js[4 * v + c]] * glm::vec4(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], 1.0f));
    for (int k = 0; k < kMaxInfluences; ++k)
      got += body.skin.weights[v][k] * (pose.skinning[body.skin.joints[v][k]] * glm::vec4(body.mesh.positions[v], 1.0f));
    // The loader turned the figure to face +Z (ImportedBody::facing_turn); the file's skinning is in its own space.
    worst = std::max(worst, glm::length(body.facing_turn * glm::vec3(expected) - glm::vec3(got)));
  }
  return worst;
}

TEST(Gltf, CesiumManCountsAndRestPose) {
  SKIP_WITHOUT(kCesium);
  const ImportedBody b = load_gltf(kCesium);
  const Glb glb(kCesium);
  EXPECT_EQ(glb.json["animations"][0]["channels"].size(), 57u);
  EXPECT_EQ(b.mesh.vertex_count(), 3273u);
  EXPECT_EQ(b.mesh.triangle_count(), 4672u);
  EXPECT_EQ(b.skeleton.joint_count(), 19u);
  EXPECT_EQ(b.mesh.uvs.size(), 3273u);
  EXPECT_EQ(b.mesh.normals.size(), 3273u);
  EXPECT_NO_THROW(validate_mesh(b.mesh, "CesiumMan"));
  EXPECT_EQ(b.skeleton.parents[0], -1);
  for (std::size_t j = 1; j < b.skeleton.joint_count(); ++j) {
    EXPECT_GE(b.skeleton.parents[j], 0);
    EXPECT_LT(b.skeleton.parents[j], (int)j);
    EXPECT_EQ(b.skeleton.source_joint_names[j].rfind("joint_", 0), 0u);  // every node is unnamed
  }
  // Named by shape (components/humanoid_shape.h) and turned to face +Z: the left hip at +X, knees below hips,
  // ankles below knees, the neck above the chest, every limb a parent-child chain as the IK needs.
  const Skeleton& s = b.skeleton;
  for (const char* name : {"HumanoidRoot", "vl5", "vt6", "vc4", "skullbase", "l_hip", "l_knee", "l_ankle", "r_hip",
                           "r_knee", "r_ankle", "l_shoulder", "l_elbow", "l_wrist", "r_shoulder", "r_elbow", "r_wrist"})
    EXPECT_GE(s.find_joint(name), 0) << name;
  auto at = [&](const char* name) { return s.centers[static_cast<std::size_t>(s.find_joint(name))]; };
  EXPECT_GT(at("l_hip").x, at("r_hip").x + 0.1f);
  EXPECT_GT(at("l_shoulder").x, at("r_shoulder").x + 0.1f);
  EXPECT_GT(at("l_hip").y, at("l_knee").y + 0.2f);  // CesiumMan is 1.5 m: 0.26 m thighs, 0.27 m shins
  EXPECT_GT(at("l_knee").y, at("l_ankle").y + 0.2f);
  EXPECT_GT(at("vc4").y, at("vt6").y);
  EXPECT_EQ(s.parents[s.find_joint("l_knee")], s.find_joint("l_hip"));
  EXPECT_EQ(s.parents[s.find_joint("r_wrist")], s.find_joint("r_elbow"));
  // The toes point forward (+Z) once turned.
  EXPECT_GT(at("l_midtarsal").z, at("l_ankle").z + 0.02f);
  EXPECT_TRUE(std::any_of(b.warnings.begin(), b.warnings.end(),
                          [](const std::string& w) { return w.find("turned -90 deg about +Y") != std::string::npos; }));
  // Z-up content under the root's -90 deg X matrix comes out Y-up, feet on the floor.
  glm::vec3 lo(1e9f), hi(-1e9f);
  for (const glm::vec3& p : b.mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  std::cout << "[ info ] CesiumMan bounds " << lo.x << " " << lo.y << " " << lo.z << " .. " << hi.x << " " << hi.y
            << " " << hi.z << "\n";
  // Up is the longest extent (the file's Z); the outstretched arms span X now that the figure faces +Z (the file's
  // figure faces X).
  EXPECT_NEAR(hi.y - lo.y, 1.51f, 0.03f);
  EXPECT_GT(hi.y - lo.y, hi.z - lo.z + 0.3f);
  EXPECT_GT(hi.y - lo.y, hi.x - lo.x + 0.3f);
  EXPECT_NEAR(lo.y, 0.0f, 0.05f);
  // Weights normalised; 210 vertices had sums well below 1 in the file.
  for (std::size_t v = 0; v < b.skin.vertex_count(); ++v) {
    float sum = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k) {
      sum += b.skin.weights[v][k];
      if (b.skin.weights[v][k] == 0.0f) { EXPECT_EQ(b.skin.joints[v][k], 0); }
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f);
  }
  ASSERT_EQ(b.clips.size(), 1u);
  EXPECT_NEAR(b.clips[0].duration, 2.0f, 0.05f);
  EXPECT_EQ(b.clips[0].rotations.size(), 19u);
  EXPECT_EQ(b.clips[0].rotations[0].times.size(), 49u);  // 49 keys, shared by every channel
  for (const std::string& w : b.warnings) std::cout << "[ info ] " << w << "\n";
  EXPECT_TRUE(std::any_of(b.warnings.begin(), b.warnings.end(),
                          [](const std::string& w) { return w.find("210 vertices") != std::string::npos; }));
}

TEST(Gltf, CesiumManBakedClipReproducesGltfSkinning) {
  SKIP_WITHOUT(kCesium);
  const ImportedBody b = load_gltf(kCesium);
  const Glb glb(kCesium);
  const std::vector<float> keys = glb.read<float>(glb.json["animations"][0]["samplers"][0]["input"]);
  float worst_key = 0.0f, worst_between = 0.0f;
  for (std::size_t k : {0u, 7u, 16u, 25u, 33u, 47u}) worst_key = std::max(worst_key, skinning_error(glb, b, keys[k]));
  for (std::size_t k : {3u, 12u, 30u, 44u})
    worst_between = std::max(worst_between, skinning_error(glb, b, 0.5f * (keys[k] + keys[k + 1])));
  std::cout << "[ info ] CesiumMan max skinning error: at keys " << worst_key * 1000.0f << " mm, between keys "
            << worst_between * 1000.0f << " mm\n";
  // Measured 3.99 mm at and between keys: CesiumMan animates the translation of non-root joints by up to 3 mm
  // (the loader's reported residual), which rotations about fixed centres cannot express. Exact otherwise
  // (RiggedSimple, whose joints only rotate, reproduces to 0.002 mm).
  EXPECT_LT(worst_key, 0.006f);
  EXPECT_LT(worst_between, 0.006f);
}

TEST(Gltf, RiggedSimple) {
  SKIP_WITHOUT(kRigged);
  const ImportedBody b = load_gltf(kRigged);
  EXPECT_EQ(b.mesh.vertex_count(), 96u);
  EXPECT_EQ(b.mesh.triangle_count(), 188u);
  EXPECT_EQ(b.skeleton.joint_count(), 2u);
  EXPECT_TRUE(b.mesh.uvs.empty());
  std::size_t one = 0, two = 0;
  for (std::size_t v = 0; v < 96; ++v) (b.skin.influence_count(v) == 1 ? one : two) += 1;
  EXPECT_EQ(one, 64u);
  EXPECT_EQ(two, 32u);
  glm::vec3 lo(1e9f), hi(-1e9f);
  for (const glm::vec3& p : b.mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  EXPECT_NEAR(hi.y - lo.y, 9.15f, 0.05f);  // the cylinder's long axis is Z in the file, Y after the root matrix
  const Glb glb(kRigged);
  const std::vector<float> keys = glb.read<float>(glb.json["animations"][0]["samplers"][0]["input"]);
  ASSERT_EQ(keys.size(), 3u);
  float worst = 0.0f;
  for (float t : {keys[0], keys[1], keys[2] - 1e-3f, 0.5f * (keys[0] + keys[1])})
    worst = std::max(worst, skinning_error(glb, b, t));
  std::cout << "[ info ] RiggedSimple max skinning error " << worst * 1000.0f << " mm\n";
  EXPECT_LT(worst, 0.005f);
}

// --- small glTF files written by the test, for the error paths ------------------------------------------------

std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = (bytes[i] << 16) | ((i + 1 < bytes.size() ? bytes[i + 1] : 0) << 8) |
                            (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += table[(n >> 18) & 63];
    out += table[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[n & 63] : '=';
  }
  return out;
}

// One triangle skinned to one joint. `position_count` lets a test claim more vertices than the buffer holds.
std::filesystem::path write_triangle_gltf(const std::filesystem::path& path, bool skinned, int position_count = 3,
                                          float bad_coordinate = 0.0f) {
  std::vector<unsigned char> bytes;
  auto put = [&](const void* p, std::size_t n) {
    bytes.insert(bytes.end(), static_cast<const unsigned char*>(p), static_cast<const unsigned char*>(p) + n);
  };
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, bad_coordinate};
  put(pos, sizeof pos);                                // 0..36
  const std::uint16_t joints[12] = {};                 // 36..60
  put(joints, sizeof joints);
  const float weights[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};  // 60..108
  put(weights, sizeof weights);
  nlohmann::json j = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}},
        {{"buffer", 0}, {"byteOffset", 60}, {"byteLength", 48}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", position_count}, {"type", "VEC3"},
         {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "VEC4"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"JOINTS_0", 1}, {"WEIGHTS_0", 2}}}}}}}}},
      {"nodes", {{{"mesh", 0}}, {{"name", "bone"}, {"translation", {0, 1, 0}}}}},
  };
  if (skinned) {
    j["nodes"][0]["skin"] = 0;
    j["skins"] = {{{"joints", {1}}}};
  }
  std::ofstream(path) << j.dump();
  return path;
}

TEST(Gltf, Errors) {
  EXPECT_NE(load_error_message([] { load_gltf("/nonexistent/a.glb"); }).find("/nonexistent/a.glb: cannot open"),
            std::string::npos);
  const test::TempDir tmp("strata_import");
  const std::filesystem::path junk = tmp / "strata_import_junk.gltf";
  std::ofstream(junk) << "this is not json";
  EXPECT_NE(load_error_message([&] { load_gltf(junk); }).find("strata_import_junk.gltf: not a readable glTF"),
            std::string::npos);

  // The small file is valid when skinned: one joint at (0, 1, 0), identity IBM, rest = bind positions.
  const ImportedBody ok = load_gltf(write_triangle_gltf(tmp / "strata_import_ok.gltf", true));
  EXPECT_EQ(ok.mesh.vertex_count(), 3u);
  EXPECT_EQ(ok.skeleton.joint_names, (std::vector<std::string>{"bone"}));
  EXPECT_EQ(ok.skeleton.centers[0], glm::vec3(0, 1, 0));
  EXPECT_NEAR(ok.mesh.positions[1].y, 1.0f, 1e-6f);  // identity IBM: the joint's default global moves the mesh
  EXPECT_TRUE(ok.clips.empty());

  EXPECT_NE(load_error_message([&] { load_gltf(write_triangle_gltf(tmp / "strata_import_noskin.gltf", false)); })
                .find("no skinned mesh"),
            std::string::npos);
  const std::string range = load_error_message([&] { load_gltf(write_triangle_gltf(tmp / "strata_import_range.gltf", true, 5)); });
  EXPECT_NE(range.find("strata_import_range.gltf: accessor 0 (POSITION)"), std::string::npos) << range;
  EXPECT_NE(range.find("out of range"), std::string::npos) << range;
  const std::string nan = load_error_message(
      [&] { load_gltf(write_triangle_gltf(tmp / "strata_import_nan.gltf", true, 3, std::numeric_limits<float>::quiet_NaN())); });
  EXPECT_NE(nan.find("accessor 0 (POSITION): element 2 is not finite"), std::string::npos) << nan;
}

}  // namespace
}  // namespace strata
