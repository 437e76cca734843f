#include "motion/bvh_naming.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace strata {

std::string normalised_joint_name(std::string_view name) {
  const std::size_t colon = name.rfind(':');
  if (colon != std::string_view::npos) name.remove_prefix(colon + 1);
  std::string out(name);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

namespace {

// The BVH's joint names, normalised once; lookups by the first of several candidate names.
struct NameIndex {
  const BvhMotion& motion;
  std::vector<std::string> names;
  explicit NameIndex(const BvhMotion& m) : motion(m) {
    names.reserve(m.joint_count());
    for (const BvhJoint& j : m.joints) names.push_back(normalised_joint_name(j.name));
  }
  std::int32_t find(const std::vector<std::string>& candidates) const {
    for (const std::string& c : candidates)
      for (std::size_t j = 0; j < names.size(); ++j)
        if (names[j] == c) return static_cast<std::int32_t>(j);
    return -1;
  }
  bool has(std::string_view n) const { return std::find(names.begin(), names.end(), n) != names.end(); }
  bool is_ancestor(std::int32_t ancestor, std::int32_t j) const {
    for (; j >= 0; j = motion.joints[static_cast<std::size_t>(j)].parent)
      if (j == ancestor) return true;
    return false;
  }
};

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
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

BvhNaming recognise_bvh_naming(const BvhMotion& motion) {
  const NameIndex index(motion);
  BvhNaming out;
  std::vector<std::string> unmatched;
  auto name_of = [&](std::int32_t j) { return motion.joints[static_cast<std::size_t>(j)].name; };
  auto require = [&](const char* hanim, const std::vector<std::string>& candidates) {
    const std::int32_t j = index.find(candidates);
    if (j < 0) unmatched.push_back(std::string(hanim) + " (tried " + joined(candidates) + ")");
    return j;
  };

  // Limbs, per side: Poser's one-letter prefix, then the "Left"/"Right" word of the other families.
  struct Side {
    std::int32_t collar, shoulder, elbow, wrist, hand_aim, hip, knee, ankle, toe;
  };
  Side sides[2];
  for (int s = 0; s < 2; ++s) {
    const std::string p = s == 0 ? "l" : "r", w = s == 0 ? "left" : "right", h = s == 0 ? "l_" : "r_";
    Side& side = sides[s];
    side.collar = require((h + "sternoclavicular").c_str(), {p + "collar", w + "shoulder", w + "collar", w + "clavicle"});
    side.shoulder = require((h + "shoulder").c_str(), {p + "shldr", w + "arm", w + "upperarm"});
    side.elbow = require((h + "elbow").c_str(), {p + "forearm", w + "forearm", w + "lowerarm"});
    side.wrist = require((h + "wrist").c_str(), {p + "hand", w + "hand"});
    side.hip = require((h + "hip").c_str(), {p + "thigh", w + "upleg", w + "hip", w + "thigh", w + "upperleg"});
    side.knee = require((h + "knee").c_str(), {p + "shin", w + "leg", w + "knee", w + "lowerleg", w + "calf"});
    side.ankle = require((h + "ankle").c_str(), {p + "foot", w + "foot", w + "ankle"});
    side.toe = index.find({p + "toe", w + "toebase", w + "toe"});
    // The hand's direction: its middle finger where the file has one, else its first child or End Site.
    side.hand_aim = index.find({p + "mid1", w + "handmiddle1", w + "middle1", w + "handmiddle", w + "fingerbase"});
    if (side.hand_aim >= 0 && side.wrist >= 0 && !index.is_ancestor(side.wrist, side.hand_aim)) side.hand_aim = -1;
    if (side.toe >= 0 && side.ankle >= 0 && !index.is_ancestor(side.ankle, side.toe)) side.toe = -1;
  }
  const std::int32_t neck = require("vc4", {"neck", "neck1"});
  const std::int32_t head = require("skullbase", {"head"});
  if (!unmatched.empty())
    throw std::invalid_argument("retarget: " + motion.source + ": no joint matched for " + joined(unmatched) +
                                "; the file's joints are not a naming family Strata knows (Poser/DAZ, CMU, Mixamo, "
                                "HumanIK)");

  // The root: the hips by name, else the nearest joint both thighs hang from (a root called anything).
  std::int32_t root = index.find({"hips", "hip", "pelvis"});
  if (root < 0 || !index.is_ancestor(root, sides[0].hip) || !index.is_ancestor(root, sides[1].hip)) {
    root = motion.joints[static_cast<std::size_t>(sides[0].hip)].parent;
    while (root >= 0 && !index.is_ancestor(root, sides[1].hip)) root = motion.joints[static_cast<std::size_t>(root)].parent;
    if (root < 0)
      throw std::invalid_argument("retarget: " + motion.source + ": the thighs '" + name_of(sides[0].hip) + "' and '" +
                                  name_of(sides[1].hip) + "' share no parent joint");
  }
  if (!index.is_ancestor(root, neck))
    throw std::invalid_argument("retarget: " + motion.source + ": the neck '" + name_of(neck) +
                                "' does not hang from the hips '" + name_of(root) + "'");
  // The spine by position: the joints strictly between the root and the neck, lowest first.
  std::vector<std::int32_t> spine;
  for (std::int32_t j = motion.joints[static_cast<std::size_t>(neck)].parent; j >= 0 && j != root;
       j = motion.joints[static_cast<std::size_t>(j)].parent)
    spine.insert(spine.begin(), j);

  out.map.push_back({name_of(root), "HumanoidRoot", "", ""});
  if (!spine.empty()) out.map.push_back({name_of(spine.front()), "vl5", "", ""});
  if (spine.size() >= 2) out.map.push_back({name_of(spine.back()), "vt6", "", ""});
  out.map.push_back({name_of(neck), "vc4", "", ""});
  out.map.push_back({name_of(head), "skullbase", "", ""});
  for (int s = 0; s < 2; ++s) {
    const Side& d = sides[s];
    const std::string h = s == 0 ? "l_" : "r_";
    out.map.push_back({name_of(d.collar), h + "sternoclavicular", name_of(d.shoulder), h + "shoulder"});
    out.map.push_back({name_of(d.shoulder), h + "shoulder", name_of(d.elbow), h + "elbow"});
    out.map.push_back({name_of(d.elbow), h + "elbow", name_of(d.wrist), h + "wrist"});
    out.map.push_back({name_of(d.wrist), h + "wrist", d.hand_aim >= 0 ? name_of(d.hand_aim) : "", h + "hand_tip"});
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

  // The family, for the user: told by the names that only one family uses.
  bool prefixed = false;
  for (const BvhJoint& j : motion.joints) prefixed |= j.name.find(':') != std::string::npos &&
                                                      normalised_joint_name(j.name.substr(0, 9)) == "mixamorig";
  const std::string thigh = index.names[static_cast<std::size_t>(sides[0].hip)];
  if (prefixed)
    out.family = "Mixamo";
  else if (thigh == "lthigh")
    out.family = "Poser/DAZ";
  else if (index.has("lhipjoint") || index.has("lowerback"))
    out.family = thigh == "lefthip" ? "CMU (3ds Max)" : "CMU (MotionBuilder)";
  else if (thigh == "leftupleg")
    out.family = "HumanIK";
  else
    out.family = "generic (Left/Right names)";

  // Axes and units from the rest pose.
  const std::vector<glm::vec3> rest = motion.rest_positions();
  out.axes = bvh_file_axes(rest[static_cast<std::size_t>(sides[0].hip)] - rest[static_cast<std::size_t>(sides[1].hip)],
                           rest[static_cast<std::size_t>(neck)] - rest[static_cast<std::size_t>(root)]);
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

}  // namespace strata
