// Tests of the H-Anim loaders (io/hanim_loader.h), the XML helpers (io/xml_util.h), the Skeleton helpers
// (components/skeleton.h) and the shipped default skeleton (data/default_skeleton.x3d).
//
// Counts asserted for the real files under ../shared/data/hanim_x3d were measured independently of this code
// (grep and a Python ElementTree script over the same bytes), and agree with data-README.md where it gives them.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

#include "components/skeleton.h"
#include "io/hanim_loader.h"
#include "io/xml_util.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

const fs::path kHanimDir = fs::path(STRATA_SHARED_DATA) / "hanim_x3d";
const fs::path kRepoDefault = fs::path(STRATA_TEST_DATA) / ".." / ".." / "data" / "default_skeleton.x3d";

#define SKIP_WITHOUT_SHARED_DATA()                                                         \
  do {                                                                                     \
    if (!fs::is_directory(kHanimDir)) GTEST_SKIP() << "no shared data at " << kHanimDir; \
  } while (0)

// Loads `text` expecting a LoadError; checks the message names the source, the line and every `needles` entry.
void expect_load_error(const std::string& text, int line, std::initializer_list<std::string> needles) {
  const std::string source = "case.x3d";
  try {
    (void)load_humanoid_text(text, source);
    ADD_FAILURE() << "no LoadError for:\n" << text;
  } catch (const LoadError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(source + ":" + std::to_string(line) + ":"), std::string::npos) << msg;
    for (const std::string& needle : needles) EXPECT_NE(msg.find(needle), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

// The x component of an X3D rotation about +X, recovered from a quaternion; also checks it is about x only.
float angle_about_x(const glm::quat& q) {
  EXPECT_NEAR(q.y, 0.0f, 1e-6f);
  EXPECT_NEAR(q.z, 0.0f, 1e-6f);
  return 2.0f * std::atan2(q.x, q.w);
}

const RotationTrack* find_rotation(const AnimationClip& clip, std::int32_t joint) {
  for (const RotationTrack& t : clip.rotations)
    if (t.joint == joint) return &t;
  return nullptr;
}

bool any_warning_contains(const Skeleton& s, std::initializer_list<std::string> needles) {
  for (const std::string& w : s.warnings) {
    bool all = true;
    for (const std::string& n : needles) all = all && w.find(n) != std::string::npos;
    if (all) return true;
  }
  return false;
}

// ---- xml_util -----------------------------------------------------------------------------------------------

TEST(XmlUtil, ParsesNumberListsWithMixedSeparators) {
  std::vector<float> v;
  ASSERT_TRUE(xml::parse_floats(" 1, 2 3\n\t-4.5e-1,,+6 ", v, nullptr));
  ASSERT_EQ(v.size(), 5u);
  EXPECT_FLOAT_EQ(v[0], 1.0f);
  EXPECT_FLOAT_EQ(v[2], 3.0f);
  EXPECT_FLOAT_EQ(v[3], -0.45f);
  EXPECT_FLOAT_EQ(v[4], 6.0f);
  ASSERT_TRUE(xml::parse_floats("", v, nullptr));
  EXPECT_TRUE(v.empty());
}

TEST(XmlUtil, RejectsGarbageAndNonFiniteNumbers) {
  std::vector<float> v;
  std::string error;
  EXPECT_FALSE(xml::parse_floats("0.1 abc", v, &error));
  EXPECT_NE(error.find("abc"), std::string::npos);
  EXPECT_FALSE(xml::parse_floats("1.5x 2", v, nullptr));
  EXPECT_FALSE(xml::parse_floats("1 nan 2", v, nullptr));
  EXPECT_FALSE(xml::parse_floats("inf", v, nullptr));
  EXPECT_FALSE(xml::parse_floats("1e999", v, nullptr));
  std::vector<std::int64_t> i;
  EXPECT_TRUE(xml::parse_ints("0 1 2 -1", i, nullptr));
  EXPECT_EQ(i.size(), 4u);
  EXPECT_FALSE(xml::parse_ints("0 1.5", i, nullptr));
}

// The exact one-line format of io/load_error.h. (xml::Document itself is not used here: pugixml is a private
// dependency of the library, so a test calling its node API directly would not link.)
TEST(XmlUtil, ErrorMessageFormat) {
  try {
    (void)load_humanoid_text("<X3D><Scene>\n<HAnimHumanoid>\n\n  <HAnimJoint DEF='J_x' center='0 0 0'/>\n"
                             "</HAnimHumanoid></Scene></X3D>",
                             "dir/file.x3d");
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_STREQ(e.what(),
                 "dir/file.x3d:4: <HAnimJoint DEF='J_x'>: joint without name, and its DEF 'J_x' does not end in an "
                 "H-Anim joint name; add name='...'");
  }
}

// ---- Skeleton helpers -----------------------------------------------------------------------------------------

TEST(SkeletonNames, MapsHAnim2019NamesToTheInternalSet) {
  EXPECT_EQ(canonical_joint_name("humanoid_root"), "HumanoidRoot");
  EXPECT_EQ(canonical_joint_name("l_talocrural"), "l_ankle");
  EXPECT_EQ(canonical_joint_name("r_radiocarpal"), "r_wrist");
  EXPECT_EQ(canonical_joint_name("l_talocalcaneonavicular"), "l_subtalar");
  EXPECT_EQ(canonical_joint_name("r_transversetarsal"), "r_midtarsal");
  EXPECT_EQ(canonical_joint_name("l_knee"), "l_knee");
  EXPECT_TRUE(is_hanim2019_name("humanoid_root"));
  EXPECT_TRUE(is_hanim2019_name("l_metacarpophalangeal_2"));
  EXPECT_TRUE(is_hanim2019_name("r_tarsometatarsal_5"));
  EXPECT_FALSE(is_hanim2019_name("l_knee"));
  EXPECT_FALSE(is_hanim2019_name("HumanoidRoot"));
  EXPECT_FALSE(is_hanim2019_name("l_index1"));
  EXPECT_STRNE(to_string(JointNaming::HAnim1_1), to_string(JointNaming::HAnim2019));
}

// ---- the shipped default ----------------------------------------------------------------------------------------

TEST(DefaultSkeleton, HasThePapers25JointsInTopologicalOrder) {
  const HumanoidAsset asset = load_default_humanoid();
  const Skeleton& s = asset.skeleton;
  EXPECT_EQ(s.name, "strata_default");
  EXPECT_EQ(asset.format, HumanoidFormat::X3D);
  EXPECT_EQ(s.naming, JointNaming::HAnim1_1);
  ASSERT_EQ(s.joint_count(), 25u);
  EXPECT_EQ(s.joint_names[0], "HumanoidRoot");
  EXPECT_EQ(s.parents[0], -1);
  for (std::size_t j = 1; j < s.joint_count(); ++j) {
    EXPECT_GE(s.parents[j], 0);
    EXPECT_LT(s.parents[j], static_cast<std::int32_t>(j));
  }
  // The tree of tech-brief.md section 2.2, written out by hand.
  const std::map<std::string, std::string> parent_of = {
      {"sacroiliac", "HumanoidRoot"},       {"vl5", "HumanoidRoot"},
      {"l_hip", "sacroiliac"},              {"r_hip", "sacroiliac"},
      {"l_knee", "l_hip"},                  {"r_knee", "r_hip"},
      {"l_ankle", "l_knee"},                {"r_ankle", "r_knee"},
      {"l_midtarsal", "l_ankle"},           {"r_midtarsal", "r_ankle"},
      {"vt6", "vl5"},                       {"vt1", "vt6"},
      {"vc4", "vt1"},                       {"skullbase", "vc4"},
      {"l_sternoclavicular", "vt1"},        {"r_sternoclavicular", "vt1"},
      {"l_acromioclavicular", "l_sternoclavicular"}, {"r_acromioclavicular", "r_sternoclavicular"},
      {"l_shoulder", "l_acromioclavicular"}, {"r_shoulder", "r_acromioclavicular"},
      {"l_elbow", "l_shoulder"},            {"r_elbow", "r_shoulder"},
      {"l_wrist", "l_elbow"},               {"r_wrist", "r_elbow"},
  };
  ASSERT_EQ(parent_of.size(), 24u);
  for (const auto& [child, parent] : parent_of) {
    const std::int32_t c = s.find_joint(child);
    ASSERT_GE(c, 0) << child;
    EXPECT_EQ(s.parents[c], s.find_joint(parent)) << child;
  }
  EXPECT_EQ(s.depth(0), 0);
  EXPECT_EQ(s.depth(s.find_joint("skullbase")), 5);
  EXPECT_EQ(s.depth(s.find_joint("l_wrist")), 8);
}

// The ISO 200x knee centre sits 6.8 cm in front of the hip-ankle line (an 18 degree bend at rest); Strata's default
// moves it onto that line so that its rest leg is straight as H-Anim's default pose asks. Everything else is 200x.
TEST(DefaultSkeleton, CentresAreTheSymmetric200xDefaultsWithTheKneeOnTheStraightLeg) {
  const Skeleton s = load_default_humanoid().skeleton;
  const std::map<std::string, glm::vec3> expected = {
      {"HumanoidRoot", {0, 0.824f, 0.0277f}},   {"l_hip", {0.0961f, 0.9124f, -0.0001f}},
      {"l_knee", {0.1031f, 0.4867f, -0.037f}},  {"l_ankle", {0.1101f, 0.0656f, -0.0736f}},
      {"vt1", {0.0065f, 1.4951f, -0.0387f}},    {"skullbase", {0.0044f, 1.6209f, 0.0236f}},
      {"l_elbow", {0.2014f, 1.1357f, -0.0682f}}, {"l_wrist", {0.1984f, 0.8663f, -0.0583f}},
  };
  for (const auto& [name, c] : expected) {
    const std::int32_t j = s.find_joint(name);
    ASSERT_GE(j, 0) << name;
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.centers[j][a], c[a], 1e-6f) << name << " axis " << a;
  }
  for (const char* side : {"l_", "r_"}) {
    const glm::vec3 hip = s.centers[s.find_joint(std::string(side) + "hip")];
    const glm::vec3 knee = s.centers[s.find_joint(std::string(side) + "knee")];
    const glm::vec3 ankle = s.centers[s.find_joint(std::string(side) + "ankle")];
    const float bend = glm::degrees(std::acos(glm::dot(glm::normalize(knee - hip), glm::normalize(ankle - knee))));
    EXPECT_LT(bend, 0.2f) << side << "leg: the rest leg is straight";
  }
  for (std::size_t j = 0; j < s.joint_count(); ++j) {
    const std::string& n = s.joint_names[j];
    if (n.rfind("l_", 0) != 0) continue;
    const std::int32_t r = s.find_joint("r_" + n.substr(2));
    ASSERT_GE(r, 0) << n;
    EXPECT_FLOAT_EQ(s.centers[r].x, -s.centers[j].x) << n;
    EXPECT_FLOAT_EQ(s.centers[r].y, s.centers[j].y) << n;
    EXPECT_FLOAT_EQ(s.centers[r].z, s.centers[j].z) << n;
  }
  for (const char* site : {"l_forefoot_tip", "r_forefoot_tip", "l_calcaneous_post_pt", "r_calcaneous_post_pt",
                           "skull_tip", "l_hand_tip", "r_hand_tip"})
    EXPECT_GE(s.find_site(site), 0) << site;
  EXPECT_NEAR(s.sites[s.find_site("skull_tip")].position.y, 1.7504f, 1e-6f);
  // The hand tip hangs ~0.19 m below the wrist and is carried by it.
  const SkeletonSite& hand = s.sites[s.find_site("l_hand_tip")];
  EXPECT_EQ(hand.joint, s.find_joint("l_wrist"));
  EXPECT_NEAR(s.centers[hand.joint].y - hand.position.y, 0.19f, 0.01f);
}

TEST(DefaultSkeleton, SegmentsAndLimitsAreSensible) {
  const Skeleton s = load_default_humanoid().skeleton;
  EXPECT_EQ(s.segments.size(), 25u);
  float total = 0.0f;
  for (const SkeletonSegment& seg : s.segments) {
    EXPECT_GT(seg.mass, 0.0f) << seg.name;
    EXPECT_GE(seg.joint, 0) << seg.name;
    total += seg.mass;
  }
  EXPECT_NEAR(total, 75.0f, 1.0f);
  for (std::size_t j = 0; j < s.joint_count(); ++j) {
    const JointLimits& l = s.limits[j];
    EXPECT_EQ(l.present, j != 0) << s.joint_names[j];  // every joint but the free root
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(l.lower[a], 0.0f) << s.joint_names[j] << " axis " << a;  // rest pose inside
      EXPECT_GE(l.upper[a], 0.0f) << s.joint_names[j] << " axis " << a;
    }
  }
  // Knees flex (positive x) far more than they hyperextend; elbows flex the other way (negative x).
  const JointLimits& knee = s.limits[s.find_joint("l_knee")];
  EXPECT_GT(knee.upper.x, 2.0f);
  EXPECT_GT(knee.lower.x, -0.1f);
  const JointLimits& elbow = s.limits[s.find_joint("r_elbow")];
  EXPECT_LT(elbow.lower.x, -2.0f);
  EXPECT_LT(elbow.upper.x, 0.1f);
}

TEST(DefaultSkeleton, WalkCycleRespectsLimitsAndBendsTheRightWay) {
  const HumanoidAsset asset = load_default_humanoid();
  const Skeleton& s = asset.skeleton;
  ASSERT_EQ(asset.clips.size(), 1u);
  const AnimationClip& clip = asset.clips[0];
  EXPECT_FLOAT_EQ(clip.duration, 1.1f);
  EXPECT_TRUE(clip.loop);
  EXPECT_EQ(clip.rotations.size(), 8u);
  ASSERT_EQ(clip.translations.size(), 1u);
  EXPECT_EQ(clip.translations[0].joint, 0);

  for (const RotationTrack& t : clip.rotations) {
    ASSERT_GE(t.joint, 0);
    EXPECT_GE(t.times.size(), 5u);
    EXPECT_LE(t.times.size(), 9u);
    ASSERT_EQ(t.times.size(), t.values.size());
    EXPECT_FLOAT_EQ(t.times.front(), 0.0f);
    EXPECT_NEAR(t.times.back(), clip.duration, 1e-6f);
    for (std::size_t k = 1; k < t.times.size(); ++k) EXPECT_GT(t.times[k], t.times[k - 1]);
    const JointLimits& l = s.limits[t.joint];
    for (const glm::quat& q : t.values) {
      const float a = angle_about_x(q);
      EXPECT_GE(a, l.lower.x) << s.joint_names[t.joint];
      EXPECT_LE(a, l.upper.x) << s.joint_names[t.joint];
    }
  }

  // Knees: at the most flexed key the ankle, rotated about the knee centre, must move backward (-Z).
  for (const char* name : {"l_knee", "r_knee"}) {
    const std::int32_t knee = s.find_joint(name);
    const RotationTrack* t = find_rotation(clip, knee);
    ASSERT_NE(t, nullptr) << name;
    const glm::quat most = *std::max_element(t->values.begin(), t->values.end(), [](auto& a, auto& b) {
      return std::abs(2 * std::atan2(a.x, a.w)) < std::abs(2 * std::atan2(b.x, b.w));
    });
    const std::int32_t ankle = s.find_joint(std::string(name, 2) + "ankle");
    const glm::vec3 shin = s.centers[ankle] - s.centers[knee];
    EXPECT_LT((most * shin).z, shin.z - 0.1f) << name;
  }
  // Elbows: the wrist comes forward (+Z) at every key.
  for (const char* name : {"l_elbow", "r_elbow"}) {
    const std::int32_t elbow = s.find_joint(name);
    const RotationTrack* t = find_rotation(clip, elbow);
    ASSERT_NE(t, nullptr) << name;
    const glm::vec3 forearm = s.centers[s.find_joint(std::string(name, 2) + "wrist")] - s.centers[elbow];
    for (const glm::quat& q : t->values) EXPECT_GT((q * forearm).z, forearm.z + 0.02f) << name;
  }
  // Hips and shoulders swing in anti-phase: left + right angle ~ 0 at every key; shoulder opposite the same hip.
  const RotationTrack* lh = find_rotation(clip, s.find_joint("l_hip"));
  const RotationTrack* rh = find_rotation(clip, s.find_joint("r_hip"));
  const RotationTrack* ls = find_rotation(clip, s.find_joint("l_shoulder"));
  ASSERT_TRUE(lh && rh && ls);
  ASSERT_EQ(lh->values.size(), rh->values.size());
  float max_hip = 0.0f;
  for (std::size_t k = 0; k < lh->values.size(); ++k) {
    const float l = angle_about_x(lh->values[k]);
    EXPECT_NEAR(l + angle_about_x(rh->values[k]), 0.0f, 1e-4f);
    if (std::abs(l) > 0.05f) {
      EXPECT_LT(l * angle_about_x(ls->values[k]), 0.0f);
    }
    max_hip = std::max(max_hip, std::abs(l));
  }
  EXPECT_NEAR(max_hip, glm::radians(20.0f), 0.01f);
  // Root bobs ~2 cm.
  float lo = 1.0f, hi = -1.0f;
  for (const glm::vec3& p : clip.translations[0].values) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  EXPECT_NEAR(hi - lo, 0.02f, 0.005f);
}

TEST(DefaultSkeleton, RepositoryFileLoadsToTheSameResult) {
  const HumanoidAsset a = load_default_humanoid();
  const HumanoidAsset b = load_humanoid_file(kRepoDefault);
  EXPECT_NE(a.skeleton.source, b.skeleton.source);
  EXPECT_EQ(a.skeleton.joint_names, b.skeleton.joint_names);
  EXPECT_EQ(a.skeleton.parents, b.skeleton.parents);
  EXPECT_EQ(a.skeleton.centers, b.skeleton.centers);
  ASSERT_EQ(a.skeleton.limits.size(), b.skeleton.limits.size());
  for (std::size_t j = 0; j < a.skeleton.limits.size(); ++j) {
    EXPECT_EQ(a.skeleton.limits[j].lower, b.skeleton.limits[j].lower);
    EXPECT_EQ(a.skeleton.limits[j].upper, b.skeleton.limits[j].upper);
  }
  ASSERT_EQ(a.clips.size(), b.clips.size());
  EXPECT_EQ(a.clips[0].channel_count(), b.clips[0].channel_count());
  EXPECT_TRUE(a.skeleton.warnings.empty()) << a.skeleton.warnings.front();
}

// The default written out by hand in the paper's XML (string building here, not a writer in the library) must
// read back with the same names, tree, centres and limits.
TEST(PaperXml, DefaultSkeletonRoundTripsThroughPaperXml) {
  const Skeleton s = load_default_humanoid().skeleton;
  std::ostringstream xml;
  xml.precision(9);
  xml << "<Humanoid author='test'>\n<name>" << s.name << "</name>\n<center value='" << s.centers[0].x << ' '
      << s.centers[0].y << ' ' << s.centers[0].z << "'/>\n";
  std::vector<std::vector<std::size_t>> children(s.joint_count());
  for (std::size_t j = 1; j < s.joint_count(); ++j) children[s.parents[j]].push_back(j);
  auto write = [&](auto&& self, std::size_t j) -> void {
    const glm::vec3 c = s.centers[j];
    xml << "<Joint name='" << s.joint_names[j] << "' center='" << c.x << ' ' << c.y << ' ' << c.z << "'";
    if (s.limits[j].present) {
      const char* attr[3] = {"limitx", "limity", "limitz"};
      for (int a = 0; a < 3; ++a)
        xml << ' ' << attr[a] << "='" << s.limits[j].lower[a] << ' ' << s.limits[j].upper[a] << "'";
    }
    xml << ">\n";
    for (std::size_t k : children[j]) self(self, k);
    xml << "</Joint>\n";
  };
  write(write, 0);
  xml << "</Humanoid>\n";

  const HumanoidAsset back = load_humanoid_text(xml.str(), "roundtrip.xml");
  EXPECT_EQ(back.format, HumanoidFormat::PaperXml);
  EXPECT_EQ(back.skeleton.name, s.name);
  EXPECT_EQ(back.skeleton.joint_names, s.joint_names);
  EXPECT_EQ(back.skeleton.parents, s.parents);
  ASSERT_EQ(back.skeleton.centers.size(), s.centers.size());
  for (std::size_t j = 0; j < s.joint_count(); ++j) {
    EXPECT_EQ(back.skeleton.centers[j], s.centers[j]) << s.joint_names[j];
    EXPECT_EQ(back.skeleton.limits[j].present, s.limits[j].present);
    EXPECT_EQ(back.skeleton.limits[j].lower, s.limits[j].lower) << s.joint_names[j];
  }
}

TEST(PaperXml, LoadsFixtureWithLimitsSegmentsAndSites) {
  const HumanoidAsset asset = load_humanoid_file(fs::path(STRATA_TEST_DATA) / "paper_arm.xml");
  const Skeleton& s = asset.skeleton;
  EXPECT_EQ(asset.format, HumanoidFormat::PaperXml);
  EXPECT_EQ(s.name, "Little");
  ASSERT_EQ(s.joint_count(), 4u);
  EXPECT_EQ(s.joint_names, (std::vector<std::string>{"HumanoidRoot", "l_shoulder", "l_elbow", "l_wrist"}));
  EXPECT_EQ(s.parents, (std::vector<std::int32_t>{-1, 0, 1, 2}));
  EXPECT_FALSE(s.limits[0].present);
  const JointLimits& shoulder = s.limits[1];
  EXPECT_TRUE(shoulder.present);
  EXPECT_FLOAT_EQ(shoulder.lower.x, -1.0f);
  EXPECT_FLOAT_EQ(shoulder.upper.x, 3.0f);
  EXPECT_FLOAT_EQ(shoulder.lower.z, -1.0f);
  EXPECT_FLOAT_EQ(shoulder.upper.z, 1.3f);
  // limity not given: the axis keeps the unlimited default.
  EXPECT_EQ(shoulder.lower.y, JointLimits{}.lower.y);
  EXPECT_EQ(shoulder.upper.y, JointLimits{}.upper.y);
  const JointLimits& elbow = s.limits[2];
  EXPECT_TRUE(elbow.present);
  EXPECT_FLOAT_EQ(elbow.lower.x, -2.6f);
  EXPECT_FLOAT_EQ(elbow.upper.x, 0.0f);
  EXPECT_FLOAT_EQ(s.centers[2].y, 1.1357f);
  ASSERT_EQ(s.segments.size(), 2u);
  EXPECT_EQ(s.segments[1].name, "l_upperarm");
  EXPECT_EQ(s.segments[1].joint, 1);
  EXPECT_FLOAT_EQ(s.segments[1].mass, 2.1f);
  ASSERT_EQ(s.sites.size(), 1u);
  EXPECT_EQ(s.sites[0].joint, 3);
  EXPECT_FLOAT_EQ(s.sites[0].position.y, 0.6763f);
}

TEST(PaperXml, AcceptsAuthorAndNameAsAttributesAndTwentyNineteenNames) {
  const HumanoidAsset asset = load_humanoid_text(
      "<Humanoid name='Attr' author='me'><Joint name='humanoid_root' center='0 1 0'>"
      "<Joint name='l_hip' center='0.1 0.9 0'/></Joint></Humanoid>",
      "attr.xml");
  EXPECT_EQ(asset.skeleton.name, "Attr");
  EXPECT_EQ(asset.skeleton.joint_names[0], "HumanoidRoot");
  EXPECT_EQ(asset.skeleton.source_joint_names[0], "humanoid_root");
  EXPECT_EQ(asset.skeleton.naming, JointNaming::HAnim2019);
}

// ---- X3D features in memory ---------------------------------------------------------------------------------

TEST(X3d, SkinWeightsFansAndMismatchPolicy) {
  const std::string text =
      "<X3D><Scene>\n"                                                          // 1
      "<HAnimHumanoid name='h'>\n"                                              // 2
      " <Shape containerField='skin'><IndexedFaceSet coordIndex='0 1 2 3 -1 1 2 4'>"
      "<Coordinate DEF='C' point='0 0 0, 1 0 0, 1 1 0, 0 1 0, 2 2 2'/></IndexedFaceSet></Shape>\n"  // 3
      " <Coordinate USE='C' containerField='skinCoord'/>\n"                       // 4
      " <HAnimJoint DEF='R' name='HumanoidRoot' center='0 1 0' containerField='skeleton'\n"  // 5
      "   skinCoordIndex='0 1 2' skinCoordWeight='1 0.5 0.5 0.25'>\n"            // 6
      "  <HAnimJoint DEF='K' name='l_knee' center='0 0.5 0' skinCoordIndex='1 2'/>\n"  // 7
      "  <HAnimJoint DEF='E' name='l_elbow' center='0 1.2 0'/>\n"                // 8
      " </HAnimJoint>\n"                                                         // 9
      "</HAnimHumanoid></Scene></X3D>\n";
  const Skeleton s = load_humanoid_text(text, "skin.x3d").skeleton;
  ASSERT_EQ(s.joint_count(), 3u);
  EXPECT_EQ(s.skin_points.size(), 5u);
  // A quad fans into two triangles, the unterminated triangle is kept.
  EXPECT_EQ(s.skin_triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 2, 4}));
  EXPECT_EQ(s.skin_offsets, (std::vector<std::uint32_t>{0, 3, 5, 5}));
  ASSERT_EQ(s.skin_influences.size(), 5u);
  EXPECT_FLOAT_EQ(s.skin_influences[1].weight, 0.5f);
  EXPECT_EQ(s.skin_influences[3].vertex, 1u);
  EXPECT_FLOAT_EQ(s.skin_influences[3].weight, 1.0f);  // no skinCoordWeight: rigid
  EXPECT_TRUE(any_warning_contains(s, {"skin.x3d:5:", "HumanoidRoot", "3", "4"}));
}

TEST(X3d, AnimationClipsFromRoutes) {
  const std::string text = R"(<X3D><Scene>
<Transform><Group><HAnimHumanoid name='h'>
 <HAnimJoint DEF='R' name='HumanoidRoot' center='0 1 0' containerField='skeleton'>
  <HAnimJoint DEF='K' name='l_knee' center='0 0.5 0'/>
  <HAnimJoint DEF='E' name='l_elbow' center='0 1.2 0'/>
 </HAnimJoint>
</HAnimHumanoid></Group></Transform>
<TimeSensor DEF='Small' cycleInterval='4'/>
<TimeSensor DEF='Big' cycleInterval='2' loop='true'/>
<TimeSensor DEF='Idle' cycleInterval='3' loop='true'/>
<OrientationInterpolator DEF='Bend' key='0 0.5 1' keyValue='1 0 0 0, 2 0 0 1.0, 0 0 0 3'/>
<PositionInterpolator DEF='Bob' key='0 1' keyValue='0 0 0 0 0.1 0'/>
<OrientationInterpolator DEF='Unrouted' key='0 1' keyValue='1 0 0'/>
<ROUTE fromNode='Big' fromField='fraction_changed' toNode='Bend' toField='set_fraction'/>
<ROUTE fromNode='Bend' fromField='value_changed' toNode='K' toField='set_rotation'/>
<ROUTE fromNode='Bend' fromField='value_changed' toNode='E' toField='set_rotation'/>
<ROUTE fromNode='Big' fromField='fraction_changed' toNode='Bob' toField='set_fraction'/>
<ROUTE fromNode='Bob' fromField='value_changed' toNode='R' toField='set_translation'/>
<ROUTE fromNode='Small' fromField='fraction_changed' toNode='Bob' toField='set_fraction'/>
<ROUTE fromNode='Idle' fromField='fraction_changed' toNode='Unrouted' toField='set_fraction'/>
</Scene></X3D>)";
  const HumanoidAsset asset = load_humanoid_text(text, "anim.x3d");
  ASSERT_EQ(asset.clips.size(), 2u);  // Idle drives an interpolator that reaches no joint
  const AnimationClip& big = asset.clips[0];
  EXPECT_EQ(big.name, "Big");
  EXPECT_FLOAT_EQ(big.duration, 2.0f);
  EXPECT_TRUE(big.loop);
  ASSERT_EQ(big.rotations.size(), 2u);
  ASSERT_EQ(big.translations.size(), 1u);
  const RotationTrack& bend = big.rotations[0];
  EXPECT_EQ(bend.joint, 1);
  EXPECT_EQ(bend.times, (std::vector<float>{0.0f, 1.0f, 2.0f}));
  // The axis (2 0 0) is normalised; the zero axis gives identity.
  EXPECT_NEAR(bend.values[1].w, std::cos(0.5f), 1e-6f);
  EXPECT_NEAR(bend.values[1].x, std::sin(0.5f), 1e-6f);
  EXPECT_EQ(bend.values[2], glm::quat(1, 0, 0, 0));
  EXPECT_EQ(big.translations[0].joint, 0);
  EXPECT_FLOAT_EQ(big.translations[0].values[1].y, 0.1f);
  const AnimationClip& small = asset.clips[1];
  EXPECT_EQ(small.name, "Small");
  EXPECT_FALSE(small.loop);  // X3D's default
  EXPECT_EQ(small.translations[0].times.back(), 4.0f);
}

// ---- errors ---------------------------------------------------------------------------------------------------

const char* kOpen = "<X3D><Scene>\n<HAnimHumanoid name='h'>\n";  // lines 1-2
const char* kClose = "</HAnimHumanoid></Scene></X3D>\n";

TEST(LoadErrors, MalformedXml) {
  expect_load_error("<X3D><Scene>\n<HAnimHumanoid>\n<HAnimJoint name='a' center='0 0 0'>\n</X3D>\n", 4,
                    {"malformed XML", "X3D"});
}

TEST(LoadErrors, NoHumanoidAndUnknownRoot) {
  expect_load_error("<X3D>\n<Scene><Transform/></Scene></X3D>", 1, {"<X3D>", "no HAnimHumanoid"});
  expect_load_error("\n<Body/>", 2, {"<Body>", "unknown root element"});
}

TEST(LoadErrors, JointWithoutName) {
  expect_load_error(std::string(kOpen) + "<HAnimJoint DEF='J_x' center='0 0 0'/>\n" + kClose, 3,
                    {"J_x", "joint without name"});
}

TEST(LoadErrors, BadCentres) {
  expect_load_error(std::string(kOpen) + "<HAnimJoint DEF='J_k' name='l_knee' center='0 0.5'/>\n" + kClose, 3,
                    {"l_knee", "center has 2 numbers, expected 3"});
  expect_load_error(std::string(kOpen) + "\n<HAnimJoint name='l_knee' center='0 0.5 abc'/>\n" + kClose, 4,
                    {"l_knee", "center", "abc"});
  expect_load_error(std::string(kOpen) + "<HAnimJoint name='l_knee' center='0 nan 0'/>\n" + kClose, 3,
                    {"l_knee", "center", "nan"});
  expect_load_error(std::string(kOpen) + "<HAnimJoint name='l_knee'/>\n" + kClose, 3, {"l_knee", "missing center"});
  try {
    (void)load_humanoid_text("<Humanoid><Joint name='root' center='0 0 0'>\n<Joint name='l_hip'/></Joint></Humanoid>",
                             "paper.xml");
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("paper.xml:2: <Joint name='l_hip'>: missing center"), std::string::npos)
        << e.what();
  }
}

// An X3D child joint without centre (StandardHumanoid's toe tips) inherits its parent's, with a warning.
TEST(X3d, MissingCentreOfAChildInheritsTheParentsWithAWarning) {
  const Skeleton s = load_humanoid_text(std::string(kOpen) +
                                            "<HAnimJoint name='a' center='1 2 3'>\n"
                                            " <HAnimJoint name='toe'/>\n"
                                            "</HAnimJoint>\n" +
                                            kClose,
                                        "case.x3d")
                         .skeleton;
  ASSERT_EQ(s.joint_count(), 2u);
  EXPECT_EQ(s.centers[1], glm::vec3(1, 2, 3));
  EXPECT_TRUE(any_warning_contains(s, {"case.x3d:4:", "toe", "missing center"}));
}

TEST(LoadErrors, DuplicateDefUnknownUseAndCycle) {
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint DEF='A' name='a' center='0 0 0'>\n"
                        " <HAnimJoint DEF='A' name='b' center='0 0 0'/>\n"
                        "</HAnimJoint>\n" +
                        kClose,
                    4, {"name='b'", "duplicate DEF 'A'", "line 3"});
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint DEF='A' name='a' center='0 0 0'>\n"
                        " <HAnimJoint USE='Nope'/>\n"
                        "</HAnimJoint>\n" +
                        kClose,
                    4, {"USE='Nope'", "unknown DEF 'Nope'"});
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint DEF='A' name='a' center='0 0 0'>\n"
                        " <HAnimJoint DEF='B' name='b' center='0 0 0'>\n"
                        "  <HAnimJoint USE='A'/>\n"
                        " </HAnimJoint>\n"
                        "</HAnimJoint>\n" +
                        kClose,
                    5, {"USE='A'", "cycle", "'a'"});
}

TEST(LoadErrors, DuplicateJointNamesAndSecondRoot) {
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint name='a' center='0 0 0'>\n"
                        " <HAnimJoint DEF='X' name='a' center='0 1 0'/>\n"
                        "</HAnimJoint>\n" +
                        kClose,
                    4, {"DEF='X'", "duplicate joint name 'a'", "line 3"});
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint name='a' center='0 0 0'/>\n"
                        "<HAnimJoint name='b' center='0 0 0' containerField='skeleton'/>\n" +
                        kClose,
                    4, {"name='b'", "second skeleton root"});
}

TEST(LoadErrors, SkinIndexOutOfRange) {
  expect_load_error(std::string(kOpen) +
                        "<Coordinate DEF='C' point='0 0 0 1 1 1' containerField='skinCoord'/>\n"
                        "<HAnimJoint name='hip' center='0 0 0' skinCoordIndex='0 2' skinCoordWeight='1 1'/>\n" +
                        kClose,
                    4, {"name='hip'", "skinCoordIndex 2 out of range", "2 points"});
}

TEST(LoadErrors, BadLimits) {
  expect_load_error(std::string(kOpen) +
                        "<HAnimJoint name='knee' center='0 0 0' llimit='0 0 1' ulimit='1 1 0'/>\n" + kClose,
                    3, {"name='knee'", "about z", "lower 1 > upper 0"});
  expect_load_error(std::string(kOpen) + "<HAnimJoint name='knee' center='0 0 0' llimit='0 0'/>\n" + kClose, 3,
                    {"name='knee'", "llimit has 2 numbers"});
  try {
    (void)load_humanoid_text("<Humanoid>\n<Joint name='root' center='0 0 0'>\n"
                             "<Joint name='l_knee' center='0 1 0' limitx='2 -1'/></Joint></Humanoid>",
                             "paper.xml");
    ADD_FAILURE();
  } catch (const LoadError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("paper.xml:3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("l_knee"), std::string::npos) << msg;
    EXPECT_NE(msg.find("about x"), std::string::npos) << msg;
  }
}

TEST(LoadErrors, InterpolatorKeysAndValues) {
  const std::string humanoid = std::string(kOpen) + "<HAnimJoint DEF='R' name='r' center='0 0 0'/>\n" +
                               "</HAnimHumanoid>\n<TimeSensor DEF='T'/>\n";  // lines 3-5
  const std::string routes =
      "<ROUTE fromNode='T' fromField='fraction_changed' toNode='I' toField='set_fraction'/>\n"
      "<ROUTE fromNode='I' fromField='value_changed' toNode='R' toField='set_rotation'/>\n</Scene></X3D>";
  expect_load_error(humanoid + "<OrientationInterpolator DEF='I' key='0 1' keyValue='1 0 0 0 1 0 0 1 0 1 0'/>\n" +
                        routes,
                    6, {"DEF='I'", "key has 2 entries", "keyValue has 11 numbers"});
  expect_load_error(humanoid + "<OrientationInterpolator DEF='I' key='0 0.6 0.5' "
                               "keyValue='1 0 0 0 1 0 0 1 1 0 0 2'/>\n" +
                        routes,
                    6, {"DEF='I'", "keys decrease"});
  expect_load_error(humanoid + "<OrientationInterpolator DEF='I' key='0 1' keyValue='1 0 0 0 1 0 0 1'/>\n" +
                        "<ROUTE fromNode='T' fromField='fraction_changed' toNode='Gone' toField='set_fraction'/>\n"
                        "</Scene></X3D>",
                    7, {"ROUTE", "unknown node 'Gone'"});
}

TEST(LoadErrors, UnreadableFileNamesThePath) {
  const fs::path missing = fs::path(STRATA_TEST_DATA) / "does_not_exist.x3d";
  try {
    (void)load_humanoid_file(missing);
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

// ---- the real files ---------------------------------------------------------------------------------------------

TEST(RealFiles, JoeSkeletonSkinSiteSaluteWalk) {
  SKIP_WITHOUT_SHARED_DATA();
  const fs::path path = kHanimDir / "JoeSkeletonSkinSiteSaluteWalk.x3d";
  const HumanoidAsset asset = load_humanoid_file(path);
  const Skeleton& s = asset.skeleton;
  EXPECT_EQ(s.naming, JointNaming::HAnim1_1);
  ASSERT_EQ(s.joint_count(), 89u);
  EXPECT_EQ(s.joint_names[0], "HumanoidRoot");
  for (std::size_t j = 1; j < s.joint_count(); ++j) EXPECT_LT(s.parents[j], static_cast<std::int32_t>(j));
  EXPECT_EQ(s.segments.size(), 90u);
  EXPECT_EQ(s.sites.size(), 88u);
  EXPECT_EQ(s.centers[0], glm::vec3(0, 0.875f, 0));
  EXPECT_EQ(s.centers[s.find_joint("r_knee")], glm::vec3(-0.05f, 0.466f, 0));  // the file's asymmetry

  EXPECT_EQ(s.skin_points.size(), 390u);
  EXPECT_EQ(s.skin_triangles.size(), 3u * 695u);
  ASSERT_EQ(s.skin_offsets.size(), 90u);
  int weighted_joints = 0;
  std::set<std::uint32_t> vertices;
  for (std::size_t j = 0; j < 89; ++j) {
    if (s.skin_offsets[j + 1] > s.skin_offsets[j]) ++weighted_joints;
    for (std::uint32_t k = s.skin_offsets[j]; k < s.skin_offsets[j + 1]; ++k)
      vertices.insert(s.skin_influences[k].vertex);
  }
  EXPECT_EQ(weighted_joints, 69);
  EXPECT_EQ(vertices.size(), 351u);
  const std::int32_t elbow = s.find_joint("l_elbow");
  EXPECT_EQ(s.skin_offsets[elbow + 1] - s.skin_offsets[elbow], 12u);
  // Warnings: the 12-vs-15 list (l_elbow, line 1104) and the duplicated HumanoidRoot (line 1945).
  EXPECT_TRUE(any_warning_contains(s, {path.string() + ":1104:", "l_elbow", "12", "15"}));
  EXPECT_TRUE(any_warning_contains(s, {path.string() + ":1945:", "Joe_HumanoidRoot"}));

  // Clips, most channels first: Time2 (salute: vc6, 5 right-arm joints, 16 finger joints via r_handPitch,
  // thumb1..3 = 25), Time1 (walk: 18 rotations + 1 translation), Time3 (eyes: 2).
  ASSERT_EQ(asset.clips.size(), 3u);
  EXPECT_EQ(asset.clips[0].name, "Time2");
  EXPECT_EQ(asset.clips[0].channel_count(), 25u);
  const AnimationClip& walk = asset.clips[1];
  EXPECT_EQ(walk.name, "Time1");
  EXPECT_NEAR(walk.duration, 2.86f, 1e-5f);
  EXPECT_TRUE(walk.loop);
  EXPECT_EQ(walk.rotations.size(), 18u);
  ASSERT_EQ(walk.translations.size(), 1u);
  EXPECT_EQ(walk.translations[0].joint, 0);
  EXPECT_EQ(walk.translations[0].times.size(), 19u);
  for (const glm::vec3& p : walk.translations[0].values) {
    EXPECT_EQ(p.x, 0.0f);
    EXPECT_GE(p.y, -0.0750f);
    EXPECT_LE(p.y, -0.0019f);
  }
  EXPECT_EQ(asset.clips[2].name, "Time3");
  EXPECT_EQ(asset.clips[2].rotations.size(), 2u);
}

TEST(RealFiles, StandardHumanoid) {
  SKIP_WITHOUT_SHARED_DATA();
  const HumanoidAsset asset = load_humanoid_file(kHanimDir / "StandardHumanoid.x3d");
  const Skeleton& s = asset.skeleton;
  EXPECT_EQ(s.naming, JointNaming::HAnim2019);
  EXPECT_EQ(s.joint_count(), 146u);
  EXPECT_EQ(s.sites.size(), 118u);
  EXPECT_EQ(s.segments.size(), 119u);
  EXPECT_EQ(s.joint_names[0], "HumanoidRoot");
  EXPECT_EQ(s.source_joint_names[0], "humanoid_root");
  EXPECT_GE(s.find_joint("l_ankle"), 0);
  EXPECT_EQ(s.find_joint("l_ankle"), s.find_joint("l_talocrural"));
  EXPECT_EQ(s.find_joint("l_midtarsal"), s.find_joint("l_transversetarsal"));
  EXPECT_EQ(s.skin_triangles.size(), 3u * 695u);
  EXPECT_TRUE(s.skin_offsets.empty());  // unweighted skin
  EXPECT_TRUE(asset.clips.empty());
  // The two toe-tip joints written without a centre (lines 353 and 781) take their parents'.
  const std::int32_t toe = s.find_joint("l_tarsal_interphalangeal_1");
  ASSERT_GE(toe, 0);
  EXPECT_EQ(s.centers[toe], s.centers[s.parents[toe]]);
  EXPECT_TRUE(any_warning_contains(s, {":353:", "l_tarsal_interphalangeal_1", "missing center"}));
  EXPECT_TRUE(any_warning_contains(s, {":781:", "r_tarsal_interphalangeal_1", "missing center"}));
}

TEST(RealFiles, Humanoid1) {
  SKIP_WITHOUT_SHARED_DATA();
  const Skeleton s = load_humanoid_file(kHanimDir / "Humanoid1.x3d").skeleton;
  EXPECT_EQ(s.naming, JointNaming::HAnim2019);
  ASSERT_EQ(s.joint_count(), 18u);
  EXPECT_EQ(s.joint_names[0], "HumanoidRoot");
  EXPECT_EQ(s.source_joint_names[0], "humanoid_root");
  const std::int32_t ankle = s.find_joint("l_ankle");
  ASSERT_GE(ankle, 0);
  EXPECT_EQ(s.source_joint_names[ankle], "l_talocrural");
  EXPECT_EQ(s.centers[ankle], glm::vec3(0.1101f, 0.0656f, -0.0736f));
  EXPECT_EQ(s.source_joint_names[s.find_joint("r_wrist")], "r_radiocarpal");
  EXPECT_EQ(s.centers[s.find_joint("r_hip")], glm::vec3(-0.0950f, 0.9171f, 0.0029f));
  EXPECT_EQ(s.joint_names[s.parents[s.find_joint("l_shoulder")]], "vl5");
  EXPECT_EQ(s.segments.size(), 13u);
  EXPECT_EQ(s.sites.size(), 56u);
  const std::int32_t heel = s.find_site("l_calcaneus_posterior_pt");
  ASSERT_GE(heel, 0);
  EXPECT_EQ(s.sites[heel].position, glm::vec3(0.0974f, 0.0259f, -0.1171f));  // absolute
  EXPECT_EQ(s.joint_names[s.sites[heel].joint], "l_knee");
}

// ---- the humanoid's transform, units and DEF-only joints ------------------------------------------------------

// A small figure written in its own units: root at 40, hips at 40, knees at 20, ankles at 2, a skull_tip at 78.
std::string unit_figure(const std::string& humanoid_attributes, const std::string& head = "") {
  return "<X3D><head>" + head + "</head><Scene>\n<HAnimHumanoid name='u' " + humanoid_attributes + ">\n" +
         R"(<HAnimJoint DEF='R' name='HumanoidRoot' center='0 40 0' containerField='skeleton'>
 <HAnimJoint name='l_hip' center='4 40 0'><HAnimJoint name='l_knee' center='4 20 1'>
  <HAnimJoint name='l_ankle' center='4 2 0'/></HAnimJoint></HAnimJoint>
 <HAnimSite name='skull_tip' translation='0 78 0'/>
</HAnimJoint>
<Coordinate containerField='skinCoord' point='0 0 0 0 80 0 1 40 0'/>
<IndexedFaceSet containerField='skin' coordIndex='0 1 2 -1'/>
</HAnimHumanoid>
<TimeSensor DEF='T' cycleInterval='1'/>
<PositionInterpolator DEF='P' key='0 1' keyValue='0 0 0 10 0 0'/>
<OrientationInterpolator DEF='O' key='0 1' keyValue='0 1 0 0 0 1 0 0.5'/>
<ROUTE fromNode='T' fromField='fraction_changed' toNode='P' toField='set_fraction'/>
<ROUTE fromNode='T' fromField='fraction_changed' toNode='O' toField='set_fraction'/>
<ROUTE fromNode='P' fromField='value_changed' toNode='R' toField='set_translation'/>
<ROUTE fromNode='O' fromField='value_changed' toNode='R' toField='set_rotation'/>
</Scene></X3D>)";
}

void expect_vec_near(const glm::vec3& got, const glm::vec3& want, const char* what) {
  EXPECT_NEAR(got.x, want.x, 1e-5f) << what;
  EXPECT_NEAR(got.y, want.y, 1e-5f) << what;
  EXPECT_NEAR(got.z, want.z, 1e-5f) << what;
}

// The issue's giant: joint centres in the file's units and a humanoid scale that brings them to metres.
TEST(X3dHumanoidTransform, ScaleBringsTheFigureToMetres) {
  const HumanoidAsset a = load_humanoid_text(unit_figure("scale='0.0225 0.0225 0.0225'"), "scaled.x3d");
  const Skeleton& s = a.skeleton;
  expect_vec_near(s.centers[s.find_joint("l_knee")], glm::vec3(4, 20, 1) * 0.0225f, "knee");
  expect_vec_near(s.sites[s.find_site("skull_tip")].position, glm::vec3(0, 78, 0) * 0.0225f, "skull tip");
  expect_vec_near(s.skin_points[1], glm::vec3(0, 80, 0) * 0.0225f, "skin");
  // The root's animated translation is an offset: scaled, not moved. A uniform scale leaves rotations alone.
  expect_vec_near(a.clips.at(0).translations.at(0).values[1], glm::vec3(10, 0, 0) * 0.0225f, "translation key");
  EXPECT_NEAR(a.clips[0].rotations.at(0).values[1].y, std::sin(0.25f), 1e-6f);
  const RestStature st = rest_stature(s);
  EXPECT_NEAR(st.metres, 80 * 0.0225f, 1e-5f);
  EXPECT_STREQ(st.source, "skin");
}

// X3D Transform order: P' = T + C + R * S * (P - C). Scaled 0.01 about a centre at the hips, turned a quarter
// about +Y and lifted by 0.5: each point checked against that formula written out by hand.
TEST(X3dHumanoidTransform, TranslationRotationScaleAndCentreComposeAsX3dTransform) {
  const HumanoidAsset a = load_humanoid_text(
      unit_figure("scale='0.01 0.01 0.01' center='0 40 0' rotation='0 1 0 1.5707963' translation='0 0.5 0'"),
      "placed.x3d");
  const Skeleton& s = a.skeleton;
  // knee (4 20 1) - C = (4 -20 1); scaled (0.04 -0.2 0.01); +Y quarter turn maps (x, y, z) -> (z, y, -x).
  expect_vec_near(s.centers[s.find_joint("l_knee")], glm::vec3(0.01f, -0.2f, -0.04f) + glm::vec3(0, 40.5f, 0),
                  "knee");
  // The root's translation key turns with the figure; its rotation key (about +Y) commutes with a +Y turn.
  expect_vec_near(a.clips.at(0).translations.at(0).values[1], glm::vec3(0, 0, -0.1f), "translation key");
  EXPECT_NEAR(a.clips[0].rotations.at(0).values[1].y, std::sin(0.25f), 1e-5f);
}

// A Z-up file stood up by the humanoid's rotation: a rotation key about the file's +Z (its vertical) becomes one
// about our +Y, so an animated turn stays a turn about the vertical.
TEST(X3dHumanoidTransform, RotationKeysAreConjugatedIntoTheUprightFrame) {
  std::string text = unit_figure("scale='0.01 0.01 0.01' rotation='1 0 0 -1.5707963'");
  text.replace(text.find("0 1 0 0 0 1 0 0.5"), 17, "0 0 1 0 0 0 1 0.5");
  const HumanoidAsset a = load_humanoid_text(text, "zup.x3d");
  const glm::quat q = a.clips.at(0).rotations.at(0).values[1];
  EXPECT_NEAR(std::abs(q.y), std::sin(0.25f), 1e-5f);
  EXPECT_NEAR(q.x, 0.0f, 1e-5f);
  EXPECT_NEAR(q.z, 0.0f, 1e-5f);
  // The file's +Z (its up) is our +Y: the knee written at z = 1 is now 1 cm up... and the file's y went to -z.
  expect_vec_near(a.skeleton.centers[a.skeleton.find_joint("l_knee")], glm::vec3(0.04f, 0.01f, -0.2f), "knee");
}

// A mirroring scale keeps the skin's triangles facing out.
TEST(X3dHumanoidTransform, MirroringScaleRewindsTheSkinTriangles) {
  const Skeleton s = load_humanoid_text(unit_figure("scale='-0.01 0.01 0.01'"), "mirror.x3d").skeleton;
  EXPECT_EQ(s.skin_triangles, (std::vector<std::uint32_t>{0, 2, 1}));
  const Skeleton plain = load_humanoid_text(unit_figure("scale='0.01 0.01 0.01'"), "plain.x3d").skeleton;
  EXPECT_EQ(plain.skin_triangles, (std::vector<std::uint32_t>{0, 1, 2}));
  expect_load_error(unit_figure("scale='0.01 0 0.01'"), 2, {"<HAnimHumanoid", "scale has a zero component"});
}

TEST(X3dHumanoidTransform, NonUniformScaleWithAnimatedRotationsWarns) {
  const Skeleton s = load_humanoid_text(unit_figure("scale='0.01 0.02 0.01'"), "sheared.x3d").skeleton;
  EXPECT_TRUE(any_warning_contains(s, {"sheared.x3d:2:", "non-uniform scale"}));
  const Skeleton u = load_humanoid_text(unit_figure("scale='0.01 0.01 0.01'"), "even.x3d").skeleton;
  EXPECT_FALSE(any_warning_contains(u, {"non-uniform"}));
}

// X3D 3.3's UNIT statement: lengths in inches (and angles in degrees) are read into metres (and radians), and the
// humanoid's scale applies on top.
TEST(X3dUnits, LengthAndAngleUnitsAreHonoured) {
  const std::string inches = "<unit category='length' name='inch' conversionFactor='0.0254'/>";
  const HumanoidAsset a = load_humanoid_text(unit_figure("", inches), "inches.x3d");
  expect_vec_near(a.skeleton.centers[a.skeleton.find_joint("l_knee")], glm::vec3(4, 20, 1) * 0.0254f, "knee");
  EXPECT_NEAR(rest_stature(a.skeleton).metres, 80 * 0.0254f, 1e-5f);
  const HumanoidAsset halved = load_humanoid_text(unit_figure("scale='0.5 0.5 0.5'", inches), "half.x3d");
  EXPECT_NEAR(rest_stature(halved.skeleton).metres, 40 * 0.0254f, 1e-5f);

  std::string degrees = unit_figure("", "<unit category='angle' name='degree' conversionFactor='0.017453293'/>");
  degrees.replace(degrees.find("0 1 0 0.5"), 9, "0 1 0 90");
  const HumanoidAsset d = load_humanoid_text(degrees, "degrees.x3d");
  EXPECT_NEAR(d.clips.at(0).rotations.at(0).values[1].y, std::sin(0.25f * 3.14159265f), 1e-5f);

  expect_load_error(unit_figure("", "\n<unit category='length' name='x' conversionFactor='-1'/>"), 2,
                    {"<unit", "conversionFactor must be a positive number"});
}

// Web3D examples with joints that carry only a DEF: the name is the H-Anim joint name the DEF ends in.
TEST(X3d, JointWithOnlyADefTakesItsHanimNameFromTheDef) {
  const Skeleton s = load_humanoid_text(std::string(kOpen) +
                                            "<HAnimJoint DEF='hanim_humanoid_root' center='0 1 0'>\n"
                                            " <HAnimJoint DEF='Joe_l_hip' center='0.1 0.9 0'>\n"
                                            "  <HAnimJoint DEF='x_l_thumb2' center='0.1 0.5 0'/>\n"
                                            " </HAnimJoint>\n"
                                            " <HAnimJoint DEF='hanim_vt12' center='0 1.1 0'/>\n"
                                            "</HAnimJoint>\n" +
                                            kClose,
                                        "defs.x3d")
                        .skeleton;
  EXPECT_EQ(s.source_joint_names,
            (std::vector<std::string>{"humanoid_root", "l_hip", "l_thumb2", "vt12"}));
  EXPECT_EQ(s.joint_names[0], "HumanoidRoot");
  EXPECT_TRUE(any_warning_contains(s, {"defs.x3d:4:", "Joe_l_hip", "named 'l_hip' after its DEF"}));
  // Ambiguous: the DEF reads as a name another joint already has.
  expect_load_error(std::string(kOpen) + "<HAnimJoint name='l_hip' center='0 1 0'>\n" +
                        "<HAnimJoint DEF='other_l_hip' center='0 1 0'/></HAnimJoint>\n" + kClose,
                    4, {"other_l_hip", "reads as 'l_hip'", "line 3 already has"});
  // Not a joint name: vt13 does not exist, l_index4 neither.
  expect_load_error(std::string(kOpen) + "<HAnimJoint DEF='h_vt13' center='0 1 0'/>\n" + kClose, 3,
                    {"h_vt13", "does not end in an H-Anim joint name"});
  EXPECT_FALSE(is_hanim_joint_name("l_index4"));
  EXPECT_FALSE(is_hanim_joint_name("vl0"));
  EXPECT_TRUE(is_hanim_joint_name("r_index0"));
  EXPECT_TRUE(is_hanim_joint_name("r_tarsometatarsal_2"));
  EXPECT_TRUE(is_hanim_joint_name("l_eyeball_joint"));
  EXPECT_FALSE(is_hanim_joint_name("l_thumb0"));
}

// `strata info`'s stature on the shipped default (skull_tip) and on a skeleton without a skull site.
TEST(RestStature, FromTheSkullTipElseTheTopJointPlusAHead) {
  const Skeleton s = load_default_humanoid().skeleton;
  const RestStature st = rest_stature(s);
  EXPECT_STREQ(st.source, "skull_tip");
  EXPECT_GT(st.metres, 1.6f);
  EXPECT_LT(st.metres, 1.9f);
  const Skeleton bare = load_humanoid_text(std::string(kOpen) +
                                               "<HAnimJoint name='HumanoidRoot' center='0 1 0'>\n"
                                               "<HAnimJoint name='skullbase' center='0 1.6 0'/>\n"
                                               "<HAnimJoint name='l_ankle' center='0.1 0.1 0'/></HAnimJoint>\n" +
                                               kClose,
                                           "bare.x3d")
                           .skeleton;
  EXPECT_NEAR(rest_stature(bare).metres, 1.6f + 0.13f - 0.1f, 1e-5f);
  EXPECT_STREQ(rest_stature(bare).source, "joints");
}


// An LOA-1 style figure built from rigid segment meshes and no skin: the meshes become the skin, each vertex
// weighted 1 to its segment's joint, with Transforms applied and faces wound outward.
TEST(X3dSegments, SegmentMeshesBecomeARigidSkin) {
  const std::string text = R"(<X3D><Scene>
<HAnimHumanoid name='loa1'>
 <HAnimJoint name='HumanoidRoot' center='0 1 0' containerField='skeleton'>
  <HAnimSegment name='pelvis'>
   <Transform translation='0 1 0' scale='2 2 2'>
    <Shape><Appearance/><IndexedFaceSet coordIndex='0 1 2 3 -1'>
     <Coordinate point='-0.1 0 0 0.1 0 0 0.1 0.1 0 -0.1 0.1 0'/></IndexedFaceSet></Shape>
   </Transform>
  </HAnimSegment>
  <HAnimJoint name='l_hip' center='0.1 0.9 0'>
   <HAnimSegment name='l_thigh'>
    <Group><Shape><IndexedTriangleSet index='0 1 2' ccw='false'>
     <Coordinate point='0.1 0.9 0 0.1 0.5 0 0.12 0.5 0.02'/></IndexedTriangleSet></Shape></Group>
    <Shape><IndexedLineSet coordIndex='0 1'><Coordinate point='0 0 0 1 1 1'/></IndexedLineSet></Shape>
   </HAnimSegment>
  </HAnimJoint>
 </HAnimJoint>
</HAnimHumanoid></Scene></X3D>)";
  const Skeleton s = load_humanoid_text(text, "loa1.x3d").skeleton;
  ASSERT_EQ(s.skin_points.size(), 7u);
  // The pelvis quad: scaled 2 and lifted 1 by its Transform, a fan of two triangles.
  expect_vec_near(s.skin_points[1], glm::vec3(0.2f, 1.0f, 0.0f), "pelvis corner");
  expect_vec_near(s.skin_points[2], glm::vec3(0.2f, 1.2f, 0.0f), "pelvis corner");
  // ccw='false' is rewound: 4 5 6 becomes 4 6 5.
  EXPECT_EQ(s.skin_triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 4, 6, 5}));
  ASSERT_EQ(s.skin_offsets.size(), 3u);
  EXPECT_EQ(s.skin_offsets[1] - s.skin_offsets[0], 4u);  // the root carries the pelvis
  EXPECT_EQ(s.skin_offsets[2] - s.skin_offsets[1], 3u);  // l_hip the thigh
  for (const SkinInfluence& inf : s.skin_influences) EXPECT_EQ(inf.weight, 1.0f);
  EXPECT_EQ(s.skin_influences[s.skin_offsets[1]].vertex, 4u);
  EXPECT_TRUE(any_warning_contains(s, {"lines, primitives", "not drawn"}));
  // Bad segment geometry is named like every other error.
  std::string bad = text;
  bad.replace(bad.find("index='0 1 2'"), 13, "index='0 1 7'");
  expect_load_error(bad, 12, {"IndexedTriangleSet", "index 7 out of range (the segment mesh has 3 points)"});
}

}  // namespace
}  // namespace strata
