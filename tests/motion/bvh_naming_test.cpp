// The naming families: the shipped CMU walk (Poser names) written out again as each family writes it -- its
// names, a namespace prefix, another root name, inches, a Z-up file, CRLF line ends -- is recognised and
// retargets to the same clip as the original.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include "io/bvh.h"
#include "io/hanim_loader.h"
#include "io/load_error.h"
#include "io/retarget_map_file.h"
#include "motion/bvh_naming.h"
#include "motion/retarget.h"

namespace strata {
namespace {

const std::filesystem::path kWalk = std::filesystem::path(STRATA_SHARED_DATA) / "cmu_mocap_bvh" / "02_02_daz.bvh";

struct Variant {
  std::string label;
  std::string family;                        // what recognise_bvh_naming must say
  std::map<std::string, std::string> names;  // Poser name -> this family's; per side, written for the left
  std::string root;                          // the root's name
  std::string prefix;                        // before every name ("mixamorig:")
  float units_per_cm = 1.0f;                 // 1 / 2.54 for inches
  bool z_up = false;                         // H-Anim (x, y, z) written as (x, -z, y): Z up, forward -Y
  bool crlf = false;
  std::string units;                         // what recognise_bvh_naming must infer
};

std::string side_name(const std::map<std::string, std::string>& names, const std::string& poser) {
  // Left names are listed; "rThigh" -> the listed "lThigh" with Left -> Right.
  auto it = names.find(poser);
  if (it != names.end()) return it->second;
  if (!poser.empty() && poser[0] == 'r') {
    it = names.find("l" + poser.substr(1));
    if (it != names.end()) {
      std::string n = it->second;
      const std::size_t at = n.find("Left");
      if (at != std::string::npos) return n.replace(at, 4, "Right");
      if (!n.empty() && n[0] == 'L') n[0] = 'R';
      return n;
    }
  }
  return poser;  // fingers, eyes: kept
}

// H-Anim axis a of the original goes to file axis axis_to[a], times sign[a].
void axis_map(bool z_up, int axis_to[3], float sign[3]) {
  axis_to[0] = 0, axis_to[1] = z_up ? 2 : 1, axis_to[2] = z_up ? 1 : 2;
  sign[0] = 1.0f, sign[1] = 1.0f, sign[2] = z_up ? -1.0f : 1.0f;
}

std::string write_variant(const BvhMotion& m, const Variant& v) {
  int to[3];
  float sign[3];
  axis_map(v.z_up, to, sign);
  auto vec = [&](const glm::vec3& p) {
    glm::vec3 out;
    for (int a = 0; a < 3; ++a) out[to[a]] = sign[a] * p[a] * v.units_per_cm;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.7g %.7g %.7g", out.x, out.y, out.z);
    return std::string(buf);
  };
  const char* axis_letter = "XYZ";
  std::string text = "HIERARCHY\n";
  std::vector<int> open;  // depth bookkeeping
  for (std::size_t j = 0; j < m.joint_count(); ++j) {
    const BvhJoint& b = m.joints[j];
    // Close the blocks of joints that are not ancestors of this one.
    while (!open.empty() && open.back() != b.parent) {
      text += std::string(open.size() - 1, ' ') + "}\n";
      open.pop_back();
    }
    const std::string indent(open.size(), ' ');
    const std::string name = j == 0 ? v.root : side_name(v.names, b.name);
    text += indent + (j == 0 ? "ROOT " : "JOINT ") + v.prefix + name + "\n" + indent + "{\n";
    text += indent + " OFFSET " + vec(b.offset) + "\n" + indent + " CHANNELS " + std::to_string(b.channels.size());
    for (const BvhChannel c : b.channels) {
      const int axis = static_cast<int>(c) % 3;
      const bool rotation = static_cast<int>(c) >= 3;
      text += std::string(" ") + axis_letter[to[axis]] + (rotation ? "rotation" : "position");
    }
    text += "\n";
    if (b.has_end_site)
      text += indent + " End Site\n" + indent + " {\n" + indent + "  OFFSET " + vec(b.end_site) + "\n" + indent + " }\n";
    open.push_back(static_cast<int>(j));
  }
  while (!open.empty()) {
    text += std::string(open.size() - 1, ' ') + "}\n";
    open.pop_back();
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "MOTION\nFrames: %zu\nFrame Time: %.8g\n", m.frame_count, m.frame_time);
  text += buf;
  for (std::size_t f = 0; f < m.frame_count; ++f) {
    const std::span<const float> row = m.frame(f);
    std::size_t col = 0;
    for (const BvhJoint& b : m.joints)
      for (const BvhChannel c : b.channels) {
        const int axis = static_cast<int>(c) % 3;
        const bool rotation = static_cast<int>(c) >= 3;
        const float value = row[col++] * sign[axis] * (rotation ? 1.0f : v.units_per_cm);
        std::snprintf(buf, sizeof buf, "%s%.7g", col == 1 ? "" : " ", value);
        text += buf;
      }
    text += "\n";
  }
  if (v.crlf) {
    std::string crlf;
    for (const char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    return crlf;
  }
  return text;
}

std::vector<Variant> variants() {
  const std::map<std::string, std::string> cmu = {
      {"abdomen", "LowerBack"}, {"chest", "Spine1"},       {"neck", "Neck"},         {"head", "Head"},
      {"lCollar", "LeftShoulder"}, {"lShldr", "LeftArm"},  {"lForeArm", "LeftForeArm"}, {"lHand", "LeftHand"},
      {"lButtock", "LHipJoint"},  {"lThigh", "LeftUpLeg"}, {"lShin", "LeftLeg"},     {"lFoot", "LeftFoot"},
      {"lMid1", "LeftHandMiddle1"}};
  std::map<std::string, std::string> max = cmu;
  max["lThigh"] = "LeftHip", max["lShin"] = "LeftKnee", max["lFoot"] = "LeftAnkle";
  std::map<std::string, std::string> mixamo = cmu;
  mixamo["abdomen"] = "Spine", mixamo["chest"] = "Spine2", mixamo["lButtock"] = "LeftHipHelper";
  return {
      {"cmu-motionbuilder-crlf", "CMU (MotionBuilder)", cmu, "Hips", "", 1.0f, false, true, "centimetres"},
      {"cmu-3dsmax-z-up", "CMU (3ds Max)", max, "Hips", "", 1.0f, true, false, "centimetres"},
      {"mixamo-prefixed", "Mixamo", mixamo, "Hips", "mixamorig:", 1.0f, false, false, "centimetres"},
      {"humanik-inches-odd-root", "HumanIK", mixamo, "CharacterPelvisRoot", "", 1.0f / 2.54f, false, true, "inches"},
  };
}

// Angle of the rotation between two unit quaternions, from the vector part of conj(a) b (acos of a float dot is
// too coarse near 1: it reads 0.06 deg for quaternions one rounding apart).
float angle_deg(const glm::quat& a, const glm::quat& b) {
  const glm::dquat d = glm::conjugate(glm::dquat(a)) * glm::dquat(b);
  return static_cast<float>(glm::degrees(2.0 * std::atan2(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), std::abs(d.w))));
}

// The worst key-by-key angle between two retargets of one capture (same tracks in the same order), and the worst
// root translation difference.
void expect_same_clip(const RetargetResult& r, const RetargetResult& reference) {
  ASSERT_EQ(r.clip.rotations.size(), reference.clip.rotations.size());
  float worst = 0.0f;
  for (std::size_t t = 0; t < r.clip.rotations.size(); ++t) {
    const RotationTrack& a = r.clip.rotations[t];
    const RotationTrack& b = reference.clip.rotations[t];
    ASSERT_EQ(a.joint, b.joint);
    ASSERT_EQ(a.values.size(), b.values.size());
    for (std::size_t k = 0; k < a.values.size(); ++k) worst = std::max(worst, angle_deg(a.values[k], b.values[k]));
  }
  EXPECT_LT(worst, 0.05f) << "degrees, worst key";
  const TranslationTrack& root = r.clip.translations.at(0);
  const TranslationTrack& root_ref = reference.clip.translations.at(0);
  ASSERT_EQ(root.values.size(), root_ref.values.size());
  float worst_root = 0.0f;
  for (std::size_t k = 0; k < root.values.size(); ++k)
    worst_root = std::max(worst_root, glm::length(root.values[k] - root_ref.values[k]));
  EXPECT_LT(worst_root, 5e-4f) << "metres";
  EXPECT_EQ(r.contacts.legs[0].size(), reference.contacts.legs[0].size());
}

// Every joint renamed to a meaningless "b<index>", so no family matches.
Variant meaningless_names(const BvhMotion& m, bool z_up) {
  Variant v;
  v.label = z_up ? "meaningless-z-up" : "meaningless";
  for (std::size_t j = 1; j < m.joint_count(); ++j) v.names[m.joints[j].name] = std::to_string(j).insert(0, 1, 'b');
  v.root = "b0";
  v.z_up = z_up;
  v.units = "centimetres";
  return v;
}

std::string renamed(const std::string& poser, const BvhMotion& m) {
  const std::int32_t j = m.find_joint(poser);
  return j < 0 ? poser : std::to_string(j).insert(0, 1, 'b');
}

class BvhFamilies : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kWalk)) GTEST_SKIP() << "no shared data at " << kWalk;
  }
};

TEST_F(BvhFamilies, ThePoserFileIsRecognisedInCentimetresWithHAnimAxes) {
  const BvhNaming n = recognise_bvh_naming(load_bvh_file(kWalk));
  EXPECT_EQ(n.family, "Poser/DAZ");
  EXPECT_EQ(n.units, "centimetres");
  EXPECT_NEAR(n.stature * n.metres_per_unit, 1.6, 0.15);
  EXPECT_EQ(n.axes, glm::mat3(1.0f));
}

TEST_F(BvhFamilies, EveryFamilyRetargetsToTheSameClipAsThePoserOriginal) {
  const BvhMotion original = load_bvh_file(kWalk);
  const Skeleton skeleton = load_default_humanoid().skeleton;
  const RetargetResult reference = retarget_bvh(original, skeleton);
  ASSERT_FALSE(reference.clip.rotations.empty());
  for (const Variant& v : variants()) {
    SCOPED_TRACE(v.label);
    const BvhMotion m = load_bvh_text(write_variant(original, v), v.label + ".bvh");
    const BvhNaming naming = recognise_bvh_naming(m);
    EXPECT_EQ(naming.family, v.family);
    EXPECT_EQ(naming.units, v.units);
    EXPECT_NEAR(naming.stature * naming.metres_per_unit, 1.6, 0.15);
    const RetargetResult r = retarget_bvh(m, skeleton);
    EXPECT_EQ(r.family, v.family);
    expect_same_clip(r, reference);
  }
}

// Names no family uses: the skeleton's shape alone finds the same joints as the Poser names (the same map, row for
// row), in Y-up and in Z-up, and the capture retargets to the same clip.
TEST_F(BvhFamilies, UnknownNamesAreMappedByTheSkeletonsShape) {
  const BvhMotion original = load_bvh_file(kWalk);
  const Skeleton skeleton = load_default_humanoid().skeleton;
  const BvhNaming by_name = recognise_bvh_naming(original);
  const RetargetResult reference = retarget_bvh(original, skeleton);
  for (const bool z_up : {false, true}) {
    const Variant v = meaningless_names(original, z_up);
    SCOPED_TRACE(v.label);
    const BvhMotion m = load_bvh_text(write_variant(original, v), v.label + ".bvh");
    const BvhNaming naming = recognise_bvh_naming(m);
    EXPECT_EQ(naming.family, "by shape (names not recognised)");
    EXPECT_EQ(naming.units, "centimetres");
    ASSERT_EQ(naming.map.size(), by_name.map.size());
    for (std::size_t r = 0; r < naming.map.size(); ++r) {
      SCOPED_TRACE(by_name.map[r].hanim);
      EXPECT_EQ(naming.map[r].hanim, by_name.map[r].hanim);
      EXPECT_EQ(naming.map[r].bvh, renamed(by_name.map[r].bvh, original));
      EXPECT_EQ(naming.map[r].bvh_aim, renamed(by_name.map[r].bvh_aim, original));
    }
    expect_same_clip(retarget_bvh(m, skeleton), reference);
  }
}

// A map file names the joints instead; rows aim and axes turn as for a recognised family.
TEST_F(BvhFamilies, AMapFileRetargetsWhatNoNameOrShapeRuleReads) {
  const BvhMotion original = load_bvh_file(kWalk);
  const Skeleton skeleton = load_default_humanoid().skeleton;
  const BvhNaming by_name = recognise_bvh_naming(original);
  const RetargetResult reference = retarget_bvh(original, skeleton);
  const Variant v = meaningless_names(original, true);
  const BvhMotion m = load_bvh_text(write_variant(original, v), "mapped.bvh");
  std::string text = "# BVH joint, H-Anim joint\n";
  for (const RetargetMapping& row : by_name.map)
    if (row.hanim != "l_midtarsal" && row.hanim != "r_midtarsal") text += renamed(row.bvh, original) + " " + row.hanim + "\n";
  const BvhNaming naming = bvh_naming_from_map(m, parse_retarget_map(text, "lab.map"));
  EXPECT_EQ(naming.family, "map lab.map");
  EXPECT_EQ(naming.axes * glm::vec3(0, 0, 1), glm::vec3(0, 1, 0));  // the file's +Z is up
  RetargetOptions options;
  options.map = naming.map;
  options.axes = naming.axes;
  options.family = naming.family;
  const RetargetResult r = retarget_bvh(m, skeleton, options);
  EXPECT_EQ(r.family, "map lab.map");
  expect_same_clip(r, reference);

  // A row naming a joint the capture lacks, and rows that do not hang one below the other.
  try {
    (void)bvh_naming_from_map(m, parse_retarget_map(text + "nosuch l_midtarsal\n", "lab.map"));
    ADD_FAILURE();
  } catch (const LoadError& e) {
    const std::string line = std::to_string(std::count(text.begin(), text.end(), '\n') + 1);
    EXPECT_NE(std::string(e.what()).find("lab.map:" + line + ": mapped.bvh has no joint 'nosuch'"), std::string::npos)
        << e.what();
  }
  std::string swapped = text;
  const std::string knee = renamed("lShin", original), ankle = renamed("lFoot", original);
  swapped.replace(swapped.find(knee + " l_knee"), knee.size(), "@");
  swapped.replace(swapped.find(ankle + " l_ankle"), ankle.size(), knee);
  swapped.replace(swapped.find("@ l_knee"), 1, ankle);
  try {
    (void)bvh_naming_from_map(m, parse_retarget_map(swapped, "lab.map"));
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("lab.map: '" + knee + "' does not hang from '" + ankle + "'"),
              std::string::npos)
        << e.what();
  }
}

TEST(BvhNaming, PrefixesAndCaseAreIgnored) {
  EXPECT_EQ(normalised_joint_name("mixamorig:LeftUpLeg"), "leftupleg");
  EXPECT_EQ(normalised_joint_name("Hips"), "hips");
  EXPECT_EQ(normalised_joint_name("a:b:Neck"), "neck");
}

TEST(BvhNaming, AxesSnapToTheNearestSignedPermutation) {
  // A Z-up file whose left is +X: forward is -Y.
  const glm::mat3 zup = bvh_file_axes(glm::vec3(1, 0, 0.05f), glm::vec3(0.02f, -0.1f, 1));
  EXPECT_EQ(zup * glm::vec3(1, 0, 0), glm::vec3(1, 0, 0));
  EXPECT_EQ(zup * glm::vec3(0, 0, 1), glm::vec3(0, 1, 0));
  EXPECT_EQ(zup * glm::vec3(0, -1, 0), glm::vec3(0, 0, 1));
  // Facing -Z (left is -X): turned half a turn about Y.
  const glm::mat3 back = bvh_file_axes(glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0));
  EXPECT_EQ(back * glm::vec3(0, 0, -1), glm::vec3(0, 0, 1));
  EXPECT_NEAR(glm::determinant(back), 1.0f, 1e-6f);
  // Degenerate (left and up along one axis): identity rather than a reflection.
  EXPECT_EQ(bvh_file_axes(glm::vec3(0, 1, 0), glm::vec3(0, 1, 0)), glm::mat3(1.0f));
}

}  // namespace
}  // namespace strata
