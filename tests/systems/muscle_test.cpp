// The muscle layer: the muscle file loader (and its errors), the binding's invariants, the force model (zero at
// rest, growing as the biceps shortens, relaxing as it lengthens, finite when a segment collapses), run-time
// force edits that touch only the edited muscle's vertices, and the muscle system's thread-count determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "io/load_error.h"
#include "io/muscle_file.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "scene/crowd.h"
#include "systems/muscle.h"
#include "systems/skin.h"
#include "systems/skin_kernel.h"
#include "systems/subdiv.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

const Skeleton& skeleton() {
  static const Skeleton s = load_default_humanoid().skeleton;
  return s;
}

Rig default_rig() {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  return rig;
}

// A one-line muscle file around one muscle entry (JSON text), for the error cases.
std::string file_with(const std::string& muscle) {
  return R"({"format": "strata-muscles", "version": 1, "muscles": [)" + muscle + "]}";
}

const std::string kBiceps = R"({"name": "m", "origin": {"joint": "l_shoulder", "offset": [0, -0.03, 0.02]},
  "insertion": {"joint": "l_elbow", "offset": [0, -0.03, 0.02]}, "outward": [0, 0, 1], "control_points": 3,
  "parts": ["lShldr"], "radius": 0.07, "forces": [[], [[0, 1, 0, 0.05]], []]})";

std::string error_of(const std::string& text) {
  try {
    parse_muscles(text, "bad.json", skeleton());
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}

TEST(MuscleFile, TheShippedSetHasTwelveMirroredMuscles) {
  const MuscleSet set = default_muscles(skeleton());
  ASSERT_EQ(set.lines.size(), 12u);
  std::uint32_t points = 0;
  for (const ActionLine& line : set.lines) {
    EXPECT_EQ(line.first_point, points);
    points += line.point_count;
    EXPECT_EQ(line.forces.size(), line.point_count);
    EXPECT_GT(glm::length(line.insertion_rest - line.origin_rest), 0.1f) << line.name;
  }
  EXPECT_EQ(set.point_count, points);
  ASSERT_EQ(set.rest_length.size(), points);
  for (const char* name : {"biceps", "triceps", "quadriceps", "hamstrings", "gastrocnemius", "tibialis_anterior"}) {
    const int l = set.find(std::string("l_") + name), r = set.find(std::string("r_") + name);
    ASSERT_GE(l, 0) << name;
    ASSERT_GE(r, 0) << name;
    const ActionLine &a = set.lines[l], &b = set.lines[r];
    // The right side is the left one through the midplane (the skeleton is symmetric to 0.6 cm).
    EXPECT_NEAR(a.origin_rest.x, -b.origin_rest.x, 1e-6f);
    EXPECT_NEAR(a.insertion_rest.y, b.insertion_rest.y, 1e-6f);
    for (auto [ja, jb] : {std::pair{a.origin_joint, b.origin_joint}, std::pair{a.insertion_joint, b.insertion_joint}}) {
      const std::string &left = skeleton().joint_names[ja], &right = skeleton().joint_names[jb];
      EXPECT_EQ(left.starts_with("l_") ? "r_" + left.substr(2) : left, right) << name;
    }
    EXPECT_EQ(b.parts[0][0], 'r');
    for (std::size_t k = 0; k < a.forces.size(); ++k)
      for (std::size_t f = 0; f < a.forces[k].size(); ++f) {
        EXPECT_EQ(a.forces[k][f].direction.x, -b.forces[k][f].direction.x);
        EXPECT_EQ(a.forces[k][f].magnitude, b.forces[k][f].magnitude);
      }
  }
}

TEST(MuscleFile, BadInputNamesTheFileAndTheElement) {
  ASSERT_EQ(error_of(file_with(kBiceps)), "");
  struct Case {
    std::string text, expect;
  };
  auto with = [](std::string from, const std::string& to) {
    std::string s = kBiceps;
    s.replace(s.find(from), from.size(), to);
    return file_with(s);
  };
  const Case cases[] = {
      {"{\"format\": \"strata-muscles\",\n \"version\": 1,,}", "bad.json: invalid JSON"},
      {"{\"format\": \"strata-muscles\",\n \"version\": 1,,}", "line 2"},
      {R"({"format": "strata-muscles", "version": 2, "muscles": []})", "bad.json: version: expected 1"},
      {file_with(""), "bad.json: muscles: expected a non-empty array"},
      {with("\"l_elbow\"", "\"l_elbw\""), "bad.json: muscles[0] (m).insertion.joint: no joint 'l_elbw'"},
      {with("\"control_points\": 3", "\"control_points\": 4"), "muscles[0] (m).forces: expected one list"},
      {with("\"control_points\": 3", "\"control_points\": 1"), "muscles[0] (m).control_points: must lie in"},
      {with("[0, 1, 0, 0.05]", "[0, 0, 0, 0.05]"), "muscles[0] (m).forces[1][0]: zero direction"},
      {with("[0, 1, 0, 0.05]", "[0, 1, 0]"), "muscles[0] (m).forces[1][0]: expected [dx, dy, dz, magnitude]"},
      {with("\"outward\": [0, 0, 1]", "\"outward\": [0, 1, 0]"), "muscles[0] (m).outward: must point away"},
      {with("\"radius\": 0.07", "\"radius\": -1"), "muscles[0] (m).radius: must lie in"},
      {with("\"radius\": 0.07", "\"radius\": 0.07, \"colour\": 1"), "muscles[0] (m).colour: unknown key"},
      {with("\"parts\": [\"lShldr\"]", "\"parts\": []"), "muscles[0] (m).parts: expected a non-empty array"},
      {with("{\"joint\": \"l_elbow\", \"offset\": [0, -0.03, 0.02]}",
            "{\"joint\": \"l_shoulder\", \"offset\": [0, -0.03, 0.02]}"),
       "muscles[0] (m).insertion: less than 1 mm from the origin"},
      {with("[0, -0.03, 0.02]}", "[0, -0.03, 1e400]}"), "bad.json: invalid JSON"},
      {with("[0, -0.03, 0.02]}", "[0, -0.03, 7]}"), "origin.offset: further than 1 m"},
      {file_with(kBiceps + ", " + kBiceps), "muscles[1] (m).name: duplicate muscle name"},
      {file_with(kBiceps + R"(, {"name": "n", "mirror_of": "x"})"), "muscles[1] (n).mirror_of: no earlier muscle 'x'"},
  };
  for (const Case& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expect), std::string::npos) << "got: " << message << "\nexpected: " << c.expect;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
  }
  EXPECT_THROW(load_muscle_file("/nonexistent/muscles.json", skeleton()), LoadError);
}

TEST(MuscleFile, OverridesScaleNamedMusclesAndRejectUnknownOnes) {
  const MuscleSet set = default_muscles(skeleton());
  const MuscleGains g =
      parse_muscle_overrides(R"({"gain": 2, "muscles": {"l_biceps": 1.5}})", "o.json", set);
  EXPECT_FLOAT_EQ(g.of(set.find("l_biceps")), 3.0f);
  EXPECT_FLOAT_EQ(g.of(set.find("r_biceps")), 2.0f);
  auto error = [&](const char* text) {
    try {
      parse_muscle_overrides(text, "o.json", set);
    } catch (const LoadError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error(R"({"muscles": {"l_bicep": 1}})"), "o.json: muscles.l_bicep: no such muscle in data/muscles.json");
  EXPECT_NE(error(R"({"gain": -1})").find("o.json: gain: gain must lie in [0, 100]"), std::string::npos);
  EXPECT_NE(error(R"({"gains": 1})").find("o.json: gains: unknown key"), std::string::npos);
}

TEST(MuscleBinding, WeightsAndSharesSumToOneWithinTheMusclesReachAndParts) {
  const Rig rig = default_rig();
  const MuscleSet& set = rig.muscles->set;
  for (std::size_t level = 0; level < rig.body->levels.size(); ++level) {
    const Mesh& mesh = rig.body->levels[level].mesh;
    const MuscleBinding& b = rig.muscles->levels[level];
    ASSERT_GT(b.size(), mesh.vertex_count() / 10) << "a good part of arms and legs binds";
    std::set<std::uint16_t> lines;
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (i > 0) {
        ASSERT_LT(b.vertex[i - 1], b.vertex[i]);
      }
      const ActionLine& line = set.lines[b.line[i]];
      lines.insert(b.line[i]);
      const std::string& part = mesh.part_names[mesh.part[b.vertex[i]]];
      ASSERT_NE(std::find(line.parts.begin(), line.parts.end(), part), line.parts.end()) << part;
      float sum = 0.0f;
      for (int s = 0; s < kMusclePointsPerVertex; ++s) {
        sum += b.weight[i][s];
        ASSERT_GE(b.point[i][s], line.first_point);
        ASSERT_LT(b.point[i][s], line.first_point + line.point_count);
        const auto& vectors = line.forces[b.point[i][s] - line.first_point];
        float shares = 0.0f;
        for (std::size_t a = 0; a < vectors.size(); ++a) shares += b.share[b.share_first[i][s] + a];
        ASSERT_NEAR(shares, 1.0f, 1e-5f);
      }
      ASSERT_NEAR(sum, 1.0f, 1e-5f);
      ASSERT_GE(b.falloff[i], 0.0f);
      ASSERT_LE(b.falloff[i], 1.0f);
    }
    EXPECT_EQ(lines.size(), set.lines.size()) << "every muscle binds some skin at level " << level;
  }
}

// A vertex in front of the biceps line takes most of its share from the outward (+y) force vector, one behind
// it from the inward (-y) one: the share follows the angle.
TEST(MuscleBinding, SharesFollowTheAngleToTheForceVector) {
  const MuscleSet set = parse_muscles(file_with(kBiceps), "one.json", skeleton());
  const ActionLine& line = set.lines[0];
  Mesh mesh;
  mesh.part_names = {"lShldr"};
  const glm::vec3 mid = 0.5f * (line.origin_rest + line.insertion_rest);
  mesh.positions = {mid + glm::vec3(0, 0, 0.04f), mid + glm::vec3(0, 0, -0.04f)};
  mesh.part = {0, 0};
  MuscleSet two = set;
  two.lines[0].forces[1] = {{{0, 1, 0}, 0.05f}, {{0, -1, 0}, 0.0f}};
  const MuscleBinding b = bind_muscles(mesh, two);
  ASSERT_EQ(b.size(), 2u);
  for (int s = 0; s < kMusclePointsPerVertex; ++s)
    if (b.point[0][s] == 1) {
      EXPECT_GT(b.share[b.share_first[0][s]], 0.9f);      // front vertex: +y
      EXPECT_LT(b.share[b.share_first[1][s]], 0.1f);      // back vertex: hardly +y
    }
  const auto c = muscle_coefficients(two, b);
  float front = 0.0f, back = 0.0f;
  for (int s = 0; s < kMusclePointsPerVertex; ++s) front += c[0][s], back += c[1][s];
  EXPECT_GT(front, 5.0f * back);
}

// One walker of the default rig, arm posed by hand, run through fk -> muscle -> skin.
struct Posed {
  Crowd scene{default_rig()};
  SkinnedCrowd out;
  explicit Posed(DetailLevel level = DetailLevel::mesh(0)) {
    CrowdConfig config;
    config.walkers = 1;
    config.motion = MotionSource::Clip;
    config.clip = kRestPose;
    config.heading_jitter = 0.0f;
    spawn_crowd(scene, config);
    set_detail_level(scene, level);
  }
  void pose(float shoulder_deg, float elbow_deg) {
    const WalkerLanes l = scene.lanes();
    const auto rotate = [&](const char* joint, float deg) {
      const glm::quat q = glm::angleAxis(-deg * 3.14159265f / 180.0f, glm::vec3(1, 0, 0));
      const float v[4] = {q.x, q.y, q.z, q.w};
      const int j = scene.rig().skeleton.find_joint(joint);
      for (int c = 0; c < 4; ++c) l.at(l.local_rotation, std::size_t(j) * 4 + c)[0] = v[c];
    };
    rotate("l_shoulder", shoulder_deg);
    rotate("l_elbow", elbow_deg);
  }
  const SkinnedCrowd& run() {
    EXPECT_TRUE(make_fk_job(scene.rig().skeleton, scene.table(initial_slot(scene))).run());
    EXPECT_TRUE(make_muscle_job(scene.rig().muscles->set, scene.table(initial_slot(scene))).run());
    EXPECT_TRUE(make_skin_job(current_layout(scene), scene.table(initial_slot(scene)), out).run());
    return out;
  }
  float force(const char* muscle) {
    const ActionLine& line = scene.rig().muscles->set.lines[scene.rig().muscles->set.find(muscle)];
    const WalkerLanes l = scene.lanes();
    return l.at(l.muscle_force, line.first_point + line.point_count / 2)[0];
  }
};

TEST(MuscleSystem, RestPoseGivesZeroForceAndZeroDisplacementOnEveryLevel) {
  for (int level = 0; level < 3; ++level) {
    Posed p(DetailLevel::mesh(level));
    p.pose(0.0f, 0.0f);
    const SkinnedCrowd with = p.run();
    const WalkerLanes l = p.scene.lanes();
    for (std::size_t k = 0; k < l.muscle_points; ++k) ASSERT_EQ(l.at(l.muscle_force, k)[0], 0.0f);
    set_muscles_enabled(p.scene, false);
    const SkinnedCrowd without = p.run();
    // Different layouts (muscle groups are split out), so compare through mesh vertex order.
    std::vector<glm::vec3> a(with.vertex_count), b(with.vertex_count);
    set_muscles_enabled(p.scene, true);
    for (std::size_t i = 0; i < with.vertex_count; ++i) a[current_layout(p.scene).original[i]] = with.position(0, i);
    set_muscles_enabled(p.scene, false);
    for (std::size_t i = 0; i < with.vertex_count; ++i) b[current_layout(p.scene).original[i]] = without.position(0, i);
    float worst = 0.0f;
    for (std::size_t v = 0; v < a.size(); ++v) worst = std::max(worst, glm::length(a[v] - b[v]));
    EXPECT_LT(worst, 1e-6f) << "level " << level;
  }
}

// The bulge over the biceps grows with every step of elbow flexion (the paper's Figure 6) and falls back the
// same way on extension; the triceps, lengthened, relaxes (negative force).
TEST(MuscleSystem, BicepsBulgesMonotonicallyWithFlexionAndRelaxesOnExtension) {
  Posed p;
  const MuscleSet& set = p.scene.rig().muscles->set;
  const MuscleBinding& binding = p.scene.rig().muscles->levels[0];
  const int biceps = set.find("l_biceps");
  auto bulge = [&](float elbow) {
    p.pose(90.0f, elbow);
    MuscleGains off;
    off.global = 0.0f;
    set_muscle_gains(p.scene, off);
    const SkinnedCrowd lbs = p.run();
    set_muscle_gains(p.scene, {});
    const SkinnedCrowd& with = p.run();
    float best = -1.0f;
    for (std::size_t i = 0; i < with.vertex_count; ++i) {
      const std::uint32_t b = current_layout(p.scene).muscle_slot[i];
      if (b != SkinLayout::kNoMuscle && binding.line[b] == biceps)
        best = std::max(best, glm::dot(with.position(0, i) - lbs.position(0, i), with.normal(0, i)));
    }
    return best;
  };
  std::vector<float> up;
  for (float a : {0.0f, 30.0f, 60.0f, 90.0f, 120.0f}) up.push_back(bulge(a));
  for (std::size_t i = 1; i < up.size(); ++i) EXPECT_GT(up[i], up[i - 1] + 1e-4f) << "step " << i;
  EXPECT_GT(up.back(), 0.005f) << "a visible bulge at 120 degrees";
  EXPECT_LT(up.back(), 0.03f) << "but not a balloon";
  EXPECT_GT(p.force("l_biceps"), 0.1f);
  EXPECT_LT(p.force("l_triceps"), 0.0f) << "the triceps lengthens on flexion";
  std::vector<float> down;
  for (float a : {120.0f, 90.0f, 60.0f, 30.0f, 0.0f}) down.push_back(bulge(a));
  for (std::size_t i = 1; i < down.size(); ++i) EXPECT_LT(down[i], down[i - 1]);
  EXPECT_NEAR(down.back(), up.front(), 1e-7f) << "no memory: the same pose gives the same shape";
}

// Origin and insertion pulled onto one point (zero-length segments), and a collapsed (all-zero) skinning
// matrix: the force clamps to 1 / min_length_ratio - 1 and every output is finite.
TEST(MuscleSystem, ZeroLengthSegmentsClampWithoutInfOrNan) {
  Rig rig = default_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.walkers = 2;
  config.motion = MotionSource::Clip;
  config.clip = kRestPose;
  spawn_crowd(scene, config);
  const MuscleSet& set = rig.muscles->set;
  const ActionLine& biceps = set.lines[set.find("l_biceps")];
  const WalkerLanes l = scene.lanes();
  ASSERT_TRUE(make_fk_job(rig.skeleton, scene.table(initial_slot(scene))).run());
  // Walker 0: the insertion joint's matrix moves the insertion exactly onto the origin.
  const glm::vec3 shift = biceps.origin_rest - biceps.insertion_rest;
  for (int c = 0; c < 3; ++c)
    l.at(l.skinning, std::size_t(biceps.insertion_joint) * kAffineFloats + 9 + c)[0] += shift[c];
  // Walker 1: every matrix collapsed to zero.
  for (std::size_t c = 0; c < std::size_t(l.joints) * kAffineFloats; ++c) l.at(l.skinning, c)[1] = 0.0f;
  ASSERT_TRUE(make_muscle_job(set, scene.table(initial_slot(scene))).run());
  for (std::size_t w = 0; w < 2; ++w)
    for (std::size_t k = 0; k < l.muscle_points; ++k) {
      ASSERT_TRUE(std::isfinite(l.at(l.muscle_force, k)[w]));
      ASSERT_TRUE(std::isfinite(l.at(l.muscle_length, k)[w]));
      for (int c = 0; c < 6; ++c) ASSERT_TRUE(std::isfinite(l.at(l.muscle_frame, k * 6 + c)[w]));
      ASSERT_LE(l.at(l.muscle_force, k)[w], 1.0f / set.min_length_ratio - 1.0f);
    }
  EXPECT_FLOAT_EQ(l.at(l.muscle_force, biceps.first_point)[0], 1.0f / set.min_length_ratio - 1.0f);
  EXPECT_FLOAT_EQ(l.at(l.muscle_force, biceps.first_point)[1], 1.0f / set.min_length_ratio - 1.0f);
  set_detail_level(scene, DetailLevel::mesh(2));
  SkinnedCrowd out;
  ASSERT_TRUE(make_skin_job(current_layout(scene), scene.table(initial_slot(scene)), out).run());
  for (std::size_t w = 0; w < 2; ++w)
    for (std::size_t v = 0; v < out.vertex_count; ++v) {
      const glm::vec3 p = out.position(w, v), n = out.normal(w, v);
      ASSERT_TRUE(std::isfinite(p.x + p.y + p.z + n.x + n.y + n.z));
    }
}

// Editing one muscle's force moves exactly the vertices bound to it (with a non-zero coefficient), nothing else.
TEST(MuscleSystem, EditingOneMuscleChangesOnlyItsVertices) {
  Posed p(DetailLevel::mesh(1));
  p.pose(60.0f, 100.0f);
  const SkinnedCrowd before = p.run();
  const MuscleSet& set = p.scene.rig().muscles->set;
  const int biceps = set.find("l_biceps");
  MuscleGains gains;
  gains.line.assign(set.lines.size(), 1.0f);
  gains.line[biceps] = 2.0f;
  set_muscle_gains(p.scene, gains);
  const SkinnedCrowd& after = p.run();
  const MuscleBinding& binding = p.scene.rig().muscles->levels[1];
  std::size_t moved = 0;
  for (std::size_t i = 0; i < after.vertex_count; ++i) {
    const std::uint32_t b = current_layout(p.scene).muscle_slot[i];
    const bool mine = b != SkinLayout::kNoMuscle && binding.line[b] == biceps;
    const bool changed = after.position(0, i) != before.position(0, i);
    if (!mine) {
      ASSERT_FALSE(changed) << "vertex " << i << " is not the biceps'";
    }
    moved += changed;
  }
  EXPECT_GT(moved, 50u);
}

// validate() rejects each missing or mismatched input, and run() then writes nothing.
TEST(MuscleJob, JobValidity) {
  Crowd scene(default_rig());
  CrowdConfig config;
  config.walkers = 3;
  config.motion = MotionSource::Clip;
  config.clip = kRestPose;
  spawn_crowd(scene, config);
  SoaTable& table = scene.table(initial_slot(scene));
  ASSERT_TRUE(make_fk_job(scene.rig().skeleton, table).run());
  const MuscleSet& set = scene.rig().muscles->set;
  const MuscleJob good = make_muscle_job(set, table);
  const std::size_t outputs[] = {kWalkerMusclePoint, kWalkerMuscleFrame, kWalkerMuscleLength, kWalkerMuscleForce};
  for (std::size_t f : outputs) test::fill_sentinel(table, f);
  auto untouched = [&] {
    for (std::size_t f : outputs)
      if (!test::holds_sentinel(table, f)) return false;
    return true;
  };
  using namespace test;
  MuscleJob j = good;
  j.set = nullptr;
  expect_refused(j, "no muscle set", untouched);
  MuscleSet short_rest = set;
  short_rest.rest_length.pop_back();
  j = good, j.set = &short_rest;
  expect_refused(j, "a rest length missing", untouched);
  MuscleSet far_joint = set;
  far_joint.lines[0].insertion_joint = static_cast<std::int32_t>(scene.rig().skeleton.joint_count());
  j = good, j.set = &far_joint;
  expect_refused(j, "a line on a joint the rig lacks", untouched);
  MuscleSet past_end = set;
  past_end.lines.back().first_point = set.point_count - 1;
  j = good, j.set = &past_end;
  expect_refused(j, "a line's points past the columns", untouched);
  j = good, j.skinning = without_base(good.skinning);
  expect_refused(j, "no skinning matrices", untouched);
  j = good, j.skinning = with_components(good.skinning, good.skinning.components - 1);
  expect_refused(j, "skinning not whole matrices", untouched);
  j = good, j.point = with_components(good.point, good.point.components - 3);
  expect_refused(j, "point output one point short", untouched);
  j = good, j.frame = with_count(good.frame, 2);
  expect_refused(j, "frame output of fewer walkers", untouched);
  j = good, j.length = with_stride(good.length, 1);
  expect_refused(j, "length stride below the walker count", untouched);
  j = good, j.force = without_base(good.force);
  expect_refused(j, "no force output", untouched);
  j = good, j.length = good.force;
  expect_refused(j, "length and force alias", untouched);
  EXPECT_FALSE(good.run_walker(3)) << "walker out of range";
  EXPECT_TRUE(untouched());

  EXPECT_TRUE(good.validate());
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(test::holds_sentinel(table, kWalkerMuscleForce));
}

TEST(MuscleSystem, SameBytesForOneAndTwoThreads) {
  std::vector<float> result[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Crowd scene(default_rig());
    CrowdConfig config;
    config.walkers = 150;  // several 64-walker chunks
    config.motion = MotionSource::Walk;
    spawn_crowd(scene, config);
    set_detail_level(scene, DetailLevel::none());
    Profiler profiler(8, false);
    for (int f = 0; f < 4; ++f) step(scene, 1.0f / 30.0f, profiler);
    const WalkerLanes l = scene.lanes();
    for (float* base : {l.muscle_point, l.muscle_frame, l.muscle_length, l.muscle_force})
      result[threads - 1].insert(result[threads - 1].end(), base, base + l.stride);
    for (std::size_t k = 0; k < l.muscle_points; ++k)
      result[threads - 1].insert(result[threads - 1].end(), l.at(l.muscle_force, k), l.at(l.muscle_force, k) + l.count);
  }
  EXPECT_TRUE(result[0] == result[1]);
  // The walk itself stretches and shortens the leg muscles.
  bool moved = false;
  for (float f : result[0]) moved = moved || std::fabs(f) > 1e-3f;
  EXPECT_TRUE(moved);
}

}  // namespace
}  // namespace strata

namespace strata {
namespace {

// At the subdivision levels the muscle layer displaces the cage before it is refined: nothing at rest, a bulge
// over the biceps once the elbow flexes.
TEST(MuscleSystem, DisplacesTheSubdivisionCageBeforeRefinement) {
  Posed p(DetailLevel::subdiv(1));
  ASSERT_EQ(p.scene.skin.level, DetailLevel::subdiv(1));
  ASSERT_TRUE(p.scene.rig().muscles->cage.has_value());
  ASSERT_GT(p.scene.rig().muscles->cage->size(), 100u);
  // The cage's displacement list built as the frame script builds it, refined with and without it.
  p.pose(90.0f, 120.0f);
  SoaTable& table = p.scene.table(initial_slot(p.scene));
  ASSERT_TRUE(make_fk_job(p.scene.rig().skeleton, table).run());
  ASSERT_TRUE(make_muscle_job(p.scene.rig().muscles->set, table).run());
  SkinnedCrowd plain, bulged;
  ASSERT_TRUE(make_subdiv_job(*p.scene.skin.subdiv.get(), table, plain, nullptr).run());
  const MuscleRig& m = *p.scene.rig().muscles;
  const MuscleDisplacementList list =
      make_muscle_displacement_list(p.scene.skin.subdiv.get()->cage_layout, *m.cage, muscle_coefficients(m.set, *m.cage));
  ASSERT_TRUE(make_subdiv_job(*p.scene.skin.subdiv.get(), table, bulged, &list).run());
  float largest = 0.0f;
  for (std::size_t v = 0; v < plain.vertex_count; ++v) {
    const glm::vec3 d = bulged.position(0, v) - plain.position(0, v);
    ASSERT_TRUE(std::isfinite(d.x + d.y + d.z));
    largest = std::max(largest, glm::dot(d, plain.normal(0, v)));
  }
  EXPECT_GT(largest, 0.004f) << "the refined surface bulges over the biceps";
  p.pose(0.0f, 0.0f);
  ASSERT_TRUE(make_fk_job(p.scene.rig().skeleton, table).run());
  ASSERT_TRUE(make_muscle_job(p.scene.rig().muscles->set, table).run());
  ASSERT_TRUE(make_subdiv_job(*p.scene.skin.subdiv.get(), table, plain, nullptr).run());
  ASSERT_TRUE(make_subdiv_job(*p.scene.skin.subdiv.get(), table, bulged, &list).run());
  for (std::size_t v = 0; v < plain.vertex_count; ++v) ASSERT_EQ(bulged.position(0, v), plain.position(0, v));
}

}  // namespace
}  // namespace strata
