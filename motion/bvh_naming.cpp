#include "motion/bvh_naming.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "components/humanoid_shape.h"
#include "io/load_error.h"

namespace strata {

namespace {

// Whether BVH joint `ancestor` is `j` or one of its ancestors.
bool is_ancestor(const BvhMotion& motion, std::int32_t ancestor, std::int32_t j) {
  for (; j >= 0; j = motion.joints[static_cast<std::size_t>(j)].parent)
    if (j == ancestor) return true;
  return false;
}

// Nearest signed axis of a direction (0..2 for x, y, z; the sign in `sign`).
int snapped_axis(const glm::vec3& d, float& sign) {
  int best = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(d[a]) > std::abs(d[best])) best = a;
  sign = d[best] < 0.0f ? -1.0f : 1.0f;
  return best;
}

}  // namespace

glm::mat3 bvh_file_axes(const glm::vec3& left, const glm::vec3& up) {
  float left_sign = 1.0f, up_sign = 1.0f;
  const int l = snapped_axis(left, left_sign), u = snapped_axis(up, up_sign);
  if (l == u || !(glm::dot(left, left) > 0.0f) || !(glm::dot(up, up) > 0.0f)) return glm::mat3(1.0f);
  glm::vec3 left_axis(0.0f), up_axis(0.0f);
  left_axis[l] = left_sign;
  up_axis[u] = up_sign;
  const glm::vec3 forward_axis = glm::cross(left_axis, up_axis);  // H-Anim: +X cross +Y = +Z
  // Rows are the file's left, up and forward axes, so the matrix takes them to +X, +Y and +Z.
  return glm::transpose(glm::mat3(left_axis, up_axis, forward_axis));
}

namespace {

// What a map needs of a capture's skeleton: BVH joint indices, -1 where the file has no such joint; the pelvis is
// the BVH joint that becomes HumanoidRoot. The same record the name and shape finders fill.
using Anatomy = HumanoidShape;

std::vector<std::vector<std::int32_t>> children_of(const BvhMotion& m) {
  std::vector<std::vector<std::int32_t>> out(m.joint_count());
  for (std::size_t j = 0; j < m.joint_count(); ++j)
    if (m.joints[j].parent >= 0) out[static_cast<std::size_t>(m.joints[j].parent)].push_back(static_cast<std::int32_t>(j));
  return out;
}

// The hand's direction when the file names no middle finger: of the wrist's children, the one closest to their mean
// direction (the middle finger of five), or its only child; -1 (End Site or first child) otherwise.
std::int32_t middle_child(const std::vector<glm::vec3>& rest,
                          const std::vector<std::vector<std::int32_t>>& children, std::int32_t wrist) {
  if (wrist < 0) return -1;
  const std::vector<std::int32_t>& c = children[static_cast<std::size_t>(wrist)];
  if (c.size() == 1) return c[0];
  if (c.size() < 3) return -1;
  glm::vec3 mean(0.0f);
  for (const std::int32_t k : c) mean += glm::normalize(rest[k] - rest[wrist] + glm::vec3(1e-9f));
  std::int32_t best = -1;
  float best_dot = -2.0f;
  for (const std::int32_t k : c) {
    const float d = glm::dot(glm::normalize(rest[k] - rest[wrist] + glm::vec3(1e-9f)), mean);
    if (d > best_dot) best = k, best_dot = d;
  }
  return best;
}

// The map rows, the file's axes and its units from the anatomy.
BvhNaming finish(const BvhMotion& motion, Anatomy a, std::string family) {
  BvhNaming out;
  out.family = std::move(family);
  auto name_of = [&](std::int32_t j) { return j < 0 ? std::string() : motion.joints[static_cast<std::size_t>(j)].name; };
  const std::vector<glm::vec3> rest = motion.rest_positions();
  const auto children = children_of(motion);

  out.map.push_back({name_of(a.pelvis), "HumanoidRoot", "", ""});
  if (a.vl5 >= 0) out.map.push_back({name_of(a.vl5), "vl5", "", ""});
  if (a.vt6 >= 0) out.map.push_back({name_of(a.vt6), "vt6", "", ""});
  if (a.neck >= 0) out.map.push_back({name_of(a.neck), "vc4", "", ""});
  if (a.head >= 0) out.map.push_back({name_of(a.head), "skullbase", "", ""});
  for (int s = 0; s < 2; ++s) {
    Anatomy::Side& d = a.sides[s];
    const std::string h = s == 0 ? "l_" : "r_";
    if (d.hand_aim < 0) d.hand_aim = middle_child(rest, children, d.wrist);
    // A row aims at the next mapped joint down the limb; with none mapped, at the BVH joint's End Site or first
    // child (an empty bvh_aim, motion/retarget.h).
    if (d.collar >= 0) out.map.push_back({name_of(d.collar), h + "sternoclavicular", name_of(d.shoulder), h + "shoulder"});
    if (d.shoulder >= 0) out.map.push_back({name_of(d.shoulder), h + "shoulder", name_of(d.elbow), h + "elbow"});
    if (d.elbow >= 0) out.map.push_back({name_of(d.elbow), h + "elbow", name_of(d.wrist), h + "wrist"});
    if (d.wrist >= 0) out.map.push_back({name_of(d.wrist), h + "wrist", name_of(d.hand_aim), h + "hand_tip"});
    out.map.push_back({name_of(d.hip), h + "hip", name_of(d.knee), h + "knee"});
    out.map.push_back({name_of(d.knee), h + "knee", name_of(d.ankle), h + "ankle"});
    if (d.toe >= 0) {
      // A foot with a toe joint aims at it, as H-Anim's ankle at its midtarsal; the toe then carries the tip.
      out.map.push_back({name_of(d.ankle), h + "ankle", name_of(d.toe), h + "midtarsal"});
      out.map.push_back({name_of(d.toe), h + "midtarsal", "", h + "forefoot_tip", false});
    } else {
      out.map.push_back({name_of(d.ankle), h + "ankle", "", h + "forefoot_tip"});
    }
  }

  // Axes and units from the rest pose. Up is the root to the neck, or the feet to the root without a neck.
  const glm::vec3 left = rest[a.sides[0].hip] - rest[a.sides[1].hip];
  const glm::vec3 up = a.neck >= 0 ? rest[a.neck] - rest[a.pelvis]
                                   : rest[a.pelvis] - 0.5f * (rest[a.sides[0].ankle] + rest[a.sides[1].ankle]);
  out.axes = bvh_file_axes(left, up);
  float lo = 1e30f, hi = -1e30f;
  for (std::size_t j = 0; j < motion.joint_count(); ++j) {
    const float y = (out.axes * rest[j]).y;
    lo = std::min(lo, y);
    hi = std::max(hi, y);
    if (motion.joints[j].has_end_site) {
      // An End Site's offset is in its joint's rest axes, which at rest are the file's.
      const float e = (out.axes * (rest[j] + motion.joints[j].end_site)).y;
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
  }
  out.stature = hi - lo;
  // A standing adult is 1.0-2.5 m: the unit that puts the stature there.
  struct Unit {
    const char* name;
    float metres;
  };
  for (const Unit u : {Unit{"metres", 1.0f}, Unit{"centimetres", 0.01f}, Unit{"millimetres", 0.001f},
                       Unit{"inches", 0.0254f}}) {
    const float m = out.stature * u.metres;
    if (m >= 1.0f && m <= 2.5f) {
      out.units = u.name;
      out.metres_per_unit = u.metres;
      break;
    }
  }
  if (out.units.empty()) out.units = "unknown";
  return out;
}

// ---- by name -----------------------------------------------------------------------------------------------------
// Fills `a` from the joint names; returns the H-Anim joints no name matched (HumanoidRoot when the thighs share no
// parent, vc4 when the neck does not hang from the root).
std::vector<std::string> anatomy_by_name(const BvhMotion& motion, Anatomy& a, std::string& family) {
  std::vector<std::int32_t> parents(motion.joint_count());
  std::vector<std::string> names(motion.joint_count());
  for (std::size_t j = 0; j < motion.joint_count(); ++j) {
    parents[j] = motion.joints[j].parent;
    names[j] = motion.joints[j].name;
  }
  return find_humanoid_by_names(parents, names, a, family);
}

// ---- by shape ----------------------------------------------------------------------------------------------------
// Names unknown: the skeleton read from its rest pose (components/humanoid_shape.h), the feet's End Sites giving the
// forward direction. Returns "" on success, else why the shape could not be read.
std::string anatomy_by_shape(const BvhMotion& motion, Anatomy& a, std::string& family) {
  std::vector<std::int32_t> parents(motion.joint_count());
  std::vector<glm::vec3> tips = motion.rest_positions();
  const std::vector<glm::vec3> rest = tips;
  for (std::size_t j = 0; j < motion.joint_count(); ++j) {
    parents[j] = motion.joints[j].parent;
    if (motion.joints[j].has_end_site) tips[j] += motion.joints[j].end_site;
  }
  const std::string why = find_humanoid_by_shape(parents, rest, tips, a);
  if (!why.empty()) return why;
  family = a.facing_assumed ? "by shape (names not recognised; facing +Z assumed)" : "by shape (names not recognised)";
  return {};
}

}  // namespace

BvhNaming recognise_bvh_naming(const BvhMotion& motion) {
  Anatomy by_name;
  std::string family;
  const std::vector<std::string> unmatched = anatomy_by_name(motion, by_name, family);
  if (unmatched.empty()) return finish(motion, by_name, family);
  Anatomy by_shape;
  const std::string why = anatomy_by_shape(motion, by_shape, family);
  if (why.empty()) return finish(motion, by_shape, family);
  std::string hanim;
  for (const std::string& u : unmatched) {
    if (!hanim.empty()) hanim += ", ";
    hanim += u;
  }
  throw std::invalid_argument("retarget: " + motion.source + ": cannot map the capture's joints: no joint name matched " +
                              hanim + " (families known: Poser/DAZ, CMU, Mixamo, HumanIK), and by shape: " + why +
                              "; pass --retarget-map FILE with one 'BVH_JOINT H-ANIM_JOINT' row per joint "
                              "(docs/motion.md)");
}

BvhNaming bvh_naming_from_map(const BvhMotion& motion, const RetargetMapFile& file) {
  Anatomy a;
  std::map<std::string, std::int32_t> rows;  // H-Anim 1.1 name -> BVH joint
  for (const RetargetMapRow& row : file.rows) {
    const std::int32_t b = motion.find_joint(row.bvh);
    if (b < 0)
      throw LoadError(file.source + ":" + std::to_string(row.line) + ": " + motion.source + " has no joint '" +
                      row.bvh + "'");
    rows[std::string(canonical_joint_name(row.hanim))] = b;
  }
  auto at = [&](const std::string& hanim) {
    const auto it = rows.find(hanim);
    return it == rows.end() ? -1 : it->second;
  };
  a.pelvis = at("HumanoidRoot"), a.vl5 = at("vl5"), a.vt6 = at("vt6"), a.neck = at("vc4"), a.head = at("skullbase");
  for (int s = 0; s < 2; ++s) {
    const std::string h = s == 0 ? "l_" : "r_";
    Anatomy::Side& d = a.sides[s];
    d.collar = at(h + "sternoclavicular"), d.shoulder = at(h + "shoulder"), d.elbow = at(h + "elbow");
    d.wrist = at(h + "wrist"), d.hip = at(h + "hip"), d.knee = at(h + "knee"), d.ankle = at(h + "ankle");
    d.toe = at(h + "midtarsal");
  }
  // A child row must hang below its parent row in the capture, or its bone would aim backwards.
  for (int s = 0; s < 2; ++s) {
    const Anatomy::Side& d = a.sides[s];
    const std::pair<std::int32_t, std::int32_t> links[] = {{a.pelvis, d.hip}, {d.hip, d.knee}, {d.knee, d.ankle},
                                                          {d.ankle, d.toe}, {d.collar, d.shoulder},
                                                          {d.shoulder, d.elbow}, {d.elbow, d.wrist}};
    for (const auto& [upper, lower] : links)
      if (upper >= 0 && lower >= 0 && !is_ancestor(motion, upper, lower))
        throw LoadError(file.source + ": '" + motion.joints[lower].name + "' does not hang from '" +
                        motion.joints[upper].name + "' in " + motion.source);
  }
  return finish(motion, a, "map " + file.source);
}

}  // namespace strata
