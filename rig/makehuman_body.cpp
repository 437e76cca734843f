#include "rig/makehuman_body.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <opensubdiv/far/primvarRefiner.h>

#include "components/fnv_hasher.h"
#include "components/shortest_arc.h"
#include "data/embedded.h"
#include "io/hanim_loader.h"
#include "rig/body_cache.h"
#include "rig/subdiv_refiner.h"
#include "rig/surface_simplify.h"
#include "rig/uv_transfer.h"

namespace strata {
namespace {

// One joint's part of the fit: x -> target_center + R (x - source_center), then a stretch by `stretch` along
// `axis` (the skeleton's segment to the joint's one child) of the part of x beyond the joint.
struct JointFit {
  glm::dquat rotation{1, 0, 0, 0};
  glm::dvec3 source_center{0.0}, target_center{0.0}, axis{0, 1, 0};
  double stretch = 1.0;
  double length = 0.0;  // the source segment's length: the stretch acts on [0, length] along the axis
  bool across_floor = false;  // the stretch also scales the horizontal width across the axis (feet)
};

// How far the hands are tilted away from the thighs about the forward axis (rad): MakeHuman's fingers, on
// ISO's hanging wrists, came within 2 mm of the thigh and its thumb crossed in front of it.
constexpr double kHandOutward = 0.15;

struct Refined {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> triangles;
  std::vector<std::uint32_t> source_vertex;  // per refined vertex, the source vertex it descends from
};

// One Loop step through OpenSubdiv (the cage refiner's options: the surface is closed, so the boundary rules do not
// matter).
Refined loop_refine(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& triangles) {
  Mesh cage;
  cage.positions = positions;
  cage.triangles = triangles;
  auto refiner = make_cage_refiner(cage);
  refiner->RefineUniform(OpenSubdiv::Far::TopologyRefiner::UniformOptions(1));
  // Each refined vertex also records the source vertex with the largest weight in its stencil (itself for a
  // vertex child, the first-listed end for an edge child's 3/8 tie), so labels follow the surface's topology.
  struct Point {
    glm::dvec3 p{0.0};
    std::uint32_t source = 0;
    float source_weight = -1.0f;
    void Clear(void* = nullptr) { p = glm::dvec3(0.0), source_weight = -1.0f; }
    void AddWithWeight(const Point& src, float w) {
      p += static_cast<double>(w) * src.p;
      if (w > source_weight) source_weight = w, source = src.source;
    }
  };
  std::vector<Point> src(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) src[v].p = positions[v], src[v].source = static_cast<std::uint32_t>(v);
  const auto& level = refiner->GetLevel(1);
  std::vector<Point> dst(static_cast<std::size_t>(level.GetNumVertices()));
  OpenSubdiv::Far::PrimvarRefiner(*refiner).Interpolate(1, src, dst);
  Refined out;
  out.positions.reserve(dst.size());
  for (const Point& d : dst) out.positions.emplace_back(d.p), out.source_vertex.push_back(d.source);
  out.triangles.reserve(static_cast<std::size_t>(level.GetNumFaces()) * 3);
  for (int f = 0; f < level.GetNumFaces(); ++f)
    for (const int v : level.GetFaceVertices(f)) out.triangles.push_back(static_cast<std::uint32_t>(v));
  return out;
}

// How far, across the limb, the middle of a hinge's limb (a knee, an elbow) sits from `centres[joint]`: the
// area-weighted centroid of the limb's cross-sections within kHingeSpan of the joint, each cut square to its bone
// (the upper one above the joint, the lower one below). Only triangles bound to the parent, the joint or the
// child alone count, so the trunk beside a hanging elbow and the other thigh beside a knee stay out.
constexpr double kHingeSpan = 0.015;  // m each side: the joint's own width, past the folds of its crease

glm::dvec3 hinge_mid_line_offset(const std::vector<glm::dvec3>& positions, const std::vector<std::uint32_t>& triangles,
                                 const SkinBinding& skin, const std::vector<glm::dvec3>& centres, std::size_t parent,
                                 std::size_t joint, std::size_t child) {
  const glm::dvec3 up = centres[joint] - centres[parent], down = centres[child] - centres[joint];
  if (glm::length(up) < 1e-6 || glm::length(down) < 1e-6) return glm::dvec3(0.0);
  std::vector<std::uint8_t> on_limb(positions.size(), 1);
  for (std::size_t v = 0; v < positions.size(); ++v)
    for (int k = 0; k < kMaxInfluences; ++k) {
      const auto j = static_cast<std::size_t>(skin.joints[v][k]);
      if (skin.weights[v][k] > 0.0f && j != parent && j != joint && j != child) on_limb[v] = 0;
    }
  std::vector<std::size_t> limb;  // triangle starts
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    if (on_limb[triangles[t]] && on_limb[triangles[t + 1]] && on_limb[triangles[t + 2]]) limb.push_back(t);
  glm::dvec3 sum(0.0);
  double total_area = 0.0;
  constexpr int kCuts = 3;  // per side, and one through the joint
  for (int cut = -kCuts; cut <= kCuts; ++cut) {
    const double along = kHingeSpan * cut / kCuts;
    const glm::dvec3 axis = glm::normalize(cut < 0 ? up : down);
    const PlaneSection s = plane_section(positions, triangles, limb, centres[joint] + along * axis, axis);
    if (!(s.area > 0.0)) continue;  // the cut missed the limb (a body without this limb's triangles)
    sum += s.area * (s.centroid_offset - glm::dot(s.centroid_offset, axis) * axis);
    total_area += s.area;
  }
  return total_area > 0.0 ? sum / total_area : glm::dvec3(0.0);
}

}  // namespace

std::vector<glm::vec3> fit_makehuman_to_skeleton(const MakeHumanSource& source, const Skeleton& target) {
  // The source's joints are the default skeleton's, in its order (io/makehuman.cpp builds them so).
  const Skeleton& reference = load_default_humanoid().skeleton;
  const std::size_t joints = reference.joint_count();
  if (source.joint_centers.size() != joints)
    throw std::invalid_argument("makehuman body: the source has " + std::to_string(source.joint_centers.size()) +
                                " joint centres, the default skeleton " + std::to_string(joints));
  std::vector<glm::dvec3> to(joints);
  for (std::size_t j = 0; j < joints; ++j) {
    const std::int32_t t = target.find_joint(reference.joint_names[j]);
    if (t < 0) throw std::invalid_argument("makehuman body: the skeleton lacks joint '" + reference.joint_names[j] + "'");
    to[j] = target.centers[static_cast<std::size_t>(t)];
  }
  // Height first, uniformly about the floor under the root, so the crown reaches the skeleton's skull_tip site
  // (its skullbase without one): proportions are MakeHuman's, the residual per segment (below) is a few per
  // cent. Stretching every segment to length alone would thin a taller skeleton's limbs and leave the head at
  // MakeHuman's size. Matching the skullbase instead made a 1.78 m body on ISO's 1.75 m skeleton: MakeHuman's
  // skullbase joint sits 3 cm lower in the head than ISO's.
  const std::int32_t skull = reference.find_joint("skullbase"), root = reference.find_joint("HumanoidRoot");
  const glm::dvec3 floor_point(source.joint_centers[static_cast<std::size_t>(root)].x, 0.0,
                               source.joint_centers[static_cast<std::size_t>(root)].z);
  double crown = 0.0;
  for (const glm::vec3& p : source.positions) crown = std::max(crown, double(p.y));
  const auto tip = std::find_if(target.sites.begin(), target.sites.end(),
                                [](const SkeletonSite& s) { return s.name == "skull_tip"; });
  const double height_scale =
      tip != target.sites.end()
          ? tip->position.y / std::max(1e-6, crown)
          : to[static_cast<std::size_t>(skull)].y /
                std::max(1e-6, double(source.joint_centers[static_cast<std::size_t>(skull)].y));
  if (!std::isfinite(height_scale) || height_scale <= 0.0)
    throw std::invalid_argument("makehuman body: the skeleton's skull is not above the floor");
  auto scaled = [&](const glm::vec3& p) { return floor_point + height_scale * (glm::dvec3(p) - floor_point); };
  std::vector<glm::dvec3> source_centres(joints);
  for (std::size_t j = 0; j < joints; ++j) source_centres[j] = scaled(source.joint_centers[j]);

  // Three kinds of joint, by what must match and what may not move:
  //   * limbs (hips, knees, shoulders, elbows): turned so their segment (to their one child) lies on the
  //     skeleton's, on top of the parent's turn, moved onto the skeleton's centre and stretched along the segment
  //     to its length (the arms come down ~45 deg, MakeHuman's wide stance closes ~8 deg). The shortest arc adds
  //     no twist: MakeHuman's A-pose and H-Anim's rest both hold the palms facing the body. Hands ride on the
  //     forearm's turn.
  //   * the trunk, clavicles, neck and head: not turned at all, only sheared by an offset that follows the
  //     vertex's height from the hips' offset to the shoulders' to the skull's (x kept, but the clavicles widen
  //     with the shoulders). Its joints are not fitted one by one: ISO's spine joints sit on the vertebrae, 7-8 cm
  //     behind MakeHuman's mid-body ones, and aiming each spine segment bowed the head 15 deg down.
  //   * feet: placed by the skeleton's heel and toe sites (calcaneous_post_pt, forefoot_tip), which the walk
  //     plants: turned about the vertical and scaled across the floor so MakeHuman's heel and toe land on them,
  //     never tilted (the sole stays flat) nor lowered (it stays on the floor). ISO's midtarsal is a point on the
  //     sole and MakeHuman's one inside the foot, so the ankle-midtarsal segments cannot be matched.
  //   * hands: on the forearm's turn, then tilted kHandOutward away from the thigh: MakeHuman's hips are 1 cm
  //     wider than the skeleton's hanging wrists allow for (ISO's wrist is 0.198 m out, MakeHuman's thigh 0.173 m
  //     and its hand 3 cm thick), and a hand sunk into the thigh stays there through the walk.
  enum class Kind { Trunk, Limb, Hand, Foot };
  auto kind_of = [&](const std::string& name) {
    if (name.ends_with("_hip") || name.ends_with("_knee") || name.ends_with("_shoulder") || name.ends_with("_elbow"))
      return Kind::Limb;
    if (name.ends_with("_wrist")) return Kind::Hand;
    if (name.ends_with("_ankle") || name.ends_with("_midtarsal")) return Kind::Foot;
    return Kind::Trunk;
  };
  std::vector<std::vector<std::size_t>> children(joints);
  for (std::size_t j = 1; j < joints; ++j) children[static_cast<std::size_t>(reference.parents[j])].push_back(j);
  // Each foot's heel (its rearmost point) and toe (its foremost), scaled, and the skeleton's sites for them.
  struct FootMarks {
    glm::dvec3 heel{0.0, 0.0, std::numeric_limits<double>::max()}, toe{0.0, 0.0, -std::numeric_limits<double>::max()};
  };
  FootMarks source_feet[2];
  const auto& part_names = paper_part_names();
  for (std::size_t v = 0; v < source.positions.size(); ++v) {
    const std::string& part = part_names[source.part[v]];
    if (part.size() < 4 || (part.substr(1) != "Foot" && part.substr(1) != "Toe")) continue;
    FootMarks& m = source_feet[part[0] == 'l' ? 0 : 1];
    const glm::dvec3 p = scaled(source.positions[v]);
    if (p.z < m.heel.z) m.heel = p;
    if (p.z > m.toe.z) m.toe = p;
  }
  auto site = [&](const char* name) -> glm::dvec3 {
    for (const SkeletonSite& s : target.sites)
      if (s.name == name) return s.position;
    throw std::invalid_argument(std::string("makehuman body: the skeleton lacks site '") + name + "'");
  };
  const FootMarks target_feet[2] = {{site("l_calcaneous_post_pt"), site("l_forefoot_tip")},
                                    {site("r_calcaneous_post_pt"), site("r_forefoot_tip")}};
  // The fit for the given source joint centres (`from`); `rotations` gets each joint's turn.
  auto pose = [&](const std::vector<glm::dvec3>& from, std::vector<glm::dquat>& rotations) {
    std::vector<Kind> kinds(joints);
    std::vector<JointFit> fit(joints);
    for (std::size_t j = 0; j < joints; ++j) {
      JointFit& f = fit[j];
      const std::int32_t parent = reference.parents[j];
      kinds[j] = kind_of(reference.joint_names[j]);
      f.source_center = from[j];
      f.target_center = to[j];
      if (kinds[j] == Kind::Foot) {
        const int side = reference.joint_names[j][0] == 'l' ? 0 : 1;
        auto flat = [](glm::dvec3 d) { return glm::dvec3(d.x, 0.0, d.z); };
        const glm::dvec3 source_axis = flat(source_feet[side].toe - source_feet[side].heel),
                         target_axis = flat(target_feet[side].toe - target_feet[side].heel);
        const double source_len = glm::length(source_axis), target_len = glm::length(target_axis);
        if (source_len < 1e-3 || target_len < 1e-3)
          throw std::invalid_argument("makehuman body: a foot without length (heel and toe one point)");
        f.rotation = shortest_arc(source_axis, target_axis);  // both horizontal: a turn about y
        f.source_center = source_feet[side].heel;
        f.target_center = glm::dvec3(target_feet[side].heel.x, source_feet[side].heel.y, target_feet[side].heel.z);
        f.axis = target_axis / target_len;
        f.stretch = target_len / source_len;
        f.length = source_len;
        f.across_floor = true;
        continue;
      }
      if (kinds[j] == Kind::Hand) {
        const double outward = reference.joint_names[j][0] == 'l' ? kHandOutward : -kHandOutward;
        f.rotation = glm::angleAxis(outward, glm::dvec3(0, 0, 1)) * fit[static_cast<std::size_t>(parent)].rotation;
        continue;
      }
      if (kinds[j] == Kind::Trunk) continue;
      f.rotation = parent < 0 ? glm::dquat(1, 0, 0, 0) : fit[static_cast<std::size_t>(parent)].rotation;
      if (kinds[j] != Kind::Limb || children[j].size() != 1) continue;
      const std::size_t c = children[j][0];
      const glm::dvec3 source_seg = f.rotation * (from[c] - from[j]), target_seg = to[c] - to[j];
      const double source_len = glm::length(source_seg), target_len = glm::length(target_seg);
      if (source_len < 1e-6 || target_len < 1e-6) continue;  // a zero-length segment: nothing to aim
      f.rotation = glm::normalize(shortest_arc(source_seg, target_seg) * f.rotation);
      f.axis = target_seg / target_len;
      f.stretch = target_len / source_len;
      f.length = source_len;
    }
    // The trunk's offset by height: the hips' and shoulders' mean offsets (their x parts cancel), then the skull's.
    auto joint_at = [&](const char* name) { return static_cast<std::size_t>(reference.find_joint(name)); };
    const std::size_t l_hip = joint_at("l_hip"), r_hip = joint_at("r_hip"), l_sh = joint_at("l_shoulder"),
                      r_sh = joint_at("r_shoulder");
    struct Anchor {
      double y;
      glm::dvec3 offset;
    };
    auto mid_anchor = [&](std::size_t a, std::size_t b) {
      glm::dvec3 offset = 0.5 * ((to[a] - from[a]) + (to[b] - from[b]));
      offset.x = 0.0;
      return Anchor{0.5 * (from[a].y + from[b].y), offset};
    };
    // The head keeps the height the scale gave it (its crown on skull_tip) and comes forward or back onto the
    // skullbase; the neck takes up the difference.
    const std::size_t skull_joint = static_cast<std::size_t>(skull);
    const Anchor anchors[3] = {mid_anchor(l_hip, r_hip), mid_anchor(l_sh, r_sh),
                               {from[skull_joint].y,
                                glm::dvec3(0.0, tip != target.sites.end() ? 0.0 : to[skull_joint].y - from[skull_joint].y,
                                           to[skull_joint].z - from[skull_joint].z)}};
    const double shoulder_half_width = 0.5 * (from[l_sh].x - from[r_sh].x);
    const double shoulder_widening = 0.5 * ((to[l_sh].x - from[l_sh].x) - (to[r_sh].x - from[r_sh].x));
    auto trunk_offset = [&](const glm::dvec3& x, bool clavicle) {
      glm::dvec3 offset = anchors[0].offset;
      for (int a = 0; a < 2; ++a)
        if (x.y > anchors[a].y) {
          const double t = std::clamp((x.y - anchors[a].y) / std::max(1e-6, anchors[a + 1].y - anchors[a].y), 0.0, 1.0);
          offset = glm::mix(anchors[a].offset, anchors[a + 1].offset, t);
        }
      if (clavicle && shoulder_half_width > 1e-6)
        offset.x += shoulder_widening * std::clamp(x.x / shoulder_half_width, -1.0, 1.0);
      return offset;
    };
    std::vector<std::uint8_t> clavicle(joints, 0);
    for (std::size_t j = 0; j < joints; ++j)
      clavicle[j] = reference.joint_names[j].ends_with("clavicular") ? 1 : 0;

    // Dual quaternion blend of the rigid parts (a linear blend of 45 deg apart shoulder and chest transforms would
    // pinch the armpit for good); the stretch, small and along each segment, is blended linearly on top.
    struct Dual {
      glm::dquat real, dual;
    };
    auto dual_of = [](const glm::dquat& rotation, const glm::dvec3& t) {
      return Dual{rotation, 0.5 * (glm::dquat(0.0, t.x, t.y, t.z) * rotation)};
    };
    std::vector<Dual> duals(joints);
    for (std::size_t j = 0; j < joints; ++j)
      duals[j] = dual_of(fit[j].rotation, fit[j].target_center - fit[j].rotation * fit[j].source_center);
    std::vector<glm::dvec3> out(source.positions.size());
    for (std::size_t v = 0; v < source.positions.size(); ++v) {
      const glm::dvec3 x = scaled(source.positions[v]);
      glm::dquat real(0, 0, 0, 0), dual(0, 0, 0, 0);
      glm::dvec3 stretch(0.0);
      const glm::dquat& pivot = duals[static_cast<std::size_t>(source.skin.joints[v][0])].real;
      for (int k = 0; k < kMaxInfluences; ++k) {
        const double w = source.skin.weights[v][k];
        if (w <= 0.0) continue;
        const std::size_t j = static_cast<std::size_t>(source.skin.joints[v][k]);
        const Dual d = kinds[j] == Kind::Trunk ? dual_of(glm::dquat(1, 0, 0, 0), trunk_offset(x, clavicle[j])) : duals[j];
        const double sign = glm::dot(d.real, pivot) < 0.0 ? -1.0 : 1.0;  // the same hemisphere
        real += (w * sign) * d.real;
        dual += (w * sign) * d.dual;
        const JointFit& f = fit[j];
        const glm::dvec3 local = f.rotation * (x - f.source_center);
        const double along = glm::dot(local, f.axis);
        stretch += w * (f.stretch - 1.0) * std::clamp(along, 0.0, f.length) * f.axis;
        if (f.across_floor) {
          const glm::dvec3 across = local - along * f.axis;
          stretch += w * (f.stretch - 1.0) * glm::dvec3(across.x, 0.0, across.z);
        }
      }
      const double norm = glm::length(real);
      glm::dvec3 p = x;
      if (norm > 1e-12) {
        real /= norm;
        dual /= norm;
        const glm::dquat t = 2.0 * (dual * glm::conjugate(real));
        p = real * x + glm::dvec3(t.x, t.y, t.z);
      }
      out[v] = p + stretch;
    }
    for (std::size_t j = 0; j < joints; ++j) rotations[j] = fit[j].rotation;
    return out;
  };
  std::vector<glm::dquat> rotations(joints);
  std::vector<glm::dvec3> posed = pose(source_centres, rotations);
  // Hinges on their limb's middle. MakeHuman's elbow sits 1.8 cm behind the middle of its arm and its knee 0.8 cm
  // in front of the middle of its leg; bent about such an axis, a limb loses volume as Pappus says (each section by
  // its area, its turn and the axis's offset): at 120 deg of flexion, dual quaternions lost 34 % of the elbow, and
  // moving the hinge by 1 cm moved that by ~25 points. So each hinge's source centre moves across its limb by the
  // offset measured in the fitted pose (turned back into the source's), and the fit runs again; twice, as the move
  // turns the segments a little (residual < 0.2 mm). Rejected: the sections weighted over the whole blend zone
  // (elbow +-6 cm), which left the elbow 2.7 mm behind where a bend keeps its volume (-6 % by dual quaternions);
  // and moving the skeleton's joints, which the procedural body and every other mesh share.
  for (int pass = 0; pass < 2; ++pass) {
    for (const char* name : {"l_elbow", "r_elbow", "l_knee", "r_knee"}) {
      const std::int32_t j = reference.find_joint(name);
      if (j < 0 || reference.parents[static_cast<std::size_t>(j)] < 0 || children[static_cast<std::size_t>(j)].size() != 1)
        continue;
      const auto joint = static_cast<std::size_t>(j);
      const glm::dvec3 offset =
          hinge_mid_line_offset(posed, source.triangles, source.skin, to,
                                static_cast<std::size_t>(reference.parents[joint]), joint, children[joint][0]);
      source_centres[joint] += glm::inverse(rotations[joint]) * offset;
    }
    posed = pose(source_centres, rotations);
  }
  std::vector<glm::vec3> out(posed.size());
  for (std::size_t v = 0; v < posed.size(); ++v) out[v] = glm::vec3(posed[v]);
  return out;
}

BodyLevels derive_makehuman_body(const MakeHumanSource& source, const Skeleton& target, const BodyOptions& options) {
  const std::vector<glm::vec3> fitted = fit_makehuman_to_skeleton(source, target);
  const Refined refined = loop_refine(fitted, source.triangles);
  // Parts follow each vertex back to the source vertex it descends from. Taking the nearest source vertex's
  // part was the first version: the thigh under a hanging thumb took the thumb's part, was bound to the wrist and
  // tore over the walk.
  // MakeHuman's texture coordinates, projected onto each level from the fitted source (rig/uv_transfer.h).
  const UvSource uv_source{fitted, source.triangles, source.corner_uvs};
  auto to_mesh = [&](SimplifiedSurface s, const std::vector<std::uint32_t>& origin, const std::string& name) {
    const std::vector<std::uint32_t> from = std::move(s.source_vertex);  // body_level_mesh needs only the rest
    Mesh mesh = body_level_mesh(std::move(s), name,
                                [&](std::size_t v, const glm::vec3&) { return source.part[origin[from[v]]]; });
    if (!source.corner_uvs.empty()) mesh.corner_uvs = transfer_corner_uvs(uv_source, mesh);
    return mesh;
  };
  BodyLevels out;
  SimplifiedSurface prev{refined.positions, refined.triangles, {}};
  std::vector<std::uint32_t> origin = refined.source_vertex;  // per vertex of `prev`, its source vertex
  for (int l = 0; l < 3; ++l) {
    SimplifiedSurface s = simplify_surface(prev.positions, prev.triangles,
                                           options.level_vertices[static_cast<std::size_t>(l)], kSkinnedMinQuality);
    std::vector<std::uint32_t> next(s.positions.size());
    for (std::size_t v = 0; v < next.size(); ++v) next[v] = origin[s.source_vertex[v]];
    prev = s;
    out.levels[static_cast<std::size_t>(l)] = to_mesh(std::move(s), origin, "makehuman_body_L" + std::to_string(l));
    origin = std::move(next);
  }
  // As the procedural cage: no sliver limit, the cage is Loop-refined before anything draws it.
  out.cage = to_mesh(simplify_surface(prev.positions, prev.triangles, options.cage_vertices, 0.0), origin,
                     "makehuman_body_cage");
  return out;
}

MakeHumanSource shipped_makehuman_source() {
  const std::optional<std::string_view> bytes = embedded::find("data/makehuman_body.bin");
  if (!bytes) throw std::logic_error("makehuman body: data/makehuman_body.bin is not embedded");
  return unpack_makehuman_source(*bytes, "<embedded>/data/makehuman_body.bin");
}

const BodyLevels& makehuman_default_body() {
  static const BodyLevels body = [] {
    // Bump when the derivation's output changes, so stale cache files are ignored.
    constexpr std::uint32_t kDerivationVersion = 4;
    const Skeleton skeleton = load_default_humanoid().skeleton;
    const BodyOptions options;
    // The key covers the skeleton, the options, the version and the shipped source's bytes (a re-packed source
    // invalidates the cache even if nobody bumps the version).
    FnvHasher hasher;
    hasher.value(body_cache_key(skeleton, options, 0x4d480000u + kDerivationVersion));
    const std::string_view bytes = *embedded::find("data/makehuman_body.bin");
    hasher.bytes(bytes.data(), bytes.size());
    return cached_body_levels("makehuman_body", hasher.h,
                              [&] { return derive_makehuman_body(shipped_makehuman_source(), skeleton, options); });
  }();
  return body;
}

}  // namespace strata
