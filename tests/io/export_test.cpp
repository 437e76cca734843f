// glTF export: the shipped walker written as GLB (io/gltf_export.h) with a baked walk (motion/walk_bake.h), read
// back by the project's own importer (io/gltf.h) and by a minimal GLB parser here, and posed against the engine.
#include <gtest/gtest.h>

#include "tests/apps/strata_cli_runner.h"
#include "tests/temp_dir.h"
#include <nlohmann/json.hpp>

#include <array>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "components/rig.h"
#include "io/gltf.h"
#include "io/gltf_export.h"
#include "io/hanim_loader.h"
#include "scene/walk_bake.h"
#include "profiling/profiler.h"
#include "rig/body_rig.h"
#include "systems/animation_sample.h"
#include "scene/crowd.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

// One scratch directory for the test program (CTest runs each test in a program of its own), removed when it exits.
const fs::path& scratch_dir() {
  static const test::TempDir dir("strata_export_test");
  return dir.path();
}

const Rig& shipped_rig() {
  static const Rig rig = [] {
    Rig r = to_rig(load_default_humanoid());
    r.body = default_bound_body();
    return r;
  }();
  return rig;
}

// The GLB's JSON chunk and BIN chunk, parsed by hand so the checks below do not go through tinygltf (which wrote
// the file) or the importer (which normalises weights).
struct Glb {
  nlohmann::json json;
  std::vector<unsigned char> bin;

  template <typename T>
  std::vector<T> accessor(int index) const {
    const auto& a = json.at("accessors").at(index);
    const auto& view = json.at("bufferViews").at(a.at("bufferView").get<int>());
    static const std::map<std::string, int> kComponents = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}};
    const std::size_t n = a.at("count").get<std::size_t>() * kComponents.at(a.at("type").get<std::string>());
    const std::size_t offset = view.value("byteOffset", 0u) + a.value("byteOffset", 0u);
    EXPECT_LE(offset + n * sizeof(T), bin.size());
    std::vector<T> out(n);
    std::memcpy(out.data(), bin.data() + offset, n * sizeof(T));
    return out;
  }
};

Glb read_glb(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Glb glb;
  auto u32 = [&](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  EXPECT_GE(bytes.size(), 20u);
  if (bytes.size() < 20) return glb;
  EXPECT_EQ(std::memcmp(bytes.data(), "glTF", 4), 0);
  EXPECT_EQ(u32(4), 2u);
  EXPECT_EQ(u32(8), bytes.size()) << "header length = file length";
  const std::uint32_t json_length = u32(12);
  EXPECT_EQ(u32(16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  glb.json = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_length);
  const std::size_t bin_at = 20 + json_length;
  EXPECT_LE(bin_at + 8, bytes.size());
  EXPECT_EQ(u32(bin_at + 4), 0x004E4942u);  // "BIN\0"
  glb.bin.assign(bytes.begin() + bin_at + 8, bytes.begin() + bin_at + 8 + u32(bin_at));
  return glb;
}

// The engine's own walker, as bake_walk drives it, `steps` frames of 1/30 s after the start state; muscles off
// (the default shipped rig here has none attached), skinned at `level`.
struct EngineWalker {
  std::unique_ptr<Crowd> scene;
  glm::vec3 start_position{0.0f};
  float start_heading = 0.0f;
};

EngineWalker engine_walker(int level, std::uint64_t seed, int steps) {
  EngineWalker w;
  w.scene = std::make_unique<Crowd>(shipped_rig());
  CrowdConfig config;
  config.motion = MotionSource::Walk;
  config.walkers = 1;
  config.seed = seed;
  config.height_mean = w.scene->motion.locomotion.get()->rig_height;
  config.height_spread = 0.0f;
  spawn_crowd(*w.scene, config);
  set_detail_level(*w.scene, DetailLevel::mesh(level));
  Profiler profiler(1, false);
  step(*w.scene, 0.0f, profiler);
  const WalkerLanes lanes = w.scene->lanes();
  w.start_position = placement_of(lanes, 0).position;
  w.start_heading = lanes.placement[3 * lanes.stride];
  for (int i = 0; i < steps; ++i) step(*w.scene, 1.0f / 30.0f, profiler);
  return w;
}

// World point p of the engine scene in the exported clip's frame: relative to the walker's start placement.
glm::vec3 relative_to_start(const EngineWalker& w, const glm::vec3& p) {
  const glm::vec3 d = p - w.start_position;
  const float c = std::cos(w.start_heading), s = std::sin(w.start_heading);
  return {c * d.x - s * d.z, d.y, s * d.x + c * d.z};  // Ry(-heading)
}

// Per vertex of a mesh read back from an export, the exported mesh's vertex at its position (within 1e-5 m, the
// importer's float round trip): the exporter splits a vertex only where a UV seam gives it two texture
// coordinates, and no two of the shipped body's vertices are that close, so the nearest is the one.
std::vector<std::uint32_t> source_vertices(const Mesh& imported, const Mesh& exported) {
  constexpr float kCell = 1e-3f;
  auto cell = [&](const glm::vec3& p) {
    return std::array<int, 3>{int(std::floor(p.x / kCell)), int(std::floor(p.y / kCell)), int(std::floor(p.z / kCell))};
  };
  std::map<std::array<int, 3>, std::vector<std::uint32_t>> grid;
  for (std::uint32_t v = 0; v < exported.vertex_count(); ++v) grid[cell(exported.positions[v])].push_back(v);
  std::vector<std::uint32_t> source(imported.vertex_count(), 0);
  for (std::size_t w = 0; w < imported.vertex_count(); ++w) {
    const glm::vec3 p = imported.positions[w];
    const std::array<int, 3> c = cell(p);
    float best = 1e-5f;
    bool found = false;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (const std::uint32_t v : it->second)
            if (const float d = glm::length(exported.positions[v] - p); d <= best) best = d, source[w] = v, found = true;
        }
    EXPECT_TRUE(found) << "imported vertex " << w << " is no exported vertex";
  }
  return source;
}

class ExportLevels : public ::testing::TestWithParam<int> {};

TEST_P(ExportLevels, RoundTripsThroughTheImporter) {
  const int level = GetParam();
  const Rig& rig = shipped_rig();
  const BodyLevel& body = rig.body->levels[level];
  const fs::path file = scratch_dir() / ("walker_" + std::to_string(level) + ".glb");
  const BakedWalk walk = bake_walk(rig, {1.0f, 30.0f, 7});
  const GltfExportStats stats = write_gltf_binary(file, rig.skeleton, body, &walk.clip);
  EXPECT_EQ(stats.bytes, fs::file_size(file));
  EXPECT_EQ(stats.keys, 31u);

  const ImportedBody imported = load_gltf(file);
  // The body's texture coordinates are per corner; the file splits a vertex at each UV seam (8 % more at level 0).
  ASSERT_EQ(body.mesh.corner_uvs.size(), body.mesh.triangles.size());
  EXPECT_EQ(stats.vertices, body.mesh.vertex_count());
  EXPECT_EQ(imported.mesh.vertex_count(), stats.written_vertices);
  EXPECT_GT(stats.written_vertices, body.mesh.vertex_count());
  EXPECT_LT(stats.written_vertices, body.mesh.vertex_count() * 23 / 20);  // 7.6 % at level 0
  EXPECT_EQ(imported.mesh.triangle_count(), body.mesh.triangle_count());
  const std::vector<std::uint32_t> source = source_vertices(imported.mesh, body.mesh);
  std::vector<std::uint8_t> seen(body.mesh.vertex_count(), 0);
  ASSERT_EQ(imported.mesh.uvs.size(), imported.mesh.vertex_count()) << "TEXCOORD_0 read back";
  double worst_uv = 0.0;
  for (std::size_t c = 0; c < body.mesh.triangles.size(); ++c) {
    ASSERT_EQ(source[imported.mesh.triangles[c]], body.mesh.triangles[c]) << "corner " << c;
    seen[body.mesh.triangles[c]] = 1;
    worst_uv = std::max(worst_uv, double(glm::length(imported.mesh.uvs[imported.mesh.triangles[c]] -
                                                      body.mesh.corner_uvs[c])));
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<std::ptrdiff_t>(body.mesh.vertex_count()));
  EXPECT_LT(worst_uv, 1e-6) << "each corner's texture coordinate, through glTF's flipped v and back";
  ASSERT_EQ(imported.skeleton.joint_count(), rig.skeleton.joint_count());
  // Same names, same tree, same centres (the importer's centres are the joints' default-pose positions).
  std::vector<int> rig_joint(imported.skeleton.joint_count(), -1);
  for (std::size_t j = 0; j < imported.skeleton.joint_count(); ++j) {
    const std::string& name = imported.skeleton.joint_names[j];
    rig_joint[j] = rig.skeleton.find_joint(name);
    ASSERT_GE(rig_joint[j], 0) << name;
    EXPECT_EQ(rig.skeleton.joint_names[rig_joint[j]], name);
    const int p = imported.skeleton.parents[j];
    const int rp = rig.skeleton.parents[rig_joint[j]];
    EXPECT_EQ(p < 0 ? std::string("-") : imported.skeleton.joint_names[p],
              rp < 0 ? std::string("-") : rig.skeleton.joint_names[rp]) << name;
    EXPECT_LT(glm::length(imported.skeleton.centers[j] - rig.skeleton.centers[rig_joint[j]]), 1e-5f) << name;
  }
  // Rest mesh and binding survive: positions, and the weight of every rig joint on every vertex.
  double worst_position = 0.0, worst_weight = 0.0;
  for (std::size_t w = 0; w < imported.mesh.vertex_count(); ++w) {
    const std::size_t v = source[w];
    worst_position = std::max(worst_position, double(glm::length(imported.mesh.positions[w] - body.mesh.positions[v])));
    std::map<int, float> a, b;
    for (int k = 0; k < kMaxInfluences; ++k) {
      if (body.binding.weights[v][k] > 0) a[body.binding.joints[v][k]] += body.binding.weights[v][k];
      if (imported.skin.weights[w][k] > 0) b[rig_joint[imported.skin.joints[w][k]]] += imported.skin.weights[w][k];
    }
    ASSERT_EQ(a.size(), b.size()) << "vertex " << v;
    for (const auto& [joint, weight] : a) worst_weight = std::max(worst_weight, double(std::abs(b[joint] - weight)));
  }
  EXPECT_LT(worst_position, 1e-5);
  EXPECT_LT(worst_weight, 1e-5);

  ASSERT_EQ(imported.clips.size(), 1u);
  EXPECT_NEAR(imported.clips[0].duration, 1.0f, 1e-5f);
  EXPECT_EQ(walk.clip.duration, 1.0f);
}

TEST_P(ExportLevels, FileHasNormalisedWeightsAndTheBoundsTheValidatorRequires) {
  const int level = GetParam();
  const Rig& rig = shipped_rig();
  const fs::path file = scratch_dir() / ("raw_" + std::to_string(level) + ".glb");
  const BakedWalk walk = bake_walk(rig, {0.5f, 30.0f, 1});
  const GltfExportStats stats = write_gltf_binary(file, rig.skeleton, rig.body->levels[level], &walk.clip);
  const Glb glb = read_glb(file);
  ASSERT_FALSE(glb.json.is_null());
  const auto& prim = glb.json.at("meshes").at(0).at("primitives").at(0);
  const auto& attributes = prim.at("attributes");
  const std::vector<float> texcoords = glb.accessor<float>(attributes.at("TEXCOORD_0"));
  EXPECT_EQ(texcoords.size(), 2 * stats.written_vertices);
  for (const float t : texcoords) ASSERT_TRUE(t >= 0.0f && t <= 1.0f) << "MakeHuman's texture space is the unit square";
  const auto& joints_accessor = glb.json.at("accessors").at(attributes.at("JOINTS_0").get<int>());
  EXPECT_EQ(joints_accessor.at("componentType"), 5123) << "JOINTS_0 as unsigned short";
  const std::vector<float> weights = glb.accessor<float>(attributes.at("WEIGHTS_0"));
  const std::vector<std::uint16_t> joints = glb.accessor<std::uint16_t>(attributes.at("JOINTS_0"));
  ASSERT_EQ(weights.size(), 4 * stats.written_vertices);
  std::size_t one = 0, two = 0;
  for (std::size_t v = 0; v < weights.size() / 4; ++v) {
    double sum = 0.0;
    int used = 0;
    for (int k = 0; k < 4; ++k) {
      sum += weights[4 * v + k];
      if (weights[4 * v + k] == 0.0f) {
        EXPECT_EQ(joints[4 * v + k], 0) << "vertex " << v << " slot " << k;
      }
      used += weights[4 * v + k] > 0.0f;
      EXPECT_LT(joints[4 * v + k], rig.skeleton.joint_count());
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << "vertex " << v;
    one += used == 1, two += used == 2;
  }
  EXPECT_GT(one, 0u);
  EXPECT_GT(two, 0u);
  // POSITION's min/max enclose exactly its values; the animation inputs carry min/max too.
  const auto& position = glb.json.at("accessors").at(attributes.at("POSITION").get<int>());
  const std::vector<float> p = glb.accessor<float>(attributes.at("POSITION"));
  for (int c = 0; c < 3; ++c) {
    float lo = p[c], hi = p[c];
    for (std::size_t i = c; i < p.size(); i += 3) lo = std::min(lo, p[i]), hi = std::max(hi, p[i]);
    EXPECT_EQ(position.at("min").at(c).get<float>(), lo);
    EXPECT_EQ(position.at("max").at(c).get<float>(), hi);
  }
  const auto& animation = glb.json.at("animations").at(0);
  EXPECT_EQ(animation.at("channels").size(), rig.skeleton.joint_count() + 1) << "a rotation per joint + the root's translation";
  for (const auto& sampler : animation.at("samplers")) {
    EXPECT_EQ(sampler.at("interpolation"), "LINEAR");
    const auto& input = glb.json.at("accessors").at(sampler.at("input").get<int>());
    EXPECT_EQ(input.at("min").at(0).get<float>(), 0.0f);
    EXPECT_EQ(input.at("max").at(0).get<float>(), 0.5f);
  }
  // Skin: IBM_j = translate(-c_j).
  const auto& skin = glb.json.at("skins").at(0);
  const std::vector<float> ibm = glb.accessor<float>(skin.at("inverseBindMatrices"));
  ASSERT_EQ(ibm.size(), 16 * rig.skeleton.joint_count());
  for (std::size_t k = 0; k < rig.skeleton.joint_count(); ++k) {
    const int node = skin.at("joints").at(k);
    const int j = rig.skeleton.find_joint(glb.json.at("nodes").at(node).at("name").get<std::string>());
    ASSERT_GE(j, 0);
    EXPECT_EQ(ibm[16 * k + 12], -rig.skeleton.centers[j].x);
    EXPECT_EQ(ibm[16 * k + 13], -rig.skeleton.centers[j].y);
    EXPECT_EQ(ibm[16 * k + 0], 1.0f);
  }
}

INSTANTIATE_TEST_SUITE_P(AllLevels, ExportLevels, ::testing::Values(0, 1, 2));

// The imported rig posed at t = 0.5 s (a key of a 30 fps bake) against the engine's skinned walker after 15 frames:
// the whole chain export -> import -> clip sampling -> FK -> skinning must land where the walk generator put it.
TEST(ExportPose, ImportedClipMatchesTheEngineWalkerAtHalfASecond) {
  constexpr int kLevel = 2;
  const Rig& rig = shipped_rig();
  const fs::path file = scratch_dir() / "pose.glb";
  const BakedWalk walk = bake_walk(rig, {1.0f, 30.0f, 3});
  write_gltf_binary(file, rig.skeleton, rig.body->levels[kLevel], &walk.clip);
  ImportedBody imported = load_gltf(file);

  Rig back;
  back.name = "imported";
  back.skeleton = imported.skeleton;
  back.clips = imported.clips;
  back.body = std::make_shared<const Body>(Body{{BodyLevel{imported.mesh, imported.skin}}});
  Crowd replay(std::move(back));
  spawn_clip_walker(replay, glm::vec3(0.0f), 0.0f, 0.5f, 1.0f, 0);
  set_detail_level(replay, DetailLevel::mesh(0));
  Profiler profiler(1, false);
  step(replay, 0.0f, profiler);

  const EngineWalker engine = engine_walker(kLevel, 3, 15);
  EXPECT_LT(glm::length(engine.start_position - walk.start_position), 1e-6f);

  // Joint positions: F(j) translation, components 9..11 of the world matrix.
  WalkerLanes a = replay.lanes(), b = engine.scene->lanes();
  double worst_joint = 0.0, moved = 0.0;
  for (std::size_t j = 0; j < imported.skeleton.joint_count(); ++j) {
    const int rj = rig.skeleton.find_joint(imported.skeleton.joint_names[j]);
    ASSERT_GE(rj, 0);
    auto at = [](const WalkerLanes& l, std::size_t joint) {
      const float* m = l.world + joint * kAffineFloats * l.stride;
      return glm::vec3(m[9 * l.stride], m[10 * l.stride], m[11 * l.stride]);
    };
    const glm::vec3 expected = relative_to_start(engine, placement_of(b, 0).point(at(b, rj)));
    worst_joint = std::max(worst_joint, double(glm::length(at(a, j) - expected)));
    moved = std::max(moved, double(glm::length(expected - rig.skeleton.centers[rj])));
  }
  EXPECT_LT(worst_joint, 1e-5) << "joint world positions, m";
  EXPECT_GT(moved, 0.3) << "half a second of walking moves the joints well away from the rest pose";

  // Skinned vertices, both in mesh order (each scene's layout maps back to the mesh vertex).
  // The imported mesh has the exported one's vertices plus its UV seams' splits, each at its source's position.
  const SkinnedCrowd& sa = current_skinned(replay);
  const SkinnedCrowd& sb = current_skinned(*engine.scene);
  ASSERT_EQ(sa.vertex_count, imported.mesh.vertex_count());
  ASSERT_EQ(sb.vertex_count, rig.body->levels[kLevel].mesh.vertex_count());
  const std::vector<std::uint32_t> source = source_vertices(imported.mesh, rig.body->levels[kLevel].mesh);
  std::vector<glm::vec3> va(sa.vertex_count), vb(sb.vertex_count);
  for (std::size_t i = 0; i < sa.vertex_count; ++i) va[current_layout(replay).original[i]] = sa.position(0, i);
  for (std::size_t i = 0; i < sb.vertex_count; ++i)
    vb[current_layout(*engine.scene).original[i]] = relative_to_start(engine, sb.position(0, i));
  double worst_vertex = 0.0;
  for (std::size_t w = 0; w < va.size(); ++w)
    worst_vertex = std::max(worst_vertex, double(glm::length(va[w] - vb[source[w]])));
  EXPECT_LT(worst_vertex, 1e-5) << "skinned vertex positions, m";
}

TEST(ExportWalk, StartsAtTheOriginFacingForwardAndWalksForward) {
  const BakedWalk walk = bake_walk(shipped_rig(), {2.0f, 30.0f, 1});
  const TranslationTrack& root = walk.clip.translations.at(0);
  ASSERT_EQ(root.times.size(), 61u);
  EXPECT_EQ(root.times.back(), 2.0f);
  // t' + c_root is the root's position: at the start it sits above the origin (x = z = 0 up to the pelvis' sway
  // and the root's own rest offset), and two seconds of walking take it 1.5-3.5 m along +Z.
  const glm::vec3 c = shipped_rig().skeleton.centers[0];
  const glm::vec3 start = root.values.front() + c, end = root.values.back() + c;
  EXPECT_LT(std::abs(start.x), 0.1f);
  EXPECT_LT(std::abs(start.z - c.z), 0.1f);
  EXPECT_GT(end.z - start.z, 1.5f);
  EXPECT_LT(end.z - start.z, 3.5f);
  for (const RotationTrack& track : walk.clip.rotations)
    for (std::size_t k = 0; k < track.values.size(); ++k) {
      EXPECT_NEAR(glm::length(track.values[k]), 1.0f, 1e-5f);
      if (k) {
        EXPECT_GE(glm::dot(track.values[k], track.values[k - 1]), 0.0f) << "keys in one hemisphere";
      }
    }
  // A length that is not a whole number of frames still ends exactly on it.
  const BakedWalk odd = bake_walk(shipped_rig(), {0.51f, 30.0f, 1});
  EXPECT_EQ(odd.clip.translations[0].times.size(), 17u);
  EXPECT_EQ(odd.clip.duration, 0.51f);
  EXPECT_THROW(bake_walk(shipped_rig(), {0.0f, 30.0f, 1}), std::invalid_argument);
}

std::string export_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const ExportError& e) {
    return e.what();
  }
  return "<no ExportError>";
}

TEST(ExportErrors, UnwritablePathsAreOneLineErrorsAndLeaveNoFile) {
  const Rig& rig = shipped_rig();
  const BodyLevel& body = rig.body->levels[2];
  const fs::path dir = scratch_dir() / "errors";
  fs::create_directories(dir);
  const fs::path not_a_dir = dir / "plain_file";
  std::ofstream(not_a_dir) << "x";
  for (const fs::path& bad : {not_a_dir / "walker.glb", dir / "missing_dir" / "walker.glb", dir / "sub" / ""}) {
    const std::string message = export_error([&] { write_gltf_binary(bad, rig.skeleton, body, nullptr); });
    EXPECT_EQ(message.rfind(bad.string() + ": ", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_FALSE(fs::exists(bad));
  }
  // A directory is not replaced.
  fs::create_directories(dir / "a_directory");
  EXPECT_NE(export_error([&] { write_gltf_binary(dir / "a_directory", rig.skeleton, body, nullptr); }).find("is a directory"),
            std::string::npos);
  EXPECT_TRUE(fs::is_directory(dir / "a_directory"));
  fs::remove(dir / "a_directory");
  // A binding that does not fit the mesh: an error before anything is written, nothing left behind.
  BodyLevel broken = body;
  broken.binding.joints.pop_back();
  broken.binding.weights.pop_back();
  const fs::path target = dir / "broken.glb";
  EXPECT_NE(export_error([&] { write_gltf_binary(target, rig.skeleton, broken, nullptr); }).find("binding"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(target));
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u) << "only plain_file: no temporary file survives a failure";

  // An existing file is replaced whole.
  std::ofstream(target) << "old contents";
  write_gltf_binary(target, rig.skeleton, body, nullptr);
  EXPECT_NO_THROW(load_gltf(target));
}

TEST(ExportErrors, TruncatedFileIsAOneLineLoadErrorNamingIt) {
  const Rig& rig = shipped_rig();
  const fs::path good = scratch_dir() / "whole.glb";
  write_gltf_binary(good, rig.skeleton, rig.body->levels[2], nullptr);
  const fs::path cut = scratch_dir() / "truncated.glb";
  fs::copy_file(good, cut, fs::copy_options::overwrite_existing);
  fs::resize_file(cut, fs::file_size(good) / 2);
  try {
    load_gltf(cut);
    ADD_FAILURE() << "a truncated file loaded";
  } catch (const LoadError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(cut.string()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

using test::CliResult;
CliResult run_cli(const std::string& args) { return test::run_strata(args); }

TEST(StrataExport, WritesAGlbTheImporterReads) {
  const fs::path file = scratch_dir() / "cli.glb";
  const CliResult r = run_cli("export --format gltf --level 1 --seconds 0.5 --out " + file.string());
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("8923 vertices"), std::string::npos) << r.out;
  const ImportedBody body = load_gltf(file);
  EXPECT_GE(body.mesh.vertex_count(), shipped_rig().body->levels[1].mesh.vertex_count());  // plus UV seam splits
  EXPECT_LT(body.mesh.vertex_count(), shipped_rig().body->levels[1].mesh.vertex_count() * 23 / 20);
  ASSERT_EQ(body.clips.size(), 1u);
  EXPECT_NEAR(body.clips[0].duration, 0.5f, 1e-5f);

  const CliResult format = run_cli("export --format fbx --out " + (scratch_dir() / "x.fbx").string());
  EXPECT_NE(format.status, 0);
  EXPECT_NE(format.out.find("fbx"), std::string::npos) << format.out;
  const fs::path bad = scratch_dir() / "no_such_dir" / "w.glb";
  const CliResult unwritable = run_cli("export --level 2 --seconds 0.1 --out " + bad.string());
  EXPECT_EQ(unwritable.status, 1) << unwritable.out;
  EXPECT_NE(unwritable.out.find(bad.string()), std::string::npos) << unwritable.out;
  EXPECT_FALSE(fs::exists(bad));
}

}  // namespace
}  // namespace strata
