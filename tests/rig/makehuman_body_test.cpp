// The MakeHuman-derived default body (rig/makehuman_body.h) and its shipped source (io/makehuman_pack.h): the
// pack's round trip and bad input, the shipped file against a fresh pack of ../shared/data's hm08 folder, and the
// derived levels: exact budgets, closed 2-manifolds, 53 parts, fitted to the skeleton (crown, feet on the sites,
// hands clear of the thighs), following another skeleton's size, deterministic.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "io/hanim_loader.h"
#include "io/load_error.h"
#include "io/makehuman.h"
#include "io/makehuman_pack.h"
#include "io/mesh_check.h"
#include "rig/makehuman_body.h"
#include "rig/surface_simplify.h"

namespace strata {
namespace {

const std::filesystem::path kMakeHuman = std::filesystem::path(STRATA_SHARED_DATA) / "makehuman_hm08";

const MakeHumanSource& source() {
  static const MakeHumanSource s = shipped_makehuman_source();
  return s;
}

glm::vec3 site(const Skeleton& s, const char* name) {
  for (const SkeletonSite& site : s.sites)
    if (site.name == name) return site.position;
  ADD_FAILURE() << "no site " << name;
  return glm::vec3(0.0f);
}

bool is_part(const Mesh& m, std::size_t v, std::initializer_list<const char*> names) {
  const std::string& part = m.part_names[m.part[v]];
  for (const char* n : names)
    if (part == n) return true;
  return false;
}

// ---- The pack ----------------------------------------------------------------------------------------------------

TEST(MakeHumanPack, ShippedSourceIsTheClosedHm08Body) {
  const MakeHumanSource& s = source();
  EXPECT_EQ(s.positions.size(), 13380u);
  EXPECT_EQ(s.triangles.size(), 3u * 26756u);
  EXPECT_TRUE(is_closed_manifold(s.triangles, s.positions.size())) << "the hm08 body group is closed, genus 0";
  EXPECT_EQ(s.joint_centers.size(), load_default_humanoid().skeleton.joint_count());
  std::set<std::uint16_t> parts(s.part.begin(), s.part.end());
  EXPECT_EQ(parts.size(), 53u);
  for (std::size_t v = 0; v < s.positions.size(); ++v) {
    float sum = 0.0f;
    for (float w : s.skin.weights[v]) sum += w;
    ASSERT_NEAR(sum, 1.0f, 1e-5f) << v;
  }
}

TEST(MakeHumanPack, RoundTripKeepsTopologyPartsAndQuantisedGeometry) {
  const MakeHumanSource& s = source();
  const MakeHumanSource back = unpack_makehuman_source(pack_makehuman_source(s), "round trip");
  EXPECT_EQ(back.triangles, s.triangles);
  EXPECT_EQ(back.part, s.part);
  EXPECT_EQ(back.skin.joints, s.skin.joints);
  ASSERT_EQ(back.positions.size(), s.positions.size());
  for (std::size_t v = 0; v < s.positions.size(); ++v) {
    // Re-quantising quantised values lands on the same steps: 0.03 mm at most, and in practice exact.
    ASSERT_LT(glm::length(back.positions[v] - s.positions[v]), 5e-5f) << v;
    for (int k = 0; k < kMaxInfluences; ++k) ASSERT_NEAR(back.skin.weights[v][k], s.skin.weights[v][k], 2.0f / 255.0f);
  }
  EXPECT_EQ(back.joint_centers, s.joint_centers);
}

TEST(MakeHumanPack, ShippedFileIsAFreshPackOfTheSharedFolder) {
  if (!std::filesystem::exists(kMakeHuman / "base.obj")) GTEST_SKIP() << "test data absent: " << kMakeHuman;
  const MakeHumanSource fresh = unpack_makehuman_source(
      pack_makehuman_source(makehuman_source_from(load_makehuman(kMakeHuman))), "fresh");
  const MakeHumanSource& shipped = source();
  EXPECT_EQ(fresh.positions, shipped.positions) << "rerun build/strata_pack_makehuman (apps/pack_makehuman.cpp)";
  EXPECT_EQ(fresh.triangles, shipped.triangles);
  EXPECT_EQ(fresh.part, shipped.part);
  EXPECT_EQ(fresh.skin.joints, shipped.skin.joints);
  EXPECT_EQ(fresh.skin.weights, shipped.skin.weights);
  EXPECT_EQ(fresh.joint_centers, shipped.joint_centers);
  EXPECT_EQ(fresh.corner_uvs, shipped.corner_uvs);
}

// The raw (inflated) stream of a packed file, and a file around a raw stream.
std::string raw_of(const std::string& packed) {
  std::uint32_t raw_size = 0;
  std::memcpy(&raw_size, packed.data() + 8, 4);
  std::string raw(raw_size, '\0');
  uLongf got = raw_size;
  EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(raw.data()), &got,
                       reinterpret_cast<const Bytef*>(packed.data() + 16), static_cast<uLong>(packed.size() - 16)),
            Z_OK);
  return raw;
}
std::string repacked(const char* magic, const std::string& raw) {
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string z(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                      static_cast<uLong>(raw.size()), 9),
            Z_OK);
  z.resize(size);
  std::string out(magic, 8);
  const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(raw.size()), static_cast<std::uint32_t>(size)};
  out.append(reinterpret_cast<const char*>(sizes), sizeof sizes);
  return out + z;
}
// Where a packed file's texture coordinate section starts in its raw stream (the format in io/makehuman_pack.h:
// counts, box, joint centres, positions, triangles, parts, influence joints and weights before it), and its
// count of extra (seam) texture coordinates.
std::size_t uv_section_at(const MakeHumanSource& s) {
  const std::size_t n = s.positions.size(), t = s.triangles.size() / 3, j = s.joint_centers.size();
  return 12 + 24 + 12 * j + 6 * n + 6 * t + n + 4 * n + 4 * n;
}
std::uint32_t seam_extras(const std::string& packed) {
  std::uint32_t extras = 0;
  std::memcpy(&extras, raw_of(packed).data() + uv_section_at(source()), 4);
  return extras;
}

TEST(MakeHumanPack, BadInputIsOneLineNamingTheSourceAndWhatIsWrong) {
  const std::string good = pack_makehuman_source(source());
  auto expect_error = [](const std::string& bytes, const std::string& needle) {
    try {
      (void)unpack_makehuman_source(bytes, "body.bin");
      ADD_FAILURE() << "no error for " << needle;
    } catch (const LoadError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("body.bin: ", 0), 0u) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_error("", "truncated");
  expect_error("STMHPK09" + good.substr(8), "bad magic");
  expect_error(good.substr(0, good.size() - 10), "the header says");
  std::string corrupt = good;
  for (std::size_t i = 40; i < 80; ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
  expect_error(corrupt, "corrupt zlib stream");

  // Well-formed streams carrying bad content.
  MakeHumanSource bad = source();
  bad.triangles[7] = static_cast<std::uint32_t>(bad.positions.size());
  expect_error(pack_makehuman_source(bad), "triangle index 13380 >= 13380 vertices");
  bad = source();
  bad.part[3] = 60;
  expect_error(pack_makehuman_source(bad), "part 60");
  bad = source();
  bad.skin.joints[5][0] = 40;
  expect_error(pack_makehuman_source(bad), "influence joint 40");
  bad = source();
  bad.skin.weights[9] = {0.0f, 0.0f, 0.0f, 0.0f};
  expect_error(pack_makehuman_source(bad), "vertex 9 has no weight");

  // The texture coordinates' section, edited in the raw stream: a corner code beyond the extras, a bad box, and
  // bytes left over.
  const std::size_t extras_at = uv_section_at(source());
  EXPECT_EQ(raw_of(good).size(), extras_at + 4 + 1 + 16 + 4 * (source().positions.size() + seam_extras(good)) +
                                     2 * source().triangles.size());
  std::string raw = raw_of(good);
  raw[raw.size() - 2] = raw[raw.size() - 1] = static_cast<char>(0xff);  // the last corner's code: 65535
  expect_error(repacked("STMHPK02", raw), "corner texture coordinate 65535 >");
  raw = raw_of(good);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(raw.data() + extras_at + 5, &nan, sizeof nan);
  expect_error(repacked("STMHPK02", raw), "bad texture coordinate box");
  expect_error(repacked("STMHPK02", raw_of(good) + "x"), "trailing bytes after the texture coordinates");
  // Bad content the writer refuses outright.
  bad = source();
  bad.corner_uvs.pop_back();
  EXPECT_THROW((void)pack_makehuman_source(bad), std::invalid_argument);
}

// A version 1 file (no texture coordinates: the raw stream ends at the weights) still reads, without them.
TEST(MakeHumanPack, VersionOneFilesReadWithoutTextureCoordinates) {
  const std::string good = pack_makehuman_source(source());
  std::string raw = raw_of(good);
  raw.resize(uv_section_at(source()));
  const MakeHumanSource v1 = unpack_makehuman_source(repacked("STMHPK01", raw), "v1.bin");
  EXPECT_TRUE(v1.corner_uvs.empty());
  EXPECT_EQ(v1.triangles, source().triangles);
  EXPECT_EQ(v1.positions, unpack_makehuman_source(good, "v2.bin").positions);
}

TEST(MakeHumanPack, TextureCoordinatesRoundTripPerCorner) {
  const MakeHumanSource& s = source();
  ASSERT_EQ(s.corner_uvs.size(), s.triangles.size()) << "the shipped source carries MakeHuman's uvs";
  const MakeHumanSource back = unpack_makehuman_source(pack_makehuman_source(s), "round trip");
  ASSERT_EQ(back.corner_uvs.size(), s.corner_uvs.size());
  std::set<std::pair<float, float>> distinct;
  for (std::size_t c = 0; c < s.corner_uvs.size(); ++c) {
    ASSERT_LT(glm::length(back.corner_uvs[c] - s.corner_uvs[c]), 2e-5f) << c;  // 16-bit steps of the unit square
    distinct.insert({s.corner_uvs[c].x, s.corner_uvs[c].y});
  }
  // Seams: more distinct texture coordinates than vertices (MakeHuman's body has 14,517 on 13,380 vertices).
  EXPECT_GT(distinct.size(), s.positions.size());
}

// ---- The derived body ----------------------------------------------------------------------------------------------

const BodyLevels& body() { return makehuman_default_body(); }

TEST(MakeHumanBody, ExactlyThePapersVertexCountsAndAClosedManifoldEverywhere) {
  const std::uint32_t expected[3] = {17953, 8923, 5133};
  for (int l = 0; l < 4; ++l) {
    const Mesh& m = l < 3 ? body().levels[static_cast<std::size_t>(l)] : body().cage;
    SCOPED_TRACE(m.name);
    EXPECT_EQ(m.vertex_count(), l < 3 ? expected[l] : 1800u);
    EXPECT_TRUE(is_closed_manifold(m.triangles, m.vertex_count()));
    EXPECT_NO_THROW(validate_mesh(m, m.name));
    EXPECT_EQ(m.normals.size(), m.vertex_count());
    for (const glm::vec3& p : m.positions) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    if (l < 3) {
      std::set<std::uint16_t> parts(m.part.begin(), m.part.end());
      EXPECT_EQ(parts.size(), 53u);
    }
  }
}

TEST(MakeHumanBody, FitsTheSkeletonCrownSolesFeetAndHands) {
  const Skeleton& sk = load_default_humanoid().skeleton;
  const Mesh& m = body().levels[0];
  float floor = std::numeric_limits<float>::max(), crown = -floor;
  for (const glm::vec3& p : m.positions) floor = std::min(floor, p.y), crown = std::max(crown, p.y);
  EXPECT_NEAR(floor, 0.0f, 1e-3f) << "the soles stay on the floor";
  EXPECT_NEAR(crown, site(sk, "skull_tip").y, 5e-3f) << "the crown on the skull tip";

  // Each foot's rearmost and foremost points on the skeleton's heel and toe sites, where the walk plants them.
  for (const char side : {'l', 'r'}) {
    const std::string foot = std::string(1, side) + "Foot", toe = std::string(1, side) + "Toe";
    float heel_z = std::numeric_limits<float>::max(), toe_z = -heel_z;
    for (std::size_t v = 0; v < m.vertex_count(); ++v)
      if (is_part(m, v, {foot.c_str(), toe.c_str()})) heel_z = std::min(heel_z, m.positions[v].z), toe_z = std::max(toe_z, m.positions[v].z);
    EXPECT_NEAR(heel_z, site(sk, side == 'l' ? "l_calcaneous_post_pt" : "r_calcaneous_post_pt").z, 5e-3f) << side;
    EXPECT_NEAR(toe_z, site(sk, side == 'l' ? "l_forefoot_tip" : "r_forefoot_tip").z, 5e-3f) << side;
  }

  // The arms come down from the A-pose: every hand vertex below the elbow, the wrist's skin around its joint.
  const glm::vec3 wrist = sk.centers[static_cast<std::size_t>(sk.find_joint("l_wrist"))];
  const glm::vec3 elbow = sk.centers[static_cast<std::size_t>(sk.find_joint("l_elbow"))];
  glm::vec3 hand_sum(0.0f);
  int hand_count = 0;
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    if (is_part(m, v, {"lHand"})) {
      hand_sum += m.positions[v];
      ++hand_count;
      EXPECT_LT(m.positions[v].y, elbow.y);
    }
  ASSERT_GT(hand_count, 0);
  EXPECT_LT(glm::length(hand_sum / float(hand_count) - wrist), 0.08f) << "the palm hangs below the wrist";

  // Hands clear of the thighs and hips at rest (a hand sunk into the thigh stays there through the walk).
  float closest = std::numeric_limits<float>::max();
  for (std::size_t h = 0; h < m.vertex_count(); ++h) {
    if (m.positions[h].x < 0.05f || !is_part(m, h, {"lHand", "lThumb1", "lThumb2", "lThumb3", "lIndex3", "lMid3", "lRing3", "lPinky3"}))
      continue;
    for (std::size_t b = 0; b < m.vertex_count(); ++b)
      if (is_part(m, b, {"hip", "lThigh", "abdomen"})) closest = std::min(closest, glm::length(m.positions[h] - m.positions[b]));
  }
  EXPECT_GT(closest, 1e-3f);
}

// The area centroid, from `o`, of the closed cut of the triangles of `parts` by the plane through `o` across `axis`.
glm::dvec3 section_centroid_offset(const Mesh& m, std::initializer_list<const char*> parts, const glm::dvec3& o,
                                   const glm::dvec3& axis) {
  double area = 0.0;
  glm::dvec3 moment(0.0);
  for (std::size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
    const std::uint32_t i[3] = {m.triangles[t], m.triangles[t + 1], m.triangles[t + 2]};
    if (!is_part(m, i[0], parts) || !is_part(m, i[1], parts) || !is_part(m, i[2], parts)) continue;
    glm::dvec3 p[3];
    double d[3];
    for (int k = 0; k < 3; ++k) p[k] = glm::dvec3(m.positions[i[k]]), d[k] = glm::dot(p[k] - o, axis);
    glm::dvec3 q[2];
    int found = 0;
    for (int k = 0; k < 3 && found < 2; ++k) {
      const int l = (k + 1) % 3;
      if ((d[k] < 0.0) != (d[l] < 0.0)) q[found++] = p[k] + (d[k] / (d[k] - d[l])) * (p[l] - p[k]);
    }
    if (found < 2) continue;
    if (glm::dot(glm::cross(q[1] - q[0], axis), glm::cross(p[1] - p[0], p[2] - p[0])) < 0.0) std::swap(q[0], q[1]);
    const double a = 0.5 * glm::dot(axis, glm::cross(q[0] - o, q[1] - o));
    area += a;
    moment += a * ((q[0] - o) + (q[1] - o)) / 3.0;
  }
  EXPECT_GT(area, 20e-4) << "the cut misses the limb";  // an elbow's section is ~43 cm2, a knee's ~100 cm2
  const glm::dvec3 e = moment / area;
  return e - glm::dot(e, axis) * axis;
}

// Elbows and knees bend about their limb's middle: MakeHuman's own elbow sat 1.8 cm behind its arm's, its knee 0.8
// cm in front of its leg's, and a limb bent about an axis off its middle loses volume (Pappus; at 120 deg dual
// quaternions lost 34 % of the elbow). The fit moves each hinge's source centre onto the middle of the fitted limb.
TEST(MakeHumanBody, ElbowsAndKneesBendAboutTheirLimbsMiddle) {
  const Skeleton& sk = load_default_humanoid().skeleton;
  const Mesh& m = body().levels[0];
  struct Hinge {
    const char *joint, *child, *upper, *lower;
  };
  for (const Hinge& h : {Hinge{"l_elbow", "l_wrist", "lShldr", "lForeArm"}, Hinge{"r_elbow", "r_wrist", "rShldr", "rForeArm"},
                         Hinge{"l_knee", "l_ankle", "lThigh", "lShin"}, Hinge{"r_knee", "r_ankle", "rThigh", "rShin"}}) {
    const glm::dvec3 c(sk.centers[static_cast<std::size_t>(sk.find_joint(h.joint))]);
    const glm::dvec3 down = glm::normalize(glm::dvec3(sk.centers[static_cast<std::size_t>(sk.find_joint(h.child))]) - c);
    const glm::dvec3 offset = section_centroid_offset(m, {h.upper, h.lower}, c, down);
    EXPECT_LT(glm::length(offset), 3e-3) << h.joint << ": the limb's middle is " << 1000.0 * offset.x << ", "
                                         << 1000.0 * offset.y << ", " << 1000.0 * offset.z << " mm off the joint";
  }
}

TEST(MakeHumanBody, FollowsAnotherSkeletonsSize) {
  // The default skeleton scaled by 1.1 about the floor: the body grows with it.
  Skeleton big = load_default_humanoid().skeleton;
  for (glm::vec3& c : big.centers) c *= 1.1f;
  for (SkeletonSite& s : big.sites) s.position *= 1.1f;
  const std::vector<glm::vec3> fitted = fit_makehuman_to_skeleton(source(), big);
  const std::vector<glm::vec3> normal = fit_makehuman_to_skeleton(source(), load_default_humanoid().skeleton);
  float crown_big = 0.0f, crown = 0.0f;
  for (const glm::vec3& p : fitted) {
    crown_big = std::max(crown_big, p.y);
    ASSERT_TRUE(std::isfinite(p.x + p.y + p.z));
  }
  for (const glm::vec3& p : normal) crown = std::max(crown, p.y);
  EXPECT_NEAR(crown_big / crown, 1.1f, 0.005f);

  try {
    (void)fit_makehuman_to_skeleton(source(), Skeleton{});
    ADD_FAILURE() << "no error for a skeleton without the default joints";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lacks joint 'HumanoidRoot'"), std::string::npos) << e.what();
  }
}

TEST(MakeHumanBody, DerivationIsDeterministicAndTheCacheGivesItBack) {
  // makehuman_default_body() may come from the disk cache; derived again here it must be bit-identical.
  const BodyLevels again = derive_makehuman_body(source(), load_default_humanoid().skeleton);
  for (int l = 0; l < 3; ++l) {
    EXPECT_EQ(again.levels[static_cast<std::size_t>(l)].positions, body().levels[static_cast<std::size_t>(l)].positions);
    EXPECT_EQ(again.levels[static_cast<std::size_t>(l)].triangles, body().levels[static_cast<std::size_t>(l)].triangles);
    EXPECT_EQ(again.levels[static_cast<std::size_t>(l)].part, body().levels[static_cast<std::size_t>(l)].part);
    EXPECT_EQ(again.levels[static_cast<std::size_t>(l)].corner_uvs, body().levels[static_cast<std::size_t>(l)].corner_uvs);
  }
  EXPECT_EQ(again.cage.corner_uvs, body().cage.corner_uvs);
  EXPECT_EQ(again.cage.positions, body().cage.positions);
}

}  // namespace
}  // namespace strata
