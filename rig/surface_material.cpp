#include "rig/surface_material.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

#include <glm/geometric.hpp>

#include "rig/subdiv_topology.h"

namespace strata {
namespace {

// Class of a paper part name; Skin for the head, neck, forearms, hands and fingers, and for any other name.
SurfaceMaterial class_of_part(std::string_view name) {
  if (name == "hip") return SurfaceMaterial::Bottom;
  if (name == "abdomen" || name == "chest") return SurfaceMaterial::Top;
  if (name == "lEye" || name == "rEye") return SurfaceMaterial::Eyes;
  if (name.size() > 1 && (name[0] == 'l' || name[0] == 'r')) {
    const std::string_view part = name.substr(1);
    if (part == "Collar" || part == "Shldr") return SurfaceMaterial::Top;
    if (part == "Thigh" || part == "Shin") return SurfaceMaterial::Bottom;
    if (part == "Foot" || part == "Toe") return SurfaceMaterial::Shoes;
  }
  return SurfaceMaterial::Skin;
}

}  // namespace

SurfaceClasses surface_materials(const Mesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  SurfaceClasses out;
  out.classes.assign(n, static_cast<std::uint8_t>(SurfaceMaterial::Skin) * 17u);
  out.cut.assign(n, 1.0f);
  if (mesh.part.size() != n) return out;
  std::vector<SurfaceMaterial> by_part(mesh.part_names.size(), SurfaceMaterial::Skin);
  bool paper_parts = false;
  int head = -1;
  for (std::size_t p = 0; p < mesh.part_names.size(); ++p) {
    by_part[p] = class_of_part(mesh.part_names[p]);
    paper_parts |= by_part[p] != SurfaceMaterial::Skin;
    if (mesh.part_names[p] == "head") head = static_cast<int>(p);
  }
  if (!paper_parts) return out;
  auto set = [&](std::size_t v, SurfaceMaterial above, SurfaceMaterial below, double distance) {
    out.classes[v] = static_cast<std::uint8_t>(static_cast<unsigned>(above) | static_cast<unsigned>(below) << 4);
    out.cut[v] = static_cast<float>(distance);
  };
  std::vector<int> part_of(n, -1);
  for (std::size_t v = 0; v < n; ++v)
    if (mesh.part[v] < by_part.size()) {
      part_of[v] = mesh.part[v];
      set(v, by_part[mesh.part[v]], by_part[mesh.part[v]], 1.0);
    }
  auto part_index = [&](std::string_view name) {
    for (std::size_t p = 0; p < mesh.part_names.size(); ++p)
      if (mesh.part_names[p] == name) return static_cast<int>(p);
    return -1;
  };
  // Where parts a and b meet along `normal`: the median of dot(p, normal) over the vertices of the triangles that
  // straddle their boundary (a level cut sits at the median height of those triangles).
  auto boundary_along = [&](int a, int b, const glm::dvec3& normal, double& at) {
    std::vector<double> values;
    for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
      bool has_a = false, has_b = false;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = mesh.triangles[t + static_cast<std::size_t>(k)];
        has_a |= v < n && part_of[v] == a;
        has_b |= v < n && part_of[v] == b;
      }
      if (!has_a || !has_b) continue;
      for (int k = 0; k < 3; ++k)
        if (const std::uint32_t v = mesh.triangles[t + static_cast<std::size_t>(k)]; v < n)
          values.push_back(glm::dot(glm::dvec3(mesh.positions[v]), normal));
    }
    if (values.empty()) return false;
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
    at = values[values.size() / 2];
    return true;
  };
  const glm::dvec3 up(0.0, 1.0, 0.0);
  auto boundary_height = [&](int a, int b, double& height) { return boundary_along(a, b, up, height); };
  // Only vertices near a cut keep both classes: far from it the pair collapses to the vertex's own side, so a
  // triangle joining a cut part to a part beyond (the shin's ankle cut and the thigh) never blends in a class
  // that belongs to neither. The margin is wider than a triangle of the coarsest level.
  constexpr double kMargin = 0.05;
  auto cut_vertex = [&](std::size_t v, SurfaceMaterial above, SurfaceMaterial below, double distance) {
    if (distance >= kMargin) set(v, above, above, distance);
    else if (distance <= -kMargin) set(v, below, below, distance);
    else set(v, above, below, distance);
  };
  // A plane cut of the given parts: distance = dot(p, normal) - offset, `above` on the positive side.
  auto plane_cut = [&](std::initializer_list<int> parts, const glm::dvec3& normal, double offset, SurfaceMaterial above,
                       SurfaceMaterial below) {
    for (std::size_t v = 0; v < n; ++v)
      for (int p : parts)
        if (p >= 0 && part_of[v] == p) cut_vertex(v, above, below, glm::dot(glm::dvec3(mesh.positions[v]), normal) - offset);
  };
  const int hip = part_index("hip"), abdomen = part_index("abdomen");
  double waist = 0.0;
  // The waist cuts every part it could cross: the back of the pelvis and the buttocks rise past it.
  if (hip >= 0 && abdomen >= 0 && boundary_height(hip, abdomen, waist))
    plane_cut({hip, abdomen, part_index("chest"), part_index("lThigh"), part_index("rThigh")}, up, waist,
              SurfaceMaterial::Top, SurfaceMaterial::Bottom);
  auto centroid = [&](int part) {
    glm::dvec3 sum(0.0);
    std::size_t count = 0;
    for (std::size_t v = 0; v < n; ++v)
      if (part_of[v] == part) sum += glm::dvec3(mesh.positions[v]), ++count;
    return count ? sum / static_cast<double>(count) : sum;
  };
  // The neckline: skin above the neck's base and within a little more than the neck's radius of its axis, so the
  // shirt rounds the neck and still covers the shoulders.
  const int neck = part_index("neck"), chest = part_index("chest");
  const int collars[2] = {part_index("lCollar"), part_index("rCollar")};
  double neck_base = 0.0;
  if (neck >= 0 && chest >= 0 && boundary_height(neck, chest, neck_base)) {
    const glm::dvec3 axis = centroid(neck);
    std::vector<double> radii;
    for (std::size_t v = 0; v < n; ++v)
      if (part_of[v] == neck) radii.push_back(std::hypot(mesh.positions[v].x - axis.x, mesh.positions[v].z - axis.z));
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    const double reach = 1.5 * radii[radii.size() / 2];
    for (std::size_t v = 0; v < n; ++v) {
      if (part_of[v] != neck && part_of[v] != chest && part_of[v] != collars[0] && part_of[v] != collars[1]) continue;
      const glm::dvec3 p(mesh.positions[v]);
      // The neck's own vertices only by height: the part reaches up under the jaw, beyond the radius.
      const double around = part_of[v] == neck ? 1.0 : reach - std::hypot(p.x - axis.x, p.z - axis.z);
      cut_vertex(v, SurfaceMaterial::Skin, SurfaceMaterial::Top, std::min(p.y - (neck_base - 0.01), around));
    }
  }
  for (const char* side : {"l", "r"}) {
    const std::string s(side);
    const int shin = part_index(s + "Shin"), foot = part_index(s + "Foot"), toe = part_index(s + "Toe");
    double ankle = 0.0;
    // A shoe reaches a little above the part boundary, which runs low under the ankle bones: cut there, the top
    // of the instep showed as trouser.
    if (shin >= 0 && foot >= 0 && boundary_height(shin, foot, ankle))
      plane_cut({shin, foot, toe}, up, ankle + 0.025, SurfaceMaterial::Bottom, SurfaceMaterial::Shoes);
    // Short sleeves: across the upper arm, two fifths of the way up from the elbow (the upper arm / forearm
    // boundary), square to the arm whatever its rest pose.
    const int upper = part_index(s + "Shldr"), fore = part_index(s + "ForeArm");
    if (upper >= 0 && fore >= 0) {
      const glm::dvec3 along = centroid(upper) - centroid(fore);
      if (glm::length(along) > 1e-6) {
        const glm::dvec3 axis = glm::normalize(along);  // towards the shoulder
        double elbow = 0.0, shoulder = -1e30;
        for (std::size_t v = 0; v < n; ++v)
          if (part_of[v] == upper) shoulder = std::max(shoulder, glm::dot(glm::dvec3(mesh.positions[v]), axis));
        if (boundary_along(upper, fore, axis, elbow))
          plane_cut({upper, fore}, axis, elbow + 0.4 * (shoulder - elbow), SurfaceMaterial::Top, SurfaceMaterial::Skin);
      }
    }
    // Eyes: an iris facing forward (+Z) on a white eyeball; the cut is the distance from the iris' rim.
    const int eyeball = part_index(s + "Eye");
    if (eyeball >= 0) {
      const glm::dvec3 c = centroid(eyeball);
      double radius = 0.0;
      for (std::size_t v = 0; v < n; ++v)
        if (part_of[v] == eyeball) radius = std::max(radius, glm::length(glm::dvec3(mesh.positions[v]) - c));
      for (std::size_t v = 0; v < n; ++v) {
        if (part_of[v] != eyeball) continue;
        const glm::dvec3 d = glm::dvec3(mesh.positions[v]) - c;
        const double off_axis = d.z > 0.0 ? std::hypot(d.x, d.y) : radius;
        out.classes[v] = static_cast<std::uint8_t>(static_cast<unsigned>(SurfaceMaterial::Eyes) |
                                                   static_cast<unsigned>(SurfaceMaterial::Sclera) << 4);
        out.cut[v] = static_cast<float>(0.5 * radius - off_axis);
      }
    }
  }
  // Hair: the head's vertices above a hairline that is high over the forehead, drops to just above the ears at
  // the sides and lower still behind (the nape). Measured from the eyes and the head's centroid (H-Anim faces +Z,
  // +Y up), so it follows a head of any size; without eyes there is no face to measure from and the head stays
  // skin.
  glm::dvec3 eye_sum(0.0), head_sum(0.0);
  std::size_t eyes = 0, heads = 0;
  double head_top = -1e30;
  for (std::size_t v = 0; v < n; ++v) {
    if (part_of[v] < 0) continue;
    if (by_part[static_cast<std::size_t>(part_of[v])] == SurfaceMaterial::Eyes) eye_sum += glm::dvec3(mesh.positions[v]), ++eyes;
    if (part_of[v] == head) {
      head_sum += glm::dvec3(mesh.positions[v]), ++heads;
      head_top = std::max(head_top, static_cast<double>(mesh.positions[v].y));
    }
  }
  if (eyes == 0 || heads == 0) return out;
  const glm::dvec3 eye = eye_sum / static_cast<double>(eyes), centre = head_sum / static_cast<double>(heads);
  const double depth = std::max(eye.z - centre.z, 1e-3);  // eyes in front of the head's centroid
  const double forehead = eye.y + 0.5 * (head_top - eye.y), side = eye.y + 0.035, nape = eye.y - 0.07;
  for (std::size_t v = 0; v < n; ++v) {
    if (part_of[v] != head) continue;
    const glm::dvec3 p(mesh.positions[v]);
    const double front = (p.z - centre.z) / depth;  // 0 at the centroid, 1 at the eyes
    const double hairline = front >= 0.0 ? side + (forehead - side) * std::sqrt(std::min(front, 1.0))
                                         : side + (nape - side) * std::min(-front / 0.6, 1.0);
    cut_vertex(v, SurfaceMaterial::Hair, SurfaceMaterial::Skin, p.y - hairline);
  }
  return out;
}

SurfaceClasses layout_materials(const Mesh& mesh, const SkinLayout& layout) {
  const SurfaceClasses mesh_order = surface_materials(mesh);
  SurfaceClasses out;
  out.classes.assign(layout.vertex_count, static_cast<std::uint8_t>(SurfaceMaterial::Skin) * 17u);
  out.cut.assign(layout.vertex_count, 1.0f);
  for (std::size_t v = 0; v < layout.vertex_count && v < layout.original.size(); ++v)
    if (const std::uint32_t m = layout.original[v]; m < mesh_order.size())
      out.classes[v] = mesh_order.classes[m], out.cut[v] = mesh_order.cut[m];
  return out;
}

SurfaceClasses refined_materials(const Mesh& cage, const SubdivSurface& surface) {
  SurfaceClasses level = layout_materials(cage, surface.cage_layout);
  for (const SubdivStencils& step : surface.steps) {
    SurfaceClasses next;
    next.classes.assign(step.rows(), static_cast<std::uint8_t>(SurfaceMaterial::Skin) * 17u);
    next.cut.assign(step.rows(), 1.0f);
    for (std::size_t r = 0; r < step.rows(); ++r) {
      float best = -1.0f, sum = 0.0f, weight = 0.0f;
      for (std::uint32_t t = step.offsets[r]; t < step.offsets[r + 1]; ++t) {
        const std::uint32_t i = step.indices[t];
        if (i >= level.size()) continue;
        if (step.weights[t] > best) best = step.weights[t], next.classes[r] = level.classes[i];
        sum += step.weights[t] * level.cut[i], weight += step.weights[t];
      }
      if (weight > 1e-6f) next.cut[r] = sum / weight;
    }
    level = std::move(next);
  }
  // The last step's rows are the refined vertices in SubdivSurface numbering already (rig/subdiv_topology.cpp
  // renumbers them): what the subdivision job writes, and what the triangles index.
  level.classes.resize(surface.vertex_count, static_cast<std::uint8_t>(SurfaceMaterial::Skin) * 17u);
  level.cut.resize(surface.vertex_count, 1.0f);
  return level;
}

}  // namespace strata
