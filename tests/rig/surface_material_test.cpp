// Surface classes (rig/surface_material.h): where the default body's clothes, hair and eyes fall, that every cut
// is a consistent pair, that the refined surface and a layout carry them, and that a body without the paper's
// parts is left as skin.
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "rig/body_generator.h"
#include "rig/body_rig.h"
#include "rig/subdiv_topology.h"
#include "rig/surface_material.h"

namespace strata {
namespace {

const Mesh& level0() { return default_body().levels[0]; }

int part_index(const Mesh& m, const std::string& name) {
  for (std::size_t p = 0; p < m.part_names.size(); ++p)
    if (m.part_names[p] == name) return static_cast<int>(p);
  ADD_FAILURE() << "no part " << name;
  return -1;
}

// Counts of each class in each of the named parts.
std::array<std::size_t, kSurfaceMaterialCount> classes_in(const Mesh& m, const SurfaceClasses& c, const std::string& part) {
  std::array<std::size_t, kSurfaceMaterialCount> count{};
  const int p = part_index(m, part);
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    if (m.part[v] == p) ++count[static_cast<std::size_t>(c.at(v))];
  return count;
}

std::size_t of(const std::array<std::size_t, kSurfaceMaterialCount>& count, SurfaceMaterial m) {
  return count[static_cast<std::size_t>(m)];
}

TEST(SurfaceMaterial, DressesTheDefaultBodyWhereClothesGo) {
  const Mesh& m = level0();
  const SurfaceClasses c = surface_materials(m);
  ASSERT_EQ(c.size(), m.vertex_count());
  ASSERT_EQ(c.cut.size(), m.vertex_count());
  // Bare hands and fingers, a shirt over the chest, trousers over the thighs, shoes on the feet.
  for (const char* part : {"lHand", "rHand", "lIndex2", "rThumb3"}) {
    const auto n = classes_in(m, c, part);
    EXPECT_EQ(of(n, SurfaceMaterial::Skin), n[0] + n[1] + n[2] + n[3] + n[4] + n[5] + n[6]) << part;
  }
  const auto chest = classes_in(m, c, "chest");
  EXPECT_GT(of(chest, SurfaceMaterial::Top), 9 * of(chest, SurfaceMaterial::Skin)) << "a shirt, with a neckline";
  EXPECT_GT(of(chest, SurfaceMaterial::Skin), 0u) << "the neckline opens the top of the chest";
  for (const char* part : {"lThigh", "rThigh"}) {
    const auto n = classes_in(m, c, part);
    EXPECT_GT(of(n, SurfaceMaterial::Bottom), 9 * of(n, SurfaceMaterial::Top)) << part;
  }
  for (const char* part : {"lFoot", "rToe"}) {
    const auto n = classes_in(m, c, part);
    EXPECT_GT(of(n, SurfaceMaterial::Shoes), 9 * (of(n, SurfaceMaterial::Bottom) + 1)) << part;
  }
  // Short sleeves: the upper arm has both shirt and skin, the forearm only skin.
  const auto upper = classes_in(m, c, "lShldr"), fore = classes_in(m, c, "lForeArm");
  EXPECT_GT(of(upper, SurfaceMaterial::Top), 0u);
  EXPECT_GT(of(upper, SurfaceMaterial::Skin), 0u);
  EXPECT_EQ(of(fore, SurfaceMaterial::Top), 0u);
  // Hair on the head only, covering its top and leaving the face; eyes with an iris and a white.
  const auto head = classes_in(m, c, "head");
  EXPECT_GT(of(head, SurfaceMaterial::Hair), 0u);
  EXPECT_GT(of(head, SurfaceMaterial::Skin), of(head, SurfaceMaterial::Hair) / 4);
  const auto eye = classes_in(m, c, "lEye");
  EXPECT_GT(of(eye, SurfaceMaterial::Eyes), 0u);
  EXPECT_GT(of(eye, SurfaceMaterial::Sclera), of(eye, SurfaceMaterial::Eyes));
  // The topmost vertex is hair; the lowest shoe; no hair or shoes anywhere else.
  std::size_t top = 0, bottom = 0;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    if (m.positions[v].y > m.positions[top].y) top = v;
    if (m.positions[v].y < m.positions[bottom].y) bottom = v;
    const std::string& part = m.part_names[m.part[v]];
    if (c.at(v) == SurfaceMaterial::Hair) {
      ASSERT_EQ(part, "head") << "vertex " << v;
    }
    if (c.at(v) == SurfaceMaterial::Shoes) {
      ASSERT_TRUE(part.ends_with("Foot") || part.ends_with("Toe") || part.ends_with("Shin")) << part;
    }
  }
  EXPECT_EQ(c.at(top), SurfaceMaterial::Hair);
  EXPECT_EQ(c.at(bottom), SurfaceMaterial::Shoes);
}

// A vertex keeps two classes only near its cut, and the class it reports is the one on its side; every class
// index fits the renderer's palette.
TEST(SurfaceMaterial, CutsAreConsistentPairs) {
  const SurfaceClasses c = surface_materials(level0());
  std::size_t pairs = 0;
  for (std::size_t v = 0; v < c.size(); ++v) {
    const unsigned above = c.classes[v] & 15u, below = c.classes[v] >> 4;
    ASSERT_LT(above, kSurfaceMaterialCount);
    ASSERT_LT(below, kSurfaceMaterialCount);
    ASSERT_TRUE(std::isfinite(c.cut[v]));
    if (above != below) {
      ++pairs;
      EXPECT_LT(std::abs(c.cut[v]), 0.06f) << "vertex " << v << " far from its cut keeps two classes";
    }
  }
  EXPECT_GT(pairs, 100u) << "waist, ankles, sleeves, neckline, hairline and irises are cuts";
}

TEST(SurfaceMaterial, LayoutAndRefinedSurfaceCarryTheClasses) {
  const auto body = default_bound_body();
  const SkinLayout layout = make_skin_layout(body->levels[1]);
  const SurfaceClasses mesh_order = surface_materials(body->levels[1].mesh);
  const SurfaceClasses laid = layout_materials(body->levels[1].mesh, layout);
  ASSERT_EQ(laid.size(), layout.vertex_count);
  for (std::size_t v = 0; v < layout.vertex_count; ++v) {
    ASSERT_EQ(laid.classes[v], mesh_order.classes[layout.original[v]]);
    ASSERT_EQ(laid.cut[v], mesh_order.cut[layout.original[v]]);
  }
  const auto surface = body_subdiv_surface(*body, 1);
  ASSERT_TRUE(surface);
  const SurfaceClasses refined = refined_materials(body->cage->mesh, *surface);
  ASSERT_EQ(refined.size(), surface->vertex_count);
  // Where each refined vertex lies at rest: the stencils applied to the cage in layout order, as the
  // subdivision job applies them every frame. Its class must be the one of the cage vertex nearest it, bar a few
  // along the cuts (a class number read in the wrong vertex order scatters them all over the body).
  const Mesh& cage = body->cage->mesh;
  std::vector<glm::vec3> points(surface->cage_layout.vertex_count);
  for (std::size_t v = 0; v < points.size(); ++v) points[v] = cage.positions[surface->cage_layout.original[v]];
  for (const SubdivStencils& step : surface->steps) {
    std::vector<glm::vec3> next(step.rows(), glm::vec3(0.0f));
    for (std::size_t r = 0; r < step.rows(); ++r)
      for (std::uint32_t t = step.offsets[r]; t < step.offsets[r + 1]; ++t) next[r] += step.weights[t] * points[step.indices[t]];
    points = std::move(next);
  }
  ASSERT_EQ(points.size(), refined.size());
  const SurfaceClasses cage_classes = surface_materials(cage);
  std::size_t agree = 0;
  for (std::size_t v = 0; v < points.size(); ++v) {
    std::size_t nearest = 0;
    for (std::size_t c = 1; c < cage.vertex_count(); ++c)
      if (glm::distance(points[v], cage.positions[c]) < glm::distance(points[v], cage.positions[nearest])) nearest = c;
    agree += refined.at(v) == cage_classes.at(nearest);
  }
  EXPECT_GT(agree, points.size() * 9 / 10);
  std::array<std::size_t, kSurfaceMaterialCount> count{};
  for (std::size_t v = 0; v < refined.size(); ++v) ++count[static_cast<std::size_t>(refined.at(v))];
  for (SurfaceMaterial m : {SurfaceMaterial::Skin, SurfaceMaterial::Top, SurfaceMaterial::Bottom, SurfaceMaterial::Shoes,
                            SurfaceMaterial::Hair})
    EXPECT_GT(count[static_cast<std::size_t>(m)], refined.size() / 100) << "class " << static_cast<int>(m);
}

TEST(SurfaceMaterial, ABodyWithoutThePapersPartsIsSkin) {
  Mesh m = level0();
  for (std::string& name : m.part_names) name = "mesh_part_" + name;
  const SurfaceClasses c = surface_materials(m);
  for (std::size_t v = 0; v < c.size(); ++v) ASSERT_EQ(c.at(v), SurfaceMaterial::Skin);
  Mesh no_parts = level0();
  no_parts.part.clear();
  const SurfaceClasses none = surface_materials(no_parts);
  ASSERT_EQ(none.size(), no_parts.vertex_count());
  for (std::size_t v = 0; v < none.size(); ++v) ASSERT_EQ(none.at(v), SurfaceMaterial::Skin);
}

}  // namespace
}  // namespace strata
