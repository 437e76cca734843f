// Skin binding (the paper's three steps and bone heat), the reference skinning of equation 4, and the skin
// metrics, on small synthetic meshes built here: a capsule "arm" hanging from a shoulder, a unit cube, a sphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "components/walker.h"
#include "data/embedded.h"
#include "io/hanim_loader.h"
#include "io/load_error.h"
#include "rig/binding.h"
#include "rig/harmonic_weights.h"
#include "rig/body_generator.h"
#include "reference/skin_metrics.h"
#include "systems/fk.h"
#include "reference/fk_reference.h"
#include "reference/skin_reference.h"

namespace strata {
namespace {

constexpr float kShoulderY = 1.40f, kElbowY = 1.10f, kWristY = 0.85f, kTipY = 0.70f;
constexpr float kArmRadius = 0.04f;

Skeleton arm_skeleton() {
  Skeleton s;
  s.name = "arm";
  auto add = [&](const char* name, int parent, glm::vec3 c) {
    s.joint_names.emplace_back(name);
    s.source_joint_names.emplace_back(name);
    s.parents.push_back(parent);
    s.centers.push_back(c);
    s.limits.emplace_back();
    s.stiffness.emplace_back(1.0f);
  };
  add("HumanoidRoot", -1, {0.0f, 1.5f, 0.0f});
  add("l_shoulder", 0, {0.0f, kShoulderY, 0.0f});
  add("l_elbow", 1, {0.0f, kElbowY, 0.0f});
  add("l_wrist", 2, {0.0f, kWristY, 0.0f});
  s.sites.push_back({"l_hand_tip", 3, {0.0f, kTipY, 0.0f}});
  return s;
}

// Turns every triangle so that its normal points away from the nearest point of the segment [bottom, top] on the
// Y axis: outward for a capsule around that segment, whatever order the generator emitted.
void orient_outward(Mesh& m, float bottom, float top) {
  for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
    const glm::vec3 a = m.positions[m.triangles[t]], b = m.positions[m.triangles[t + 1]],
                    c = m.positions[m.triangles[t + 2]];
    const glm::vec3 g = (a + b + c) / 3.0f;
    const glm::vec3 axis_point(0.0f, std::clamp(g.y, bottom, top), 0.0f);
    if (glm::dot(glm::cross(b - a, c - a), g - axis_point) < 0.0f) std::swap(m.triangles[t + 1], m.triangles[t + 2]);
  }
}

// A watertight, single-index capsule along Y: cylinder rings every `spacing` metres between bottom and top, a
// hemisphere of `caps` latitude rings and a pole at each end.
Mesh capsule(float bottom, float top, float radius, int segments, float spacing, int caps) {
  Mesh m;
  m.name = "capsule";
  std::vector<std::pair<float, float>> rings;  // (y, ring radius), top to bottom
  for (int i = caps; i >= 1; --i) {
    const float phi = glm::half_pi<float>() * static_cast<float>(i) / static_cast<float>(caps + 1);
    rings.emplace_back(top + radius * std::sin(phi), radius * std::cos(phi));
  }
  const int side = static_cast<int>(std::lround((top - bottom) / spacing));
  for (int i = 0; i <= side; ++i)
    rings.emplace_back(side == 0 ? top : top - (top - bottom) * static_cast<float>(i) / static_cast<float>(side),
                       radius);
  for (int i = 1; i <= caps; ++i) {
    const float phi = glm::half_pi<float>() * static_cast<float>(i) / static_cast<float>(caps + 1);
    rings.emplace_back(bottom - radius * std::sin(phi), radius * std::cos(phi));
  }
  m.positions.emplace_back(0.0f, top + radius, 0.0f);  // top pole
  for (const auto& [y, r] : rings)
    for (int k = 0; k < segments; ++k) {
      const float th = glm::two_pi<float>() * static_cast<float>(k) / static_cast<float>(segments);
      m.positions.emplace_back(r * std::cos(th), y, r * std::sin(th));
    }
  m.positions.emplace_back(0.0f, bottom - radius, 0.0f);  // bottom pole
  const auto ring_vertex = [&](std::size_t ring, int k) {
    return static_cast<std::uint32_t>(1 + ring * segments + static_cast<std::size_t>(k % segments));
  };
  const std::uint32_t bottom_pole = static_cast<std::uint32_t>(m.positions.size() - 1);
  for (int k = 0; k < segments; ++k) {
    m.triangles.insert(m.triangles.end(), {0u, ring_vertex(0, k), ring_vertex(0, k + 1)});
    m.triangles.insert(m.triangles.end(),
                       {bottom_pole, ring_vertex(rings.size() - 1, k), ring_vertex(rings.size() - 1, k + 1)});
  }
  for (std::size_t i = 0; i + 1 < rings.size(); ++i)
    for (int k = 0; k < segments; ++k) {
      m.triangles.insert(m.triangles.end(), {ring_vertex(i, k), ring_vertex(i, k + 1), ring_vertex(i + 1, k)});
      m.triangles.insert(m.triangles.end(),
                         {ring_vertex(i, k + 1), ring_vertex(i + 1, k + 1), ring_vertex(i + 1, k)});
    }
  orient_outward(m, bottom, top);
  compute_normals(m);
  return m;
}

// The arm: upper arm above the elbow, forearm down to the wrist, hand below.
Mesh arm_mesh() {
  Mesh m = capsule(kTipY + 0.02f, kShoulderY, kArmRadius, 24, 0.01f, 4);
  m.part_names = {"lShldr", "lForeArm", "lHand"};
  for (const glm::vec3& p : m.positions) m.part.push_back(p.y > kElbowY ? 0 : p.y > kWristY ? 1 : 2);
  return m;
}

BindingTables arm_tables(std::string_view overrides = "") {
  return load_binding_tables(R"({"parts": {"lShldr": "l_shoulder", "lForeArm": "l_elbow", "lHand": "l_wrist"}})",
                             overrides, "arm_parts.json", "arm_overrides.json");
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
// A path rather than operator+ on a temporary string: GCC 12 warned (-Warray-bounds) inside libstdc++ on that form,
// a known false positive of its string inlining.
std::string repo_data(const char* name) {
  return (std::filesystem::path(STRATA_TEST_DATA) / ".." / ".." / "data" / name).string();
}

double weight_of(const SkinBinding& b, std::size_t v, int joint) {
  double w = 0.0;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (b.joints[v][k] == joint && b.weights[v][k] > 0.0f) w += b.weights[v][k];
  return w;
}

std::set<int> joints_of(const SkinBinding& b, std::size_t v) {
  std::set<int> s;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (b.weights[v][k] > 0.0f) s.insert(b.joints[v][k]);
  return s;
}

// The harmonic blend's soft threshold (rig/harmonic_weights.h min_weight) applied to exact weights.
std::vector<double> soft_threshold(std::vector<double> w) {
  const double c = HarmonicWeightOptions{}.min_weight;
  double sum = 0.0;
  for (double& x : w) sum += (x = std::max(x - c, 0.0));
  for (double& x : w) x /= sum;
  return w;
}

void expect_valid(const SkinBinding& b, std::size_t vertices, std::size_t joints) {
  ASSERT_EQ(b.vertex_count(), vertices);
  ASSERT_EQ(b.weights.size(), vertices);
  for (std::size_t v = 0; v < vertices; ++v) {
    double sum = 0.0;
    for (int k = 0; k < kMaxInfluences; ++k) {
      EXPECT_GE(b.weights[v][k], 0.0f);
      EXPECT_GE(b.joints[v][k], 0);
      EXPECT_LT(static_cast<std::size_t>(b.joints[v][k]), joints);
      sum += b.weights[v][k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << "vertex " << v;
    EXPECT_GE(b.influence_count(v), 1) << "vertex " << v << " is unbound";
    EXPECT_LE(b.influence_count(v), kMaxInfluences);
  }
}

glm::quat random_rotation(std::mt19937_64& rng, float max_angle) {
  std::normal_distribution<float> n(0.0f, 1.0f);
  std::uniform_real_distribution<float> u(-max_angle, max_angle);
  const glm::vec3 axis = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)) + glm::vec3(1e-6f));
  return glm::angleAxis(u(rng), axis);
}

// ---- Step 1 and invariants ----------------------------------------------------------------------------------------

TEST(Binding, ThreeStepInvariantsHoldAndRigidVerticesKeepTheirDistanceUnderRandomPoses) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables());
  expect_valid(b, mesh.vertex_count(), sk.joint_count());

  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<glm::quat> rot(sk.joint_count());
    for (glm::quat& q : rot) q = random_rotation(rng, 2.0f);
    const ReferencePose pose = fk_reference(sk, rot, glm::vec3(0.1f, -0.2f, 0.3f));
    const SkinnedVertices posed = skin_reference(mesh, b, pose.skinning);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      ASSERT_TRUE(std::isfinite(posed.positions[v].x + posed.positions[v].y + posed.positions[v].z));
      if (b.influence_count(v) != 1) continue;
      // A rigidly bound vertex rides its joint's frame: its distance to the joint centre cannot change.
      const int j = b.joints[v][0];
      EXPECT_NEAR(glm::length(posed.positions[v] - glm::vec3(pose.world[j][3])),
                  glm::length(mesh.positions[v] - sk.centers[j]), 2e-5f);
    }
  }
}

TEST(Binding, StepOneBindsEachPartToItsTableJoint) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  BindingOptions only_step1;
  only_step1.blend_joints.clear();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables(), only_step1);
  const int expected[3] = {sk.find_joint("l_shoulder"), sk.find_joint("l_elbow"), sk.find_joint("l_wrist")};
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    ASSERT_EQ(b.influence_count(v), 1);
    EXPECT_EQ(b.joints[v][0], expected[mesh.part[v]]);
  }
  const BindingStats stats = binding_stats(b);
  EXPECT_EQ(stats.one_joint, mesh.vertex_count());
  EXPECT_EQ(stats.two_joints + stats.more_joints, 0u);
}

TEST(Binding, MissingPartEntryOrJointIsAnError) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const BindingTables no_hand = load_binding_tables(R"({"parts": {"lShldr": "l_shoulder", "lForeArm": "l_elbow"}})",
                                                    "", "p.json", "o.json");
  EXPECT_THROW(bind_three_step(mesh, sk, no_hand), std::invalid_argument);
  const BindingTables absent_joint = load_binding_tables(
      R"({"parts": {"lShldr": "l_shoulder", "lForeArm": "l_elbow", "lHand": "l_index1"}})", "", "p.json", "o.json");
  try {
    bind_three_step(mesh, sk, absent_joint);
    FAIL() << "a joint the skeleton lacks must be reported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("l_index1"), std::string::npos) << e.what();
  }
}

// ---- Step 2 -------------------------------------------------------------------------------------------------------

TEST(Binding, StepTwoBlendsExactlyTheVerticesNearTheElbow) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const int shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow");
  const float radius = 0.07f;
  for (Step2Weights mode : {Step2Weights::AxialSmoothstep, Step2Weights::InverseDistance}) {
    BindingOptions opt;
    opt.blend_joints = {{"l_elbow", radius}};
    opt.step2_weights = mode;
    const SkinBinding b = bind_three_step(mesh, sk, arm_tables(), opt);
    expect_valid(b, mesh.vertex_count(), sk.joint_count());
    std::size_t blended = 0;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      const float d = glm::length(mesh.positions[v] - sk.centers[elbow]);
      if (d < radius - 1e-4f) {
        ++blended;
        EXPECT_EQ(joints_of(b, v), (std::set<int>{shoulder, elbow})) << "vertex " << v << " at " << d << " m";
      } else if (d > radius + 1e-4f) {
        EXPECT_EQ(b.influence_count(v), 1) << "vertex " << v << " is " << d << " m from the elbow";
      }
      if (mode == Step2Weights::InverseDistance && d < radius - 1e-4f) {
        const double ds = glm::length(mesh.positions[v] - sk.centers[shoulder]);
        EXPECT_NEAR(weight_of(b, v, elbow) / weight_of(b, v, shoulder), ds / d, 1e-4 * ds / d);
      }
    }
    // Rings within sqrt(0.07^2 - 0.04^2) = 0.057 m of the elbow: 11 rings of 24 vertices.
    EXPECT_EQ(blended, 11u * 24u);
    EXPECT_EQ(binding_stats(b).two_joints, blended);
  }
}

// A body's tables may widen one joint's step-2 sphere (data/makehuman_binding_overrides.json's knees): the radius
// from the tables replaces the options' for that joint alone, exactly as if the options had said it.
TEST(Binding, TablesStepTwoRadiusReplacesTheOptionsForThatJoint) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  BindingOptions opt;
  opt.blend_joints = {{"l_elbow", 0.07f}, {"l_wrist", 0.05f}};
  const BindingTables wider = arm_tables(R"({"step2_radii": {"l_elbow": 0.09}, "overrides": []})");
  ASSERT_EQ(wider.step2_radii.size(), 1u);
  const SkinBinding from_tables = bind_three_step(mesh, sk, wider, opt);
  BindingOptions said = opt;
  said.blend_joints[0].radius_m = 0.09f;
  const SkinBinding from_options = bind_three_step(mesh, sk, arm_tables(), said);
  EXPECT_EQ(from_tables.joints, from_options.joints);
  EXPECT_EQ(from_tables.weights, from_options.weights);
  // Wider than the options' 0.07 m: more vertices blend (rings within sqrt(0.09^2 - 0.04^2) = 0.081 m).
  EXPECT_GT(binding_stats(from_tables).two_joints, binding_stats(bind_three_step(mesh, sk, arm_tables(), opt)).two_joints);
  // A radius for a joint the options do not blend adds nothing (step 2's joints are the options' to choose).
  const BindingTables shoulder_only = arm_tables(R"({"step2_radii": {"l_shoulder": 0.2}, "overrides": []})");
  const SkinBinding unchanged = bind_three_step(mesh, sk, shoulder_only, opt);
  EXPECT_EQ(unchanged.weights, bind_three_step(mesh, sk, arm_tables(), opt).weights);
}

TEST(Binding, SmoothStepTwoIsHalfAtTheCreaseAndMonotoneAlongTheArm) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const int elbow = sk.find_joint("l_elbow");
  BindingOptions opt;
  opt.blend_joints = {{"l_elbow", 0.07f}};
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables(), opt);
  // Vertices of one meridian (x > 0, z = 0) from the shoulder to the wrist, top to bottom: the elbow's weight
  // never decreases going down.
  std::vector<std::pair<float, double>> meridian;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.positions[v].x > 0.039f && std::abs(mesh.positions[v].z) < 1e-6f && mesh.positions[v].y > kWristY)
      meridian.emplace_back(mesh.positions[v].y, weight_of(b, v, elbow));
  std::sort(meridian.begin(), meridian.end(), [](auto& a, auto& c) { return a.first > c.first; });
  ASSERT_GT(meridian.size(), 50u);
  for (std::size_t i = 1; i < meridian.size(); ++i) {
    EXPECT_GE(meridian[i].second, meridian[i - 1].second - 1e-9) << "at y = " << meridian[i].first;
    EXPECT_LT(meridian[i].second - meridian[i - 1].second, 0.25) << "a jump at y = " << meridian[i].first;
    if (std::abs(meridian[i].first - kElbowY) < 1e-5f) {
      EXPECT_NEAR(meridian[i].second, 0.5, 1e-4);
    }
  }
}

// ---- Step 3 -------------------------------------------------------------------------------------------------------

// Everything outside the selection is bit-identical to the binding without overrides.
void expect_only_selected_changed(const SkinBinding& base, const SkinBinding& got, const std::vector<bool>& selected) {
  for (std::size_t v = 0; v < selected.size(); ++v)
    if (!selected[v]) {
      EXPECT_EQ(got.joints[v], base.joints[v]) << "vertex " << v << " was not selected";
      EXPECT_EQ(got.weights[v], base.weights[v]) << "vertex " << v << " was not selected";
    }
}

TEST(Binding, OverrideByVertexIdsBindsThoseToTheClosestJointAndItsParent) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding base = bind_three_step(mesh, sk, arm_tables());
  const std::vector<std::uint32_t> ids = {3, 100, 500, static_cast<std::uint32_t>(mesh.vertex_count() - 2)};
  std::string json = R"({"overrides": [{"name": "picked", "vertices": [)";
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i > 0) json += ',';
    json += std::to_string(ids[i]);
  }
  json += "]}]}";
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables(json));
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  std::vector<bool> selected(mesh.vertex_count(), false);
  for (std::uint32_t v : ids) {
    selected[v] = true;
    // The closest joint, found here by brute force, and its parent; weights inversely proportional to distance.
    int best = 0;
    for (std::size_t j = 1; j < sk.joint_count(); ++j)
      if (glm::length(mesh.positions[v] - sk.centers[j]) < glm::length(mesh.positions[v] - sk.centers[best]))
        best = static_cast<int>(j);
    const int parent = sk.parents[best];
    ASSERT_GE(parent, 0);
    EXPECT_EQ(joints_of(b, v), (std::set<int>{best, parent})) << "vertex " << v;
    const double db = glm::length(mesh.positions[v] - sk.centers[best]);
    const double dp = glm::length(mesh.positions[v] - sk.centers[parent]);
    EXPECT_NEAR(weight_of(b, v, best), (1.0 / db) / (1.0 / db + 1.0 / dp), 1e-6);
  }
  expect_only_selected_changed(base, b, selected);
}

TEST(Binding, OverrideBySphereAndByBoxWithPartAndJointFilters) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding base = bind_three_step(mesh, sk, arm_tables());
  const int root = 0, shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow"),
            wrist = sk.find_joint("l_wrist");
  {
    const glm::vec3 centre(0.04f, 1.3f, 0.0f);
    const SkinBinding b = bind_three_step(
        mesh, sk, arm_tables(R"({"overrides": [{"sphere": {"center": [0.04, 1.3, 0.0], "radius": 0.03}}]})"));
    std::vector<bool> selected(mesh.vertex_count());
    std::size_t count = 0;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      selected[v] = glm::length(mesh.positions[v] - centre) <= 0.03f;
      if (!selected[v]) continue;
      ++count;
      EXPECT_EQ(joints_of(b, v), (std::set<int>{shoulder, root})) << "the shoulder is closest; its parent is root";
    }
    EXPECT_GT(count, 10u);
    expect_only_selected_changed(base, b, selected);
  }
  {
    // A box round the whole arm, restricted to the hand part and to the wrist as candidate joint.
    const SkinBinding b = bind_three_step(
        mesh, sk,
        arm_tables(R"({"overrides": [{"box": {"min": [-1, 0, -1], "max": [1, 2, 1]}, "parts": ["lHand"],
                                      "joints": ["l_wrist"]}]})"));
    std::vector<bool> selected(mesh.vertex_count());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      selected[v] = mesh.part[v] == 2;
      if (selected[v]) {
        EXPECT_EQ(joints_of(b, v), (std::set<int>{wrist, elbow}));
      }
    }
    expect_only_selected_changed(base, b, selected);
  }
  {
    // nearest_two blends the two closest candidates, siblings or not.
    const SkinBinding b = bind_three_step(
        mesh, sk,
        arm_tables(R"({"overrides": [{"box": {"min": [-1, 1.0, -1], "max": [1, 1.2, 1]},
                                      "joints": ["HumanoidRoot", "l_elbow", "l_wrist"], "blend": "nearest_two"}]})"));
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      if (mesh.positions[v].y >= 1.0f && mesh.positions[v].y <= 1.2f) {
        const std::set<int> expected = mesh.positions[v].y > (1.5f + kWristY) / 2.0f ? std::set<int>{elbow, root}
                                                                                     : std::set<int>{elbow, wrist};
        EXPECT_EQ(joints_of(b, v), expected) << "y = " << mesh.positions[v].y;
      }
  }
}

TEST(Binding, OverrideFalloffFadesIntoThePreviousBinding) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding base = bind_three_step(mesh, sk, arm_tables());
  const SkinBinding b = bind_three_step(
      mesh, sk,
      arm_tables(R"({"overrides": [{"box": {"min": [-1, 1.2, -1], "max": [1, 1.3, 1]}, "joints": ["HumanoidRoot"],
                                    "falloff_m": 0.04}]})"));
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  const int shoulder = sk.find_joint("l_shoulder");
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float y = mesh.positions[v].y;
    const double inside = std::min(y - 1.2, 1.3 - y);
    if (inside < -1e-6) {
      EXPECT_EQ(b.weights[v], base.weights[v]);
    } else if (inside > 0.04 + 1e-6) {
      // Full strength: root only (it has no parent), so the shoulder keeps nothing.
      EXPECT_NEAR(weight_of(b, v, 0), 1.0, 1e-6) << "y = " << y;
    } else {
      const double t = std::clamp(inside / 0.04, 0.0, 1.0), s = t * t * (3 - 2 * t);
      EXPECT_NEAR(weight_of(b, v, 0), s, 1e-5) << "y = " << y;
      EXPECT_NEAR(weight_of(b, v, shoulder), 1.0 - s, 1e-5) << "y = " << y;
    }
  }
}

// On the arm capsule the harmonic field is exactly linear in y between the two rings around the box (the strip of
// squares is flat, and the cotangent Laplacian reproduces linear functions there), before the soft threshold.
TEST(Binding, HarmonicOverrideInterpolatesLinearlyAlongTheArm) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding base = bind_three_step(mesh, sk, arm_tables());
  // Box edges between rings (every 0.01 m): rings 1.00 .. 1.20 are free, 0.99 (forearm) and 1.21 (upper arm) fixed.
  const SkinBinding b = bind_three_step(
      mesh, sk, arm_tables(R"({"overrides": [{"box": {"min": [-1, 0.995, -1], "max": [1, 1.205, 1]},
                                                "blend": "harmonic"}]})"));
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  const int shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow");
  std::vector<bool> selected(mesh.vertex_count(), false);
  std::size_t count = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float y = mesh.positions[v].y;
    selected[v] = y > 0.995f && y < 1.205f;
    if (!selected[v]) continue;
    ++count;
    EXPECT_EQ(joints_of(b, v), (std::set<int>{shoulder, elbow})) << "y = " << y;
    const double t = (y - 0.99) / 0.22;
    EXPECT_NEAR(weight_of(b, v, shoulder), soft_threshold({t, 1.0 - t})[0], 1e-4) << "y = " << y;
  }
  EXPECT_EQ(count, 21u * 24u);
  expect_only_selected_changed(base, b, selected);
  // Step 2 alone blends the same joints over a narrower band (its sphere, 1.03 .. 1.17).
  std::size_t base_blended = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) base_blended += selected[v] && base.influence_count(v) == 2;
  EXPECT_LT(base_blended, count);
}

// The field carries every joint around the region, as at the crotch of the default body, where sacroiliac and
// both hips meet. Here the forearm alone is free: above it the upper arm's lowest ring, which step 2 blends between
// shoulder and elbow, below it the hand (wrist). Harmonic data (a, 1 - a, 0) above and (0, 0, 1) below give
// t (a, 1 - a, 0) + (1 - t) (0, 0, 1) with t linear in y, then the soft threshold. A region that touches no fixed
// vertex has nothing to interpolate from and is left as it was.
TEST(Binding, HarmonicOverrideCarriesEveryJointAroundItAndSkipsClosedRegions) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding base = bind_three_step(mesh, sk, arm_tables());
  const int shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow"), wrist = sk.find_joint("l_wrist");
  const SkinBinding b = bind_three_step(
      mesh, sk, arm_tables(R"({"overrides": [{"box": {"min": [-1, 0, -1], "max": [1, 2, 1]}, "parts": ["lForeArm"],
                                                "blend": "harmonic"}]})"));
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  float top = 1e9f, bottom = -1e9f;  // the fixed rings next to the forearm
  std::size_t top_vertex = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float y = mesh.positions[v].y;
    if (mesh.part[v] == 0 && y < top) top = y, top_vertex = v;
    if (mesh.part[v] == 2) bottom = std::max(bottom, y);
  }
  const double a = weight_of(base, top_vertex, shoulder);
  ASSERT_GT(a, 0.1);
  ASSERT_LT(a, 0.9);
  std::size_t forearm = 0, three = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    if (mesh.part[v] != 1) {
      EXPECT_EQ(b.weights[v], base.weights[v]);
      continue;
    }
    ++forearm;
    const double t = (mesh.positions[v].y - bottom) / (top - bottom);
    const std::vector<double> expected = soft_threshold({t * a, t * (1.0 - a), 1.0 - t});
    std::set<int> expected_joints;
    for (int k = 0; k < 3; ++k)
      if (expected[static_cast<std::size_t>(k)] > 1e-3)
        expected_joints.insert(k == 0 ? shoulder : k == 1 ? elbow : wrist);
    EXPECT_EQ(joints_of(b, v), expected_joints) << "y = " << mesh.positions[v].y;
    three += expected_joints.size() == 3;
    EXPECT_NEAR(weight_of(b, v, shoulder), expected[0], 1e-4) << "y = " << mesh.positions[v].y;
    EXPECT_NEAR(weight_of(b, v, elbow), expected[1], 1e-4) << "y = " << mesh.positions[v].y;
    EXPECT_NEAR(weight_of(b, v, wrist), expected[2], 1e-4) << "y = " << mesh.positions[v].y;
  }
  EXPECT_GT(forearm, 20u * 24u);
  EXPECT_GT(three, forearm / 2);

  const SkinBinding closed = bind_three_step(
      mesh, sk, arm_tables(R"({"overrides": [{"box": {"min": [-1, 0, -1], "max": [1, 2, 1]}, "blend": "harmonic"}]})"));
  EXPECT_EQ(closed.joints, base.joints);
  EXPECT_EQ(closed.weights, base.weights);
}

TEST(Binding, OverrideVertexIdOutOfRangeIsAnError) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  EXPECT_THROW(bind_three_step(mesh, sk, arm_tables(R"({"overrides": [{"vertices": [99999]}]})")),
               std::invalid_argument);
  EXPECT_THROW(
      bind_three_step(mesh, sk, arm_tables(R"({"overrides": [{"vertices": [1, 99999], "blend": "harmonic"}]})")),
      std::invalid_argument);
}

// ---- Table loading ------------------------------------------------------------------------------------------------

void expect_load_error(std::string_view parts, std::string_view overrides, const std::string& needle) {
  try {
    load_binding_tables(parts, overrides, "my_parts.json", "my_overrides.json");
    FAIL() << "expected a LoadError mentioning " << needle;
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(BindingTables, LoaderErrorsNameFileAndEntry) {
  expect_load_error(R"({"parts": {"lShldr": )", "", "my_parts.json: invalid JSON");
  expect_load_error(R"({"parts": {"lWing": "l_shoulder"}})", "", "my_parts.json: parts.lWing: unknown part");
  expect_load_error(R"({"parts": {"lShldr": "l_sholder"}})", "", "parts.lShldr: unknown joint 'l_sholder'");
  expect_load_error(R"({"parts": {"lShldr": 3}})", "", "parts.lShldr");
  expect_load_error(R"({"parts": ["lShldr"]})", "", "my_parts.json");
  expect_load_error(R"({"parts": {}, "prts": {}})", "", "unknown key 'prts'");
  expect_load_error("", R"({"overrides": [{"name": "x", "sphere": {"center": [0,0,0], "radius": 1},
                            "box": {"min": [0,0,0], "max": [1,1,1]}}]})",
                    "my_overrides.json: overrides[0] 'x': needs exactly one of");
  expect_load_error("", R"({"overrides": [{}, {"sphere": {"center": [0,0], "radius": 1}}]})", "overrides[0]");
  expect_load_error("", R"({"overrides": [{"sphere": {"center": [0,0], "radius": 1}}]})",
                    "overrides[0]: sphere.center: expected an array of 3 numbers");
  expect_load_error("", R"({"overrides": [{"sphere": {"center": [0,0,0], "radius": -1}}]})", "radius");
  expect_load_error("", R"({"overrides": [{"box": {"min": [1,0,0], "max": [0,1,1]}}]})", "min exceeds max");
  expect_load_error("", R"({"overrides": [{"vertices": [1, -2]}]})", "non-negative integer");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "joints": ["l_elbo"]}]})", "unknown joint 'l_elbo'");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "parts": ["arm"]}]})", "unknown part 'arm'");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "blend": "average"}]})", "'blend'");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "falloff_m": -0.1}]})", "falloff_m");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "blend": "harmonic", "joints": ["l_elbow"]}]})",
                    "overrides[0]: a harmonic blend takes its joints from around the selection");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "blend": "harmonic", "falloff_m": 0.02}]})",
                    "no 'joints' or 'falloff_m'");
  expect_load_error("", R"({"overrides": [{"vertices": [1], "radius": 2}]})", "unknown key 'radius'");
  expect_load_error("", R"({"step2_radii": [0.1], "overrides": []})", "my_overrides.json: 'step2_radii' must be an object");
  expect_load_error("", R"({"step2_radii": {"l_kne": 0.1}, "overrides": []})", "step2_radii.l_kne: unknown joint");
  expect_load_error("", R"({"step2_radii": {"l_knee": "wide"}, "overrides": []})", "step2_radii.l_knee: the radius");
  expect_load_error("", R"({"step2_radii": {"l_knee": 0}, "overrides": []})", "step2_radii.l_knee: the radius");
  expect_load_error("", R"({"step2_radii": {"l_knee": 3}, "overrides": []})", "in (0, 1]");
}

TEST(BindingTables, AcceptsHanim2019JointNamesAndComments) {
  const BindingTables t = load_binding_tables(R"({"_doc": "x", "parts": {"lHand": "l_radiocarpal"}})", "", "a", "b");
  ASSERT_EQ(t.part_joints.size(), 1u);
  EXPECT_EQ(*t.joint_of_part("lHand"), "l_radiocarpal");
  EXPECT_EQ(t.joint_of_part("rHand"), nullptr);
}

TEST(BindingTables, ShippedTablesCoverAllPartsAndFitTheDefaultSkeleton) {
  const std::string parts = read_text(repo_data("part_joints.json"));
  const std::string overrides = read_text(repo_data("binding_overrides.json"));
  ASSERT_FALSE(parts.empty());
  ASSERT_FALSE(overrides.empty());
  const BindingTables t = load_binding_tables(parts, overrides, "part_joints.json", "binding_overrides.json");
  const Skeleton sk = load_default_humanoid().skeleton;
  for (const std::string& part : paper_part_names()) {
    const std::string* joint = t.joint_of_part(part);
    ASSERT_NE(joint, nullptr) << part;
    EXPECT_GE(sk.find_joint(*joint), 0) << part << " -> " << *joint;
  }
  EXPECT_EQ(t.part_joints.size(), 53u);
  EXPECT_EQ(*t.joint_of_part("hip"), "sacroiliac");
  EXPECT_EQ(*t.joint_of_part("lShldr"), "l_shoulder");
  EXPECT_EQ(*t.joint_of_part("rForeArm"), "r_elbow");
  EXPECT_EQ(*t.joint_of_part("lPinky3"), "l_wrist");
  ASSERT_FALSE(t.overrides.empty());
  for (const SkinSelection& s : t.overrides)
    for (const std::string& j : s.joints) EXPECT_GE(sk.find_joint(j), 0) << s.name << ": " << j;
}

TEST(BindingTables, EmbeddedDefaultsAreTheShippedFiles) {
  if (!embedded::find("data/part_joints.json") || !embedded::find("data/binding_overrides.json"))
    GTEST_SKIP() << "binding tables are not in STRATA_EMBEDDED_FILES of this build";
  const BindingTables t = load_binding_tables(read_text(repo_data("part_joints.json")),
                                              read_text(repo_data("binding_overrides.json")), "p", "o");
  EXPECT_EQ(default_binding_tables().part_joints, t.part_joints);
  ASSERT_EQ(default_binding_tables().overrides.size(), t.overrides.size());
  for (std::size_t i = 0; i < t.overrides.size(); ++i)
    EXPECT_EQ(default_binding_tables().overrides[i].name, t.overrides[i].name);
}

TEST(BindingTables, DefaultWaistOverrideBlendsSacroiliacAndVl5) {
  const BindingTables t = load_binding_tables(read_text(repo_data("part_joints.json")),
                                              read_text(repo_data("binding_overrides.json")), "p", "o");
  const Skeleton sk = load_default_humanoid().skeleton;
  const int sacro = sk.find_joint("sacroiliac"), vl5 = sk.find_joint("vl5");
  // A torso capsule: hip part below y = 1.0, abdomen above, lower back and belly between the two joints.
  Mesh torso = capsule(0.9f, 1.15f, 0.13f, 32, 0.01f, 4);
  torso.part_names = {"hip", "abdomen"};
  for (const glm::vec3& p : torso.positions) torso.part.push_back(p.y < 1.0f ? 0 : 1);
  BindingOptions no_overrides;
  no_overrides.apply_overrides = false;
  const SkinBinding base = bind_three_step(torso, sk, t, no_overrides);
  const SkinBinding b = bind_three_step(torso, sk, t);
  expect_valid(b, torso.vertex_count(), sk.joint_count());
  std::size_t blended = 0;
  for (std::size_t v = 0; v < torso.vertex_count(); ++v) {
    EXPECT_EQ(base.influence_count(v), 1);
    const float y = torso.positions[v].y;
    if (y > 0.99f && y < 1.03f && std::abs(torso.positions[v].x) < 0.2f) {
      EXPECT_EQ(joints_of(b, v), (std::set<int>{sacro, vl5})) << "y = " << y;
      ++blended;
    }
    if (y > 1.09f) {
      EXPECT_EQ(joints_of(b, v), std::set<int>{vl5}) << "above the box";
    }
  }
  EXPECT_GE(blended, 3u * 32u) << "the rings at y = 1.00, 1.01, 1.02";
}

TEST(BindingTables, ShippedTablesBindTheDefaultBody) {
  const BindingTables t = load_binding_tables(read_text(repo_data("part_joints.json")),
                                              read_text(repo_data("binding_overrides.json")), "p", "o");
  const Skeleton sk = load_default_humanoid().skeleton;
  const Mesh& body = default_body().levels[2];
  const SkinBinding b = bind_three_step(body, sk, t);
  expect_valid(b, body.vertex_count(), sk.joint_count());
  const BindingStats stats = binding_stats(b);
  // The paper's Table 1 shape: most vertices follow one joint, a band around the joints follows two.
  EXPECT_GT(stats.one_joint, stats.two_joints);
  EXPECT_GT(stats.two_joints, body.vertex_count() / 50);
  // Three or four joints only where a harmonic selection meets them (the crotch: sacroiliac and both hips).
  EXPECT_GT(stats.more_joints, 0u);
  for (std::size_t v = 0; v < body.vertex_count(); ++v) {
    if (b.influence_count(v) <= 2) continue;
    const glm::vec3 p = body.positions[v];
    bool inside = false;
    for (const SkinSelection& s : t.overrides) {
      if (s.blend != SkinSelection::Blend::Harmonic) continue;
      const std::string& part = body.part_names[body.part[v]];
      const bool in_part = s.parts.empty() || std::find(s.parts.begin(), s.parts.end(), part) != s.parts.end();
      const bool in_box = glm::all(glm::greaterThanEqual(p, s.box_min)) && glm::all(glm::lessThanEqual(p, s.box_max));
      const bool in_shape = s.kind == SkinSelection::Kind::Sphere ? glm::length(p - s.center) <= s.radius : in_box;
      inside = inside || (in_part && in_shape);
    }
    EXPECT_TRUE(inside) << "vertex " << v << " has " << b.influence_count(v)
                        << " joints outside every harmonic selection";
  }
  const int shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow");
  const auto forearm = static_cast<std::uint16_t>(
      std::find(body.part_names.begin(), body.part_names.end(), "lForeArm") - body.part_names.begin());
  std::size_t forearm_vertices = 0;
  for (std::size_t v = 0; v < body.vertex_count(); ++v) {
    if (body.part[v] != forearm) continue;
    ++forearm_vertices;
    const std::set<int> js = joints_of(b, v);
    EXPECT_TRUE(js == std::set<int>{elbow} || js == (std::set<int>{shoulder, elbow})) << "vertex " << v;
  }
  EXPECT_GT(forearm_vertices, 0u);

  const std::vector<glm::mat4> identity(sk.joint_count(), glm::mat4(1.0f));
  const SkinMetrics rest = measure_skin(body, b, identity, body.positions);
  EXPECT_EQ(rest.inverted_triangles, 0u);
  EXPECT_EQ(rest.seam_gap_max_m, 0.0);
  EXPECT_EQ(rest.nan_count, 0u);
  const double elbow_change = flexion_volume_change_pct(body, b, sk, elbow, glm::radians(120.0f), 0.09f);
  EXPECT_TRUE(std::isfinite(elbow_change));
  EXPECT_LT(elbow_change, 0.0);
}

// ---- Bone heat ----------------------------------------------------------------------------------------------------

TEST(AutoBinding, WeightsAreValidSmoothDeterministicAndSplitAtTheElbow) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_automatic(mesh, sk);
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  const SkinBinding again = bind_automatic(mesh, sk);
  EXPECT_EQ(b.joints, again.joints);
  EXPECT_EQ(b.weights, again.weights);

  // Smooth: across every edge (10 mm apart along the arm), no joint's weight jumps much.
  double worst = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const std::uint32_t a = mesh.triangles[t], c = mesh.triangles[t - t % 3 + (t % 3 + 1) % 3];
    for (std::size_t j = 0; j < sk.joint_count(); ++j)
      worst = std::max(worst, std::abs(weight_of(b, a, int(j)) - weight_of(b, c, int(j))));
  }
  EXPECT_LT(worst, 0.15);

  // The shoulder/elbow boundary (equal weights) lies at the elbow, and each bone's middle belongs to it.
  const int shoulder = sk.find_joint("l_shoulder"), elbow = sk.find_joint("l_elbow");
  float crossing = std::numeric_limits<float>::quiet_NaN();
  std::vector<std::pair<float, std::size_t>> meridian;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.positions[v].x > 0.039f && std::abs(mesh.positions[v].z) < 1e-6f)
      meridian.emplace_back(mesh.positions[v].y, v);
  std::sort(meridian.begin(), meridian.end());
  for (std::size_t i = 1; i < meridian.size(); ++i) {
    const double lo = weight_of(b, meridian[i - 1].second, elbow) - weight_of(b, meridian[i - 1].second, shoulder);
    const double hi = weight_of(b, meridian[i].second, elbow) - weight_of(b, meridian[i].second, shoulder);
    if (lo >= 0.0 && hi < 0.0 && meridian[i].first > kWristY) crossing = meridian[i].first;
    if (std::abs(meridian[i].first - 1.3f) < 0.005f) {
      EXPECT_GT(weight_of(b, meridian[i].second, shoulder), 0.9);
    }
    if (std::abs(meridian[i].first - 0.98f) < 0.005f) {
      EXPECT_GT(weight_of(b, meridian[i].second, elbow), 0.85);
    }
  }
  EXPECT_NEAR(crossing, kElbowY, 0.02f);
  EXPECT_GT(binding_stats(b).two_joints, 0u) << "bone heat blends near joints";
}

TEST(AutoBinding, LeafJointWithoutSiteStillOwnsTheHandBeyondIt) {
  Skeleton sk = arm_skeleton();
  sk.sites.clear();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_automatic(mesh, sk);
  expect_valid(b, mesh.vertex_count(), sk.joint_count());
  const int wrist = sk.find_joint("l_wrist");
  const std::size_t tip = mesh.vertex_count() - 1;  // the bottom pole, 0.13 m beyond the wrist
  ASSERT_LT(mesh.positions[tip].y, kWristY - 0.1f);
  EXPECT_GT(weight_of(b, tip, wrist), 0.9);
}

// ---- Reference skinning (equation 4) ------------------------------------------------------------------------------

TEST(SkinReference, IdentityPoseLeavesTheMeshUnchangedExactly) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  for (const SkinBinding& b : {bind_three_step(mesh, sk, arm_tables()), bind_automatic(mesh, sk)}) {
    const std::vector<glm::mat4> identity(sk.joint_count(), glm::mat4(1.0f));
    const SkinnedVertices out = skin_reference(mesh, b, identity);
    ASSERT_EQ(out.positions.size(), mesh.vertex_count());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      EXPECT_EQ(out.positions[v], mesh.positions[v]) << "vertex " << v;
      EXPECT_LT(glm::length(out.normals[v] - mesh.normals[v]), 1e-6f);
    }
  }
}

TEST(SkinReference, RotatingTheRootMovesTheMeshRigidly) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables());
  std::vector<glm::quat> rot(sk.joint_count(), glm::quat(1, 0, 0, 0));
  rot[0] = glm::angleAxis(1.1f, glm::normalize(glm::vec3(0.3f, 1.0f, -0.5f)));
  const glm::vec3 shift(0.5f, -0.1f, 2.0f);
  const ReferencePose pose = fk_reference(sk, rot, shift);
  const SkinnedVertices out = skin_reference(mesh, b, pose.skinning);
  // Expected: rotate about the root centre, then translate; computed without the skinning code.
  const glm::vec3 c = sk.centers[0];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const glm::vec3 expected = shift + c + rot[0] * (mesh.positions[v] - c);
    EXPECT_LT(glm::length(out.positions[v] - expected), 1e-6f) << "vertex " << v;
    EXPECT_LT(glm::length(out.normals[v] - rot[0] * mesh.normals[v]), 1e-6f) << "vertex " << v;
  }
}

TEST(SkinReference, HalfAndHalfVertexLandsHalfwayAndOpposedNormalsFallBack) {
  Mesh mesh;
  mesh.positions = {{0.3f, 1.0f, -0.2f}};
  mesh.normals = {{1.0f, 0.0f, 0.0f}};
  mesh.triangles = {0, 0, 0};
  SkinBinding b;
  b.joints = {{{0, 1, 0, 0}}};
  b.weights = {{{0.5f, 0.5f, 0.0f, 0.0f}}};
  const glm::mat4 r = glm::rotate(glm::mat4(1.0f), glm::pi<float>(), glm::vec3(0, 1, 0));  // n -> -n
  const glm::mat4 moved = glm::translate(glm::mat4(1.0f), glm::vec3(0.2f, 0.4f, -1.0f)) * r;
  const std::vector<glm::mat4> mats = {glm::mat4(1.0f), moved};
  const SkinnedVertices out = skin_reference(mesh, b, mats);
  const glm::vec3 a = mesh.positions[0], c = glm::vec3(moved * glm::vec4(mesh.positions[0], 1.0f));
  EXPECT_LT(glm::length(out.positions[0] - 0.5f * (a + c)), 1e-6f) << "linear blend: the midpoint of the rigid results";
  EXPECT_EQ(out.normals[0], mesh.normals[0]) << "a zero blended normal falls back to the rest normal";
  EXPECT_FALSE(std::isnan(out.normals[0].x));
}

TEST(SkinReference, LanesOverloadMatchesTheMatrixOverload) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_automatic(mesh, sk);
  const auto joints = static_cast<std::uint32_t>(sk.joint_count());
  auto table = make_walker_table("t", joints);
  std::mt19937_64 rng(3);
  std::vector<std::vector<glm::quat>> poses;
  for (std::uint64_t w = 0; w < 3; ++w) {
    table->add(Entity{static_cast<std::uint32_t>(w + 1), 1});
    std::vector<glm::quat> rot(joints);
    for (std::uint32_t j = 0; j < joints; ++j) {
      rot[j] = random_rotation(rng, 1.5f);
      table->f32(kWalkerLocalRotation, j * 4 + 0)[w] = rot[j].x;
      table->f32(kWalkerLocalRotation, j * 4 + 1)[w] = rot[j].y;
      table->f32(kWalkerLocalRotation, j * 4 + 2)[w] = rot[j].z;
      table->f32(kWalkerLocalRotation, j * 4 + 3)[w] = rot[j].w;
    }
    for (int c = 0; c < 3; ++c) table->f32(kWalkerRootTranslation, c)[w] = 0.0f;
    poses.push_back(rot);
  }
  ASSERT_TRUE(make_fk_job(sk, *table).run());
  const WalkerLanes lanes = walker_lanes(*table, joints);
  for (std::size_t w = 0; w < 3; ++w) {
    const SkinnedVertices from_lanes = skin_reference(mesh, b, lanes, w);
    const SkinnedVertices from_ref = skin_reference(mesh, b, fk_reference(sk, poses[w], glm::vec3(0.0f)).skinning);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      EXPECT_LT(glm::length(from_lanes.positions[v] - from_ref.positions[v]), 1e-5f);
  }
  EXPECT_THROW(skin_reference(mesh, b, lanes, 3), std::invalid_argument);
}

// ---- Metrics ------------------------------------------------------------------------------------------------------

Mesh unit_cube() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
  // Two triangles per face, wound counter-clockwise seen from outside (checked below by the positive volume).
  m.triangles = {0, 2, 1, 1, 2, 3,  4, 5, 6, 5, 7, 6,  0, 1, 4, 1, 5, 4,
                 2, 6, 3, 3, 6, 7,  0, 4, 2, 2, 4, 6,  1, 3, 5, 3, 7, 5};
  compute_normals(m);
  return m;
}

TEST(SkinMetrics, VolumeOfClosedCubeAndSphereAboutAnyInteriorCentre) {
  const Mesh cube = unit_cube();
  EXPECT_NEAR(joint_volume(cube, cube.positions, {0.5f, 0.5f, 0.5f}, 10.0f), 1.0, 1e-6);
  EXPECT_NEAR(joint_volume(cube, cube.positions, {0.2f, 0.9f, 0.4f}, 10.0f), 1.0, 1e-6);
  // A radius that takes in no triangle centroid encloses nothing.
  EXPECT_EQ(joint_volume(cube, cube.positions, {0.5f, 0.5f, 0.5f}, 0.1f), 0.0);

  // A capsule of zero length is a sphere: fine tessellation approaches 4/3 pi r^3 from below.
  const Mesh sphere = capsule(1.0f, 1.0f, 0.5f, 96, 1.0f, 47);
  const double v = joint_volume(sphere, sphere.positions, {0.0f, 1.0f, 0.0f}, 1.0f);
  const double exact = 4.0 / 3.0 * glm::pi<double>() * 0.125;
  EXPECT_LT(v, exact);
  EXPECT_GT(v, exact * 0.995);
}

TEST(SkinMetrics, RestAgainstRestIsClean) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables());
  const std::vector<glm::mat4> identity(sk.joint_count(), glm::mat4(1.0f));
  const SkinMetrics m = measure_skin(mesh, b, identity, mesh.positions);
  EXPECT_EQ(m.triangles, mesh.triangle_count());
  EXPECT_EQ(m.inverted_triangles, 0u);
  EXPECT_EQ(m.seam_gap_max_m, 0.0);
  EXPECT_EQ(m.nan_count, 0u);
  EXPECT_EQ(joint_volume_change_pct(mesh, mesh.positions, sk.centers[2], sk.centers[2], 0.08f), 0.0);
}

TEST(SkinMetrics, RigidlyTurnedMeshHasNoInvertedTriangles) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables());
  std::vector<glm::quat> rot(sk.joint_count(), glm::quat(1, 0, 0, 0));
  rot[0] = glm::angleAxis(3.0f, glm::vec3(1, 0, 0));  // nearly upside down: every face normal changes a lot
  const ReferencePose pose = fk_reference(sk, rot, glm::vec3(0.0f));
  const SkinnedVertices posed = skin_reference(mesh, b, pose.skinning);
  const SkinMetrics m = measure_skin(mesh, b, pose.skinning, posed.positions);
  EXPECT_EQ(m.inverted_triangles, 0u);
  EXPECT_LT(m.seam_gap_max_m, 1e-12);
  EXPECT_NEAR(joint_volume_change_pct(mesh, posed.positions, sk.centers[2], glm::vec3(pose.world[2][3]), 0.08f), 0.0,
              1e-3);
}

TEST(SkinMetrics, FlippedAndCollapsedTrianglesSeamGapsAndNaNsAreCounted) {
  Mesh mesh = unit_cube();
  const std::vector<glm::mat4> identity(1, glm::mat4(1.0f));
  // A loose triangle beside the cube, and a copy of cube vertex 7 (a seam: same point, separate index).
  const std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), {{3, 0, 0}, {4, 0, 0}, {3, 1, 0}, {1, 1, 1}});
  mesh.triangles.insert(mesh.triangles.end(), {base, base + 1, base + 2});
  compute_normals(mesh);
  SkinBinding b;
  b.joints.assign(mesh.vertex_count(), {});
  b.weights.assign(mesh.vertex_count(), {{1.0f, 0.0f, 0.0f, 0.0f}});

  std::vector<glm::vec3> posed = mesh.positions;
  EXPECT_EQ(measure_skin(mesh, b, identity, posed).inverted_triangles, 0u);
  std::swap(posed[base + 1], posed[base + 2]);  // same triangle, opposite winding
  SkinMetrics m = measure_skin(mesh, b, identity, posed);
  EXPECT_EQ(m.inverted_triangles, 1u);

  posed = mesh.positions;
  posed[base + 2] = 0.5f * (posed[base] + posed[base + 1]);  // collapsed to a line
  EXPECT_EQ(measure_skin(mesh, b, identity, posed).inverted_triangles, 1u);

  posed = mesh.positions;
  posed[base + 3] += glm::vec3(0.0f, 0.03f, 0.04f);  // the seam copy drifts 5 cm from vertex 7
  m = measure_skin(mesh, b, identity, posed);
  EXPECT_NEAR(m.seam_gap_max_m, 0.05, 1e-6);
  EXPECT_EQ(m.nan_count, 0u);

  posed[2].y = std::numeric_limits<float>::quiet_NaN();
  m = measure_skin(mesh, b, identity, posed);
  EXPECT_EQ(m.nan_count, 1u);
  const auto uses_vertex_2 = static_cast<std::size_t>(std::count(mesh.triangles.begin(), mesh.triangles.end(), 2u));
  EXPECT_EQ(m.inverted_triangles, uses_vertex_2) << "the faces that use the NaN vertex";
}

TEST(SkinMetrics, LinearBlendLosesVolumeAtAFlexedElbow) {
  const Skeleton sk = arm_skeleton();
  const Mesh mesh = arm_mesh();
  const SkinBinding b = bind_three_step(mesh, sk, arm_tables());
  const int elbow = sk.find_joint("l_elbow");
  const double change = flexion_volume_change_pct(mesh, b, sk, elbow, glm::radians(120.0f), 0.08f);
  EXPECT_TRUE(std::isfinite(change));
  EXPECT_LT(change, -1.0) << "linear blend skinning collapses the inside of a bent joint";
  EXPECT_EQ(flexion_volume_change_pct(mesh, b, sk, elbow, 0.0f, 0.08f), 0.0);
}

}  // namespace
}  // namespace strata
