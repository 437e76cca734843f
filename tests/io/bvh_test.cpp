// BVH reader: the real CMU walk (counts checked independently with grep/awk on the file), CRLF equivalence, the
// rotation convention, and one malformed input per error the reader reports.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "io/bvh.h"

namespace strata {
namespace {

const std::filesystem::path kWalk = std::filesystem::path(STRATA_SHARED_DATA) / "cmu_mocap_bvh" / "02_02_daz.bvh";

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A two-joint hierarchy whose pieces the error tests break one at a time.
std::string small_bvh(const std::string& root_channels = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                      const std::string& frames = "2", const std::string& line0 = "1 2 3 10 20 30 0 0 90",
                      const std::string& line1 = "4 5 6 0 0 0 -0.0 1e1 -2.5E-1", const std::string& tail = "}") {
  return "HIERARCHY\nROOT hips\n{\n  OFFSET 0 0 0\n  " + root_channels +
         "\n  JOINT knee\n  {\n    OFFSET 0 -10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
         "    End Site\n    {\n      OFFSET 0 -5 1\n    }\n  }\n" + tail +
         "\nMOTION\nFrames: " + frames + "\nFrame Time: 0.5\n" + line0 + "\n" + line1 + "\n";
}

std::string error_of(const std::string& text) {
  try {
    load_bvh_text(text, "bad.bvh");
  } catch (const LoadError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(BvhLoader, RealWalkCountsAndHeader) {
  if (!std::filesystem::exists(kWalk)) GTEST_SKIP() << "no shared data at " << kWalk;
  const BvhMotion m = load_bvh_file(kWalk);
  // grep -c JOINT = 42, plus ROOT; grep -c "End Site" = 14; 299 lines after "Frame Time:"; awk sum of CHANNELS counts.
  EXPECT_EQ(m.joint_count(), 43u);
  EXPECT_EQ(m.end_site_count(), 14u);
  EXPECT_EQ(m.frame_count, 299u);
  EXPECT_EQ(m.channel_count, 132u);
  EXPECT_EQ(m.values.size(), 299u * 132u);
  EXPECT_NEAR(m.frame_time, 0.00833333f, 1e-9f);
  EXPECT_EQ(m.source, "02_02_daz.bvh");

  ASSERT_EQ(m.joints[0].name, "hip");
  EXPECT_EQ(m.joints[0].parent, -1);
  const std::vector<BvhChannel> root_order = {BvhChannel::Xposition, BvhChannel::Yposition, BvhChannel::Zposition,
                                              BvhChannel::Zrotation, BvhChannel::Yrotation, BvhChannel::Xrotation};
  EXPECT_EQ(m.joints[0].channels, root_order);
  const std::int32_t shoulder = m.find_joint("lShldr");
  ASSERT_GE(shoulder, 0);
  const std::vector<BvhChannel> joint_order = {BvhChannel::Zrotation, BvhChannel::Xrotation, BvhChannel::Yrotation};
  EXPECT_EQ(m.joints[shoulder].channels, joint_order);
  EXPECT_EQ(m.joints[shoulder].first_channel, 69u) << "awk: CHANNELS before lShldr sum to 69";
  EXPECT_EQ(m.joints[m.joints[shoulder].parent].name, "lCollar");
  EXPECT_NEAR(m.joints[shoulder].offset.x, 8.77824f, 1e-5f);
  const std::int32_t foot = m.find_joint("lFoot");
  ASSERT_GE(foot, 0);
  EXPECT_TRUE(m.joints[foot].has_end_site);
  EXPECT_NEAR(m.joints[foot].end_site.z, 12.103f, 1e-5f);
  for (std::size_t j = 1; j < m.joint_count(); ++j) EXPECT_LT(m.joints[j].parent, static_cast<std::int32_t>(j));

  // Values straight from the file: frame 1 starts "50.8216 76.9281 -218.854", the last frame "56.8287 85.6058
  // 174.92" and ends "... 4.91025"; frame 0 carries "-5.35001e-15" and "-0.0".
  EXPECT_FLOAT_EQ(m.frame(1)[0], 50.8216f);
  EXPECT_FLOAT_EQ(m.frame(1)[2], -218.854f);
  EXPECT_FLOAT_EQ(m.frame(298)[1], 85.6058f);
  EXPECT_FLOAT_EQ(m.frame(298)[131], 4.91025f);
  EXPECT_FLOAT_EQ(m.frame(0)[12], -5.35001e-15f);
  EXPECT_EQ(m.frame(0)[18], 0.0f);
  EXPECT_TRUE(std::signbit(m.frame(0)[18])) << "-0.0 keeps its sign";
  EXPECT_EQ(m.root_translation(298), glm::vec3(56.8287f, 85.6058f, 174.92f));
}

TEST(BvhLoader, CrlfCopyLoadsIdentically) {
  if (!std::filesystem::exists(kWalk)) GTEST_SKIP() << "no shared data at " << kWalk;
  const std::string lf = read_text(kWalk);
  std::string crlf;
  crlf.reserve(lf.size() + lf.size() / 20);
  for (char c : lf) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  ASSERT_GT(crlf.size(), lf.size());
  const BvhMotion a = load_bvh_text(lf, "walk");
  const BvhMotion b = load_bvh_text(crlf, "walk");
  ASSERT_EQ(a.joint_count(), b.joint_count());
  for (std::size_t j = 0; j < a.joint_count(); ++j) {
    EXPECT_EQ(a.joints[j].name, b.joints[j].name) << "a CR must not stick to a joint name";
    EXPECT_EQ(a.joints[j].parent, b.joints[j].parent);
    EXPECT_EQ(a.joints[j].offset, b.joints[j].offset);
    EXPECT_EQ(a.joints[j].channels, b.joints[j].channels);
    EXPECT_EQ(a.joints[j].end_site, b.joints[j].end_site);
  }
  EXPECT_EQ(a.frame_time, b.frame_time);
  EXPECT_EQ(a.values, b.values);
}

TEST(BvhLoader, RotationIsProductInListedOrder) {
  const BvhMotion m = load_bvh_text(small_bvh(), "small.bvh");
  ASSERT_EQ(m.joint_count(), 2u);
  EXPECT_EQ(m.frame_count, 2u);
  EXPECT_EQ(m.channel_count, 9u);
  EXPECT_FLOAT_EQ(m.frame_time, 0.5f);
  EXPECT_FLOAT_EQ(m.duration(), 0.5f);
  EXPECT_EQ(m.joints[1].first_channel, 6u);
  // Root lists Z, X, Y: 10 deg about Z, then 20 about X, then 30 about Y, composed as Rz * Rx * Ry.
  const glm::mat4 expected = glm::rotate(glm::rotate(glm::rotate(glm::mat4(1.0f), glm::radians(10.0f), {0, 0, 1}),
                                                     glm::radians(20.0f), {1, 0, 0}),
                                         glm::radians(30.0f), {0, 1, 0});
  const glm::mat3 got = m.local_rotation_matrix(0, 0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(got[c][r], expected[c][r], 1e-6f) << c << "," << r;
  // The same numbers in another order give another rotation (X first): the order is really read per joint.
  const BvhMotion xzy = load_bvh_text(
      small_bvh("CHANNELS 6 Xposition Yposition Zposition Xrotation Zrotation Yrotation", "2",
                "1 2 3 20 10 30 0 0 90"),
      "xzy.bvh");
  const glm::mat4 xfirst = glm::rotate(glm::rotate(glm::rotate(glm::mat4(1.0f), glm::radians(20.0f), {1, 0, 0}),
                                                   glm::radians(10.0f), {0, 0, 1}),
                                       glm::radians(30.0f), {0, 1, 0});
  const glm::mat3 got_xzy = xzy.local_rotation_matrix(0, 0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(got_xzy[c][r], xfirst[c][r], 1e-6f);
  EXPECT_GT(std::abs(got_xzy[0][1] - got[0][1]) + std::abs(got_xzy[2][0] - got[2][0]), 1e-3f);

  // Translations, rest positions and the posed chain: knee Y rotation of 90 deg turns the end-site offset
  // (0, -5, 1) into (1, -5, 0) relative to the knee (before the root's rotation).
  EXPECT_EQ(m.root_translation(1), glm::vec3(4, 5, 6));
  const std::vector<glm::vec3> rest = m.rest_positions();
  EXPECT_EQ(rest[1], glm::vec3(0, -10, 0));
  std::vector<glm::quat> rot(2);
  std::vector<glm::vec3> pos(2);
  m.pose(0, rot, pos);
  EXPECT_EQ(pos[0], glm::vec3(1, 2, 3));
  const glm::vec3 knee_expected = glm::vec3(1, 2, 3) + glm::mat3(expected) * glm::vec3(0, -10, 0);
  EXPECT_NEAR(glm::length(pos[1] - knee_expected), 0.0f, 1e-5f);
  const glm::vec3 tip_local = glm::mat3_cast(m.local_rotation(1, 0)) * m.joints[1].end_site;
  EXPECT_NEAR(tip_local.x, 1.0f, 1e-5f);
  EXPECT_NEAR(tip_local.y, -5.0f, 1e-5f);
  EXPECT_NEAR(tip_local.z, 0.0f, 1e-5f);
  EXPECT_FLOAT_EQ(m.frame(1)[7], 10.0f) << "exponent notation";
  EXPECT_FLOAT_EQ(m.frame(1)[8], -0.25f);
}

TEST(BvhLoader, TabsAndNamesWithSpaces) {
  std::string text = small_bvh();
  text.replace(text.find("ROOT hips"), 9, "ROOT\tLeft  Hip ");
  text.replace(text.find("Frames: "), 8, "Frames:\t");
  const BvhMotion m = load_bvh_text(text, "tabs.bvh");
  EXPECT_EQ(m.joints[0].name, "Left Hip");
  EXPECT_EQ(m.frame_count, 2u);
}

TEST(BvhLoaderErrors, MissingKeywords) {
  std::string no_hierarchy = small_bvh();
  no_hierarchy.replace(0, 9, "SKELETON");
  EXPECT_EQ(error_of(no_hierarchy), "bad.bvh:1: expected HIERARCHY, found 'SKELETON'");

  std::string no_channels = small_bvh();
  no_channels.replace(no_channels.find("CHANNELS 3"), 10, "CHANELS 3");
  EXPECT_EQ(error_of(no_channels), "bad.bvh:9: expected CHANNELS, found 'CHANELS'");

  std::string no_offset = small_bvh();
  no_offset.replace(no_offset.find("OFFSET 0 -10 0"), 14, "");
  EXPECT_NE(error_of(no_offset).find("bad.bvh:9: expected OFFSET, found 'CHANNELS'"), std::string::npos) << error_of(no_offset);

  std::string no_motion = small_bvh();
  no_motion.replace(no_motion.find("MOTION"), 6, "MOTON");
  EXPECT_EQ(error_of(no_motion), "bad.bvh:16: expected MOTION, found 'MOTON'");

  std::string no_time = small_bvh();
  no_time.replace(no_time.find("Frame Time:"), 11, "FrameTime:");
  EXPECT_EQ(error_of(no_time), "bad.bvh:18: expected 'Frame Time:', found 'FrameTime:'");

  std::string cut = small_bvh();
  cut.resize(cut.find("MOTION"));
  EXPECT_EQ(error_of(cut), "bad.bvh:15: unexpected end of file, expected MOTION");
}

TEST(BvhLoaderErrors, WrongValueCountNamesTheFrameLine) {
  EXPECT_EQ(error_of(small_bvh(
                "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "2", "1 2 3 10 20 30 0 0 90",
                "4 5 6 0 0 0 0 1")),
            "bad.bvh:20: frame 1 has 8 values, expected 9");
}

TEST(BvhLoaderErrors, UnknownChannel) {
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Wrotation Yrotation")),
            "bad.bvh:5: unknown channel 'Wrotation'");
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation")),
            "bad.bvh:5: CHANNELS lists 5 names, expected 6");
}

TEST(BvhLoaderErrors, UnbalancedBraces) {
  // A missing '}' runs into MOTION while the root is still open; an extra one closes nothing.
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "2",
                               "1 2 3 10 20 30 0 0 90", "4 5 6 0 0 0 -0.0 1e1 -2.5E-1", "")),
            "bad.bvh:16: unbalanced braces: MOTION before joint 'hips' is closed");
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "2",
                               "1 2 3 10 20 30 0 0 90", "4 5 6 0 0 0 -0.0 1e1 -2.5E-1", "}\n}")),
            "bad.bvh:16: unbalanced braces: '}' without a matching '{'");
}

TEST(BvhLoaderErrors, NonNumericValues) {
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "2",
                               "1 2 3 10 2O 30 0 0 90")),
            "bad.bvh:19: frame 0: '2O' is not a finite number");
  std::string bad_offset = small_bvh();
  bad_offset.replace(bad_offset.find("OFFSET 0 -10 0"), 14, "OFFSET 0 -1x 0");
  EXPECT_EQ(error_of(bad_offset), "bad.bvh:8: OFFSET: '-1x' is not a finite number");
  EXPECT_EQ(error_of(small_bvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "2",
                               "1 2 3 10 nan 30 0 0 90")),
            "bad.bvh:19: frame 0: 'nan' is not a finite number");
}

TEST(BvhLoaderErrors, FrameCountMismatch) {
  const std::string ch = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation";
  EXPECT_EQ(error_of(small_bvh(ch, "3")), "bad.bvh:20: 'Frames: 3' but 2 motion lines");
  EXPECT_EQ(error_of(small_bvh(ch, "1")), "bad.bvh:20: more motion lines than 'Frames: 1'");
  EXPECT_EQ(error_of(small_bvh(ch, "2.5")), "bad.bvh:17: frame count must be a non-negative integer, found '2.5'");
}

TEST(BvhLoaderErrors, MissingFileNamesIt) {
  try {
    load_bvh_file("/nonexistent/walk.bvh");
    FAIL() << "no error";
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/walk.bvh: cannot open file"), std::string::npos);
  }
}

}  // namespace
}  // namespace strata
