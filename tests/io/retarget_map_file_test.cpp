// The retarget map file (io/retarget_map_file.h): rows, comments, 2019 names, and every bad input named by line.
#include <gtest/gtest.h>

#include <string>

#include "io/load_error.h"
#include "io/retarget_map_file.h"

namespace strata {
namespace {

const std::string kLegs =
    "Root HumanoidRoot\nLT l_hip\nLK l_knee\nLA l_ankle\nRT r_hip\nRK r_knee\nRA r_ankle\n";

void expect_error(const std::string& text, const std::string& needle) {
  try {
    (void)parse_retarget_map(text, "m.txt");
    ADD_FAILURE() << "no LoadError for:\n" << text;
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(RetargetMapFile, RowsCommentsAndBothNamingGenerations) {
  const RetargetMapFile m = parse_retarget_map(
      "# capture from the lab\n\n" + kLegs + "  Chest\tvt6   # the upper back\nLF l_transversetarsal\r\n", "m.txt");
  ASSERT_EQ(m.rows.size(), 9u);
  EXPECT_EQ(m.source, "m.txt");
  EXPECT_EQ(m.rows[0].bvh, "Root");
  EXPECT_EQ(m.rows[0].line, 3);
  EXPECT_EQ(m.rows[7].bvh, "Chest");
  EXPECT_EQ(m.rows[7].hanim, "vt6");
  EXPECT_EQ(m.rows[8].hanim, "l_transversetarsal");  // 2019's l_midtarsal, kept as written
}

TEST(RetargetMapFile, BadRowsAreNamedByLine) {
  expect_error(kLegs + "Chest vt6 extra\n", "m.txt:8: expected 'BVH_JOINT H-ANIM_JOINT', got 3 words");
  expect_error(kLegs + "Finger l_index1\n", "m.txt:8: 'l_index1' is not a joint retargeting drives");
  expect_error(kLegs + "LT vt6\n", "m.txt:8: BVH joint 'LT' is mapped twice (first at line 2)");
  expect_error(kLegs + "Other l_knee\n", "m.txt:8: H-Anim joint 'l_knee' is mapped twice (first at line 3)");
  expect_error(kLegs + "Other l_talocrural\n", "H-Anim joint 'l_talocrural' is mapped twice (first at line 4)");
  expect_error("Root HumanoidRoot\nLT l_hip\n", "m.txt:2: the map leaves out l_knee, l_ankle, r_hip, r_knee, r_ankle");
  expect_error("", "the map leaves out HumanoidRoot");
  try {
    (void)load_retarget_map_file("/nonexistent/map.txt");
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/map.txt: cannot open file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
