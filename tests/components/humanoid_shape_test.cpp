// Finding a humanoid's joints by shape and by name (components/humanoid_shape.h) on small skeletons written here:
// a Mixamo-like rig facing -Z with helper joints (with unknown names and with Mixamo's), a rig already named, and
// trees that are no humanoid.
#include <gtest/gtest.h>

#include <string>

#include "components/humanoid_shape.h"
#include "components/skeleton.h"

namespace strata {
namespace {

// A rig facing -Z (its left at -X), pelvis at the root, a twist helper on each upper arm, toes, and eyes on the
// head; every joint named in a vocabulary no rule knows.
Skeleton foreign_rig() {
  Skeleton s;
  s.name = "foreign";
  s.source = "foreign.glb";
  auto add = [&](const std::string& name, int parent, glm::vec3 c) {
    s.joint_names.push_back(name);
    s.source_joint_names.push_back(name);
    s.parents.push_back(parent);
    s.centers.push_back(c);
    s.limits.emplace_back();
    s.stiffness.emplace_back(1.0f);
    return static_cast<int>(s.parents.size() - 1);
  };
  const int pelvis = add("P", -1, {0, 1.0f, 0});
  const int s1 = add("S1", pelvis, {0, 1.15f, 0});
  const int chest = add("S2", s1, {0, 1.35f, 0});
  const int neck = add("N", chest, {0, 1.55f, 0});
  const int head = add("H", neck, {0, 1.65f, 0});
  add("EyeA", head, {0.03f, 1.7f, -0.08f});
  add("EyeB", head, {-0.03f, 1.7f, -0.08f});
  for (const float side : {-1.0f, 1.0f}) {  // -X is this rig's left
    const std::string tag = side < 0 ? "A" : "B";
    const int clav = add("C" + tag, chest, {0.05f * side, 1.5f, 0});
    const int upper = add("U" + tag, clav, {0.18f * side, 1.48f, 0});
    // A roll helper at the shoulder itself (a zero-length bone, as many exporters write): the limb rotates there.
    const int twist = add("T" + tag, upper, {0.18f * side, 1.48f, 0});
    const int fore = add("F" + tag, twist, {0.2f * side, 1.2f, 0});
    const int hand = add("W" + tag, fore, {0.2f * side, 0.95f, 0});
    add("M" + tag, hand, {0.2f * side, 0.85f, 0});
    (void)upper;
  }
  for (const float side : {-1.0f, 1.0f}) {
    const std::string tag = side < 0 ? "A" : "B";
    const int thigh = add("L1" + tag, pelvis, {0.1f * side, 0.95f, 0});
    const int shin = add("L2" + tag, thigh, {0.1f * side, 0.5f, 0});
    const int foot = add("L3" + tag, shin, {0.1f * side, 0.08f, 0});
    add("L4" + tag, foot, {0.1f * side, 0.02f, -0.14f});  // toes ahead, towards -Z
  }
  return s;
}

// The file's name of the joint now called `hanim`, "(none)" when no joint is.
std::string file_name_of(const Skeleton& s, const char* hanim) {
  const std::int32_t j = s.find_joint(hanim);
  return j < 0 ? std::string("(none)") : s.source_joint_names[static_cast<std::size_t>(j)];
}

TEST(HumanoidShape, NamesAForeignRigFromItsShape) {
  Skeleton s = foreign_rig();
  std::string why;
  ASSERT_TRUE(name_humanoid_joints(s, &why)) << why;
  auto named = [&](const char* hanim) { return file_name_of(s, hanim); };
  EXPECT_EQ(named("HumanoidRoot"), "P");
  EXPECT_EQ(named("vl5"), "S1");
  EXPECT_EQ(named("vt6"), "S2");
  EXPECT_EQ(named("vc4"), "N");
  EXPECT_EQ(named("skullbase"), "H");
  // Facing -Z, the left is -X: the "A" side. Upper arm and forearm are the longest consecutive pair, so the roll
  // helper at the shoulder (the elbow's parent) is the shoulder the IK turns; the collar is the joint before the
  // zero-length helper bone.
  EXPECT_EQ(named("l_sternoclavicular"), "CA");
  EXPECT_EQ(named("l_shoulder"), "TA");
  EXPECT_EQ(named("l_elbow"), "FA");
  EXPECT_EQ(named("l_wrist"), "WA");
  EXPECT_EQ(named("l_hip"), "L1A");
  EXPECT_EQ(named("l_knee"), "L2A");
  EXPECT_EQ(named("l_ankle"), "L3A");
  EXPECT_EQ(named("l_midtarsal"), "L4A");
  EXPECT_EQ(named("r_hip"), "L1B");
  EXPECT_EQ(s.source_joint_names[0], "P");  // the file's names are kept
  EXPECT_NE(s.warnings.back().find("joints named by the skeleton's shape"), std::string::npos);
}

// The foreign rig's joints given Mixamo's names (with its "mixamorig:" prefix), left side first.
Skeleton mixamo_named(Skeleton s, bool keep_roll_helpers) {
  const std::pair<const char*, const char*> names[] = {
      {"P", "Hips"}, {"S1", "Spine"}, {"S2", "Spine2"}, {"N", "Neck"}, {"H", "Head"}, {"EyeA", "LeftEye"},
      {"EyeB", "RightEye"}, {"CA", "LeftShoulder"}, {"UA", "LeftArm"}, {"TA", "LeftArmRoll"}, {"FA", "LeftForeArm"},
      {"WA", "LeftHand"}, {"MA", "LeftHandMiddle1"}, {"CB", "RightShoulder"}, {"UB", "RightArm"},
      {"TB", "RightArmRoll"}, {"FB", "RightForeArm"}, {"WB", "RightHand"}, {"MB", "RightHandMiddle1"},
      {"L1A", "LeftUpLeg"}, {"L2A", "LeftLeg"}, {"L3A", "LeftFoot"}, {"L4A", "LeftToeBase"}, {"L1B", "RightUpLeg"},
      {"L2B", "RightLeg"}, {"L3B", "RightFoot"}, {"L4B", "RightToeBase"}};
  for (std::size_t j = 0; j < s.joint_names.size(); ++j)
    for (const auto& [from, to] : names)
      if (s.joint_names[j] == from) s.joint_names[j] = s.source_joint_names[j] = std::string("mixamorig:") + to;
  if (!keep_roll_helpers) {
    // Without the zero-length roll helpers (as Mixamo exports): the forearm hangs from the upper arm.
    for (std::size_t j = 0; j < s.joint_names.size(); ++j) {
      const std::string& n = s.joint_names[j];
      if (n.find("ForeArm") != std::string::npos) s.parents[j] = s.parents[static_cast<std::size_t>(s.parents[j])];
    }
  }
  return s;
}

TEST(HumanoidShape, NamesAMixamoRigByItsNamesAndFallsBackToTheShape) {
  Skeleton s = mixamo_named(foreign_rig(), false);
  std::string why;
  ASSERT_TRUE(name_humanoid_joints(s, &why)) << why;
  auto named = [&](const char* hanim) { return file_name_of(s, hanim); };
  EXPECT_EQ(named("HumanoidRoot"), "mixamorig:Hips");
  EXPECT_EQ(named("vl5"), "mixamorig:Spine");
  EXPECT_EQ(named("vt6"), "mixamorig:Spine2");
  EXPECT_EQ(named("vc4"), "mixamorig:Neck");
  EXPECT_EQ(named("l_sternoclavicular"), "mixamorig:LeftShoulder");
  EXPECT_EQ(named("l_shoulder"), "mixamorig:LeftArm");
  EXPECT_EQ(named("l_elbow"), "mixamorig:LeftForeArm");
  EXPECT_EQ(named("r_wrist"), "mixamorig:RightHand");
  EXPECT_EQ(named("l_knee"), "mixamorig:LeftLeg");
  EXPECT_EQ(named("r_midtarsal"), "mixamorig:RightToeBase");
  EXPECT_NE(s.warnings.back().find("joints named by their Mixamo names"), std::string::npos) << s.warnings.back();

  // Named the same, but with roll helpers between upper arm and forearm: the named shoulder is not the forearm's
  // parent, so the limbs could not be built from the names; the shape rules name the rig instead.
  Skeleton helpers = mixamo_named(foreign_rig(), true);
  ASSERT_TRUE(name_humanoid_joints(helpers, &why)) << why;
  EXPECT_EQ(file_name_of(helpers, "l_shoulder"), "mixamorig:LeftArmRoll");
  EXPECT_NE(helpers.warnings.back().find("joints named by the skeleton's shape"), std::string::npos);

  // Names of no family, on a shape that is no humanoid: both reasons are given.
  Skeleton chain = foreign_rig();
  chain.parents.resize(3), chain.centers.resize(3), chain.joint_names.resize(3), chain.source_joint_names.resize(3);
  EXPECT_FALSE(name_humanoid_joints(chain, &why));
  EXPECT_NE(why.find("joint names are no known family's"), std::string::npos) << why;
}

TEST(HumanoidShape, LeavesNamedRigsAndNonHumanoidsAlone) {
  Skeleton named = foreign_rig();
  ASSERT_TRUE(name_humanoid_joints(named));
  const std::vector<std::string> before = named.joint_names;
  std::string why;
  EXPECT_FALSE(name_humanoid_joints(named, &why));
  EXPECT_EQ(why, "the skeleton already has H-Anim limb names");
  EXPECT_EQ(named.joint_names, before);

  // A chain (RiggedSimple's two-bone cylinder) and a star with no spine branch.
  Skeleton chain = foreign_rig();
  chain.parents.resize(3), chain.centers.resize(3), chain.joint_names.resize(3), chain.source_joint_names.resize(3);
  EXPECT_FALSE(name_humanoid_joints(chain, &why));
  EXPECT_NE(why.find("no joint where the legs and the spine branch"), std::string::npos) << why;
  EXPECT_EQ(chain.joint_names, (std::vector<std::string>{"P", "S1", "S2"}));

  HumanoidShape shape;
  const std::int32_t parents[] = {-1, 0, 0, 0};
  const glm::vec3 rest[] = {{0, 1, 0}, {0.1f, 0.5f, 0}, {-0.1f, 0.5f, 0}, {0, 1.5f, 0}};
  EXPECT_NE(find_humanoid_by_shape(parents, rest, {}, shape).find("branches into a neck and two arms"),
            std::string::npos);
  const std::int32_t unordered[] = {-1, 2, 0};
  EXPECT_EQ(find_humanoid_by_shape(unordered, std::span(rest, 3), {}, shape), "joints not in topological order");
}

}  // namespace
}  // namespace strata
