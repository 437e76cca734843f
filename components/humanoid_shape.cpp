#include "components/humanoid_shape.h"

#include <algorithm>
#include <cctype>
#include <initializer_list>
#include <string_view>

#include <glm/geometric.hpp>

#include "components/skeleton.h"

namespace strata {

// The rules: the pelvis is the first joint from the root where three or more chains branch; of its chains, the one
// that branches again (at the chest: neck and two arms) is the spine and the two tallest others are the legs. Down
// a leg the thigh and shin are the two consecutive bones of greatest total length (a CMU leg starts with a short
// hip bone, a Poser one with a buttock); the arm likewise (upper arm and forearm; the bone before them is the
// collar). The neck is the chest's chain whose joints lie highest above the chest; the head is where the neck's
// single chain ends or branches (eyes). Left is the side up x forward points to, forward taken from the feet
// (ankle to the end of the foot); a skeleton whose feet show no forward direction is taken to face +Z (the BVH and
// glTF conventions) and says so. Rejected: matching against a template skeleton by joint count or bone lengths,
// which fails on every rig with extra twist or helper joints.
std::string find_humanoid_by_shape(std::span<const std::int32_t> parents, std::span<const glm::vec3> rest,
                                   std::span<const glm::vec3> tips, HumanoidShape& a) {
  const std::size_t n = parents.size();
  if (n == 0 || rest.size() != n || (!tips.empty() && tips.size() != n)) return "an empty or inconsistent skeleton";
  std::vector<std::vector<std::int32_t>> children(n);
  for (std::size_t j = 1; j < n; ++j) {
    if (parents[j] < 0 || static_cast<std::size_t>(parents[j]) >= j) return "joints not in topological order";
    children[static_cast<std::size_t>(parents[j])].push_back(static_cast<std::int32_t>(j));
  }
  // Height of each joint's subtree in joints (a leaf is 1) and its size, from the leaves up.
  std::vector<int> height(n, 1), size(n, 1);
  for (std::size_t j = n; j-- > 0;)
    for (const std::int32_t c : children[j]) {
      height[j] = std::max(height[j], height[c] + 1);
      size[j] += size[c];
    }
  auto first_branch = [&](std::int32_t from, std::size_t branches) {
    for (std::int32_t j = from; j >= 0;) {
      if (children[j].size() >= branches) return j;
      if (children[j].size() != 1) return -1;
      j = children[j][0];
    }
    return -1;
  };
  // Down the tallest chain from `from`.
  auto chain_from = [&](std::int32_t from) {
    std::vector<std::int32_t> chain;
    for (std::int32_t j = from; j >= 0;) {
      chain.push_back(j);
      std::int32_t next = -1;
      for (const std::int32_t c : children[j])
        if (next < 0 || height[c] > height[next]) next = c;
      j = next;
    }
    return chain;
  };
  // Index i of the two consecutive bones chain[i] -> chain[i+2] of greatest total length; -1 when too short.
  auto longest_pair = [&](const std::vector<std::int32_t>& chain) {
    int best = -1;
    float best_len = 0.0f;
    for (std::size_t i = 0; i + 2 < chain.size(); ++i) {
      const float len = glm::length(rest[chain[i + 1]] - rest[chain[i]]) +
                        glm::length(rest[chain[i + 2]] - rest[chain[i + 1]]);
      if (len > best_len) best = static_cast<int>(i), best_len = len;
    }
    return best;
  };

  const std::int32_t pelvis = first_branch(0, 3);
  if (pelvis < 0) return "no joint where the legs and the spine branch (three chains from one joint)";
  std::int32_t spine_child = -1, chest = -1;
  for (const std::int32_t c : children[pelvis]) {
    const std::int32_t branch = first_branch(c, 3);
    if (branch >= 0 && (spine_child < 0 || size[c] > size[spine_child])) spine_child = c, chest = branch;
  }
  if (spine_child < 0) return "no chain from the pelvis that branches into a neck and two arms";
  std::vector<std::int32_t> legs;
  for (const std::int32_t c : children[pelvis])
    if (c != spine_child) legs.push_back(c);
  std::stable_sort(legs.begin(), legs.end(), [&](std::int32_t x, std::int32_t y) { return height[x] > height[y]; });
  if (legs.size() < 2 || height[legs[1]] < 3) return "the pelvis has fewer than two chains of three joints (legs)";
  legs.resize(2);

  const glm::vec3 up_guess = rest[chest] - rest[pelvis];
  if (!(glm::length(up_guess) > 0.0f)) return "the chest and the pelvis are at one point";
  std::int32_t neck = -1;
  float neck_rise = -1e30f;
  for (const std::int32_t c : children[chest]) {
    glm::vec3 mean(0.0f);
    const std::vector<std::int32_t> chain = chain_from(c);
    for (const std::int32_t j : chain) mean += rest[j];
    const float rise = glm::dot(mean / static_cast<float>(chain.size()) - rest[chest], up_guess);
    if (rise > neck_rise) neck = c, neck_rise = rise;
  }
  std::vector<std::int32_t> arms;
  for (const std::int32_t c : children[chest])
    if (c != neck) arms.push_back(c);
  std::stable_sort(arms.begin(), arms.end(), [&](std::int32_t x, std::int32_t y) { return height[x] > height[y]; });
  if (arms.size() < 2 || height[arms[1]] < 3) return "the chest has fewer than two chains of three joints (arms)";
  arms.resize(2);

  HumanoidShape::Side found_legs[2], found_arms[2];
  glm::vec3 forward(0.0f);
  for (int k = 0; k < 2; ++k) {
    const std::vector<std::int32_t> chain = chain_from(legs[k]);
    const int i = longest_pair(chain);
    if (i < 0) return "a leg chain is too short";
    HumanoidShape::Side& leg = found_legs[k];
    leg.hip = chain[i], leg.knee = chain[i + 1], leg.ankle = chain[i + 2];
    if (static_cast<std::size_t>(i) + 3 < chain.size()) leg.toe = chain[i + 3];
    const glm::vec3 tip = tips.empty() ? rest[chain.back()] : tips[chain.back()];
    forward += tip - rest[leg.ankle];
    const std::vector<std::int32_t> arm = chain_from(arms[k]);
    const int a_i = longest_pair(arm);
    if (a_i < 0) return "an arm chain is too short";
    HumanoidShape::Side& side = found_arms[k];
    side.shoulder = arm[a_i], side.elbow = arm[a_i + 1], side.wrist = arm[a_i + 2];
    // The collar is the joint before the shoulder, past any zero-length helper at the shoulder itself (a roll bone
    // written where the shoulder is), whose bone would give the collar no direction.
    int c = a_i - 1;
    while (c >= 0 && glm::length(rest[arm[c + 1]] - rest[arm[c]]) < 1e-4f * (1.0f + glm::length(rest[arm[c]]))) --c;
    if (c >= 0) side.collar = arm[c];
  }
  const glm::vec3 up = glm::normalize(up_guess);
  forward -= glm::dot(forward, up) * up;
  const float leg_length = glm::length(rest[found_legs[0].ankle] - rest[found_legs[0].hip]);
  glm::vec3 left;
  a.facing_assumed = !(glm::length(forward) > 0.1f * leg_length);
  if (!a.facing_assumed)
    left = glm::cross(up, glm::normalize(forward));
  else
    left = glm::vec3(1, 0, 0) - glm::dot(glm::vec3(1, 0, 0), up) * up;  // faces +Z: +X is the left
  auto side_of = [&](std::int32_t j) { return glm::dot(rest[j] - rest[pelvis], left); };
  const bool legs_swapped = side_of(found_legs[0].hip) < side_of(found_legs[1].hip);
  const bool arms_swapped = side_of(found_arms[0].shoulder) < side_of(found_arms[1].shoulder);
  if (side_of(found_legs[0].hip) == side_of(found_legs[1].hip)) return "the two legs are on one side of the body";
  for (int s = 0; s < 2; ++s) {
    a.sides[s] = found_legs[(s == 0) != legs_swapped ? 0 : 1];
    const HumanoidShape::Side& arm = found_arms[(s == 0) != arms_swapped ? 0 : 1];
    a.sides[s].collar = arm.collar, a.sides[s].shoulder = arm.shoulder, a.sides[s].elbow = arm.elbow,
    a.sides[s].wrist = arm.wrist;
  }

  // The neck's chain: on while it does not branch; the head is where it ends or branches.
  std::int32_t head = neck;
  while (children[head].size() == 1) head = children[head][0];
  a.pelvis = pelvis;
  a.neck = neck;
  a.head = head != neck ? head : -1;
  std::vector<std::int32_t> spine;
  for (std::int32_t j = parents[static_cast<std::size_t>(neck)]; j >= 0 && j != pelvis;
       j = parents[static_cast<std::size_t>(j)])
    spine.insert(spine.begin(), j);
  a.vl5 = spine.empty() ? -1 : spine.front();
  a.vt6 = spine.size() >= 2 ? spine.back() : -1;
  return {};
}

std::string normalised_joint_name(std::string_view name) {
  const std::size_t colon = name.rfind(':');
  if (colon != std::string_view::npos) name.remove_prefix(colon + 1);
  std::string out(name);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The families' names, per H-Anim joint, tried in order (motion/bvh_naming.h has the table by family): Poser's
// one-letter side prefix first, then the "Left"/"Right" word the others share. Compared normalised, so Mixamo's
// "mixamorig:LeftUpLeg" is "leftupleg". Rejected: a table per family tried in turn, which refuses the many files
// that mix families' names (a MotionBuilder export with 3ds Max leg names).
std::vector<std::string> find_humanoid_by_names(std::span<const std::int32_t> parents,
                                                std::span<const std::string> joint_names, HumanoidShape& a,
                                                std::string& family) {
  const std::size_t n = parents.size();
  if (joint_names.size() != n) return {"HumanoidRoot"};
  std::vector<std::string> names(n);
  for (std::size_t j = 0; j < n; ++j) names[j] = normalised_joint_name(joint_names[j]);
  auto find = [&](std::initializer_list<std::string> candidates) -> std::int32_t {
    for (const std::string& c : candidates)
      for (std::size_t j = 0; j < n; ++j)
        if (names[j] == c) return static_cast<std::int32_t>(j);
    return -1;
  };
  auto has = [&](std::string_view name) { return std::find(names.begin(), names.end(), name) != names.end(); };
  auto is_ancestor = [&](std::int32_t ancestor, std::int32_t j) {
    for (std::size_t steps = 0; j >= 0 && static_cast<std::size_t>(j) < n && steps <= n; ++steps) {
      if (j == ancestor) return true;
      j = parents[static_cast<std::size_t>(j)];
    }
    return false;
  };
  std::vector<std::string> unmatched;
  auto require = [&](const std::string& hanim, std::initializer_list<std::string> candidates) {
    const std::int32_t j = find(candidates);
    if (j < 0) unmatched.push_back(hanim);
    return j;
  };
  HumanoidShape found;
  for (int s = 0; s < 2; ++s) {
    const std::string p = s == 0 ? "l" : "r", w = s == 0 ? "left" : "right", h = s == 0 ? "l_" : "r_";
    HumanoidShape::Side& side = found.sides[s];
    side.collar = require(h + "sternoclavicular", {p + "collar", w + "shoulder", w + "collar", w + "clavicle"});
    side.shoulder = require(h + "shoulder", {p + "shldr", w + "arm", w + "upperarm"});
    side.elbow = require(h + "elbow", {p + "forearm", w + "forearm", w + "lowerarm"});
    side.wrist = require(h + "wrist", {p + "hand", w + "hand"});
    side.hip = require(h + "hip", {p + "thigh", w + "upleg", w + "hip", w + "thigh", w + "upperleg"});
    side.knee = require(h + "knee", {p + "shin", w + "leg", w + "knee", w + "lowerleg", w + "calf"});
    side.ankle = require(h + "ankle", {p + "foot", w + "foot", w + "ankle"});
    side.toe = find({p + "toe", w + "toebase", w + "toe"});
    // The hand's direction: its middle finger where there is one.
    side.hand_aim = find({p + "mid1", w + "handmiddle1", w + "middle1", w + "handmiddle", w + "fingerbase"});
    if (side.hand_aim >= 0 && side.wrist >= 0 && !is_ancestor(side.wrist, side.hand_aim)) side.hand_aim = -1;
    if (side.toe >= 0 && side.ankle >= 0 && !is_ancestor(side.ankle, side.toe)) side.toe = -1;
  }
  found.neck = require("vc4", {"neck", "neck1"});
  found.head = require("skullbase", {"head"});
  if (!unmatched.empty()) return unmatched;

  // The pelvis: the hips by name, else the nearest joint both thighs hang from (a root called anything).
  std::int32_t pelvis = find({"hips", "hip", "pelvis"});
  if (pelvis < 0 || !is_ancestor(pelvis, found.sides[0].hip) || !is_ancestor(pelvis, found.sides[1].hip)) {
    pelvis = parents[static_cast<std::size_t>(found.sides[0].hip)];
    while (pelvis >= 0 && !is_ancestor(pelvis, found.sides[1].hip)) pelvis = parents[static_cast<std::size_t>(pelvis)];
    if (pelvis < 0) return {"HumanoidRoot"};
  }
  if (!is_ancestor(pelvis, found.neck)) return {"vc4"};
  found.pelvis = pelvis;
  // The spine by position: the joints strictly between the pelvis and the neck, lowest first.
  std::vector<std::int32_t> spine;
  for (std::int32_t j = parents[static_cast<std::size_t>(found.neck)]; j >= 0 && j != pelvis;
       j = parents[static_cast<std::size_t>(j)])
    spine.insert(spine.begin(), j);
  if (!spine.empty()) found.vl5 = spine.front();
  if (spine.size() >= 2) found.vt6 = spine.back();

  // The family, for the user: told by the names only one family uses.
  bool prefixed = false;
  for (const std::string& name : joint_names)
    prefixed |= name.find(':') != std::string::npos && normalised_joint_name(name.substr(0, 9)) == "mixamorig";
  const std::string& thigh = names[static_cast<std::size_t>(found.sides[0].hip)];
  if (prefixed)
    family = "Mixamo";
  else if (thigh == "lthigh")
    family = "Poser/DAZ";
  else if (has("lhipjoint") || has("lowerback"))
    family = thigh == "lefthip" ? "CMU (3ds Max)" : "CMU (MotionBuilder)";
  else if (thigh == "leftupleg")
    family = "HumanIK";
  else
    family = "generic (Left/Right names)";
  a = found;
  return {};
}

bool name_humanoid_joints(Skeleton& skeleton, std::string* why) {
  auto say = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (skeleton.find_joint("l_hip") >= 0 && skeleton.find_joint("l_shoulder") >= 0)
    return say("the skeleton already has H-Anim limb names");
  // Names first: a rig exported from a known tool says what its joints are, where the shape rules only infer it
  // (and infer wrongly on a rig posed far from a T or A pose). The names are the file's own (source_joint_names).
  HumanoidShape shape;
  std::string family;
  std::string how;
  // The limbs the IK builds must be parent-child chains; a rig with roll helpers between its named upper arm and
  // forearm is left to the shape rules, which take the helper the forearm hangs from as the shoulder.
  auto chains_direct = [&](const HumanoidShape& h) {
    for (const HumanoidShape::Side& d : h.sides)
      if (skeleton.parents[static_cast<std::size_t>(d.knee)] != d.hip ||
          skeleton.parents[static_cast<std::size_t>(d.ankle)] != d.knee ||
          skeleton.parents[static_cast<std::size_t>(d.elbow)] != d.shoulder ||
          skeleton.parents[static_cast<std::size_t>(d.wrist)] != d.elbow)
        return false;
    return true;
  };
  if (find_humanoid_by_names(skeleton.parents, skeleton.source_joint_names, shape, family).empty() &&
      chains_direct(shape)) {
    how = "by their " + family + " names";
  } else {
    shape = HumanoidShape{};
    const std::string problem = find_humanoid_by_shape(skeleton.parents, skeleton.centers, {}, shape);
    if (!problem.empty()) return say("its joint names are no known family's, and by shape: " + problem);
    how = std::string("by the skeleton's shape") + (shape.facing_assumed ? " (facing +Z assumed)" : "");
  }
  std::vector<std::pair<std::int32_t, std::string>> names;
  // The pelvis is the root's name when it is the root; below another root (an armature, a synthetic skin root) it
  // is the sacroiliac the legs hang from, as in H-Anim.
  names.emplace_back(shape.pelvis, shape.pelvis == 0 ? "HumanoidRoot" : "sacroiliac");
  if (shape.pelvis != 0) names.emplace_back(0, "HumanoidRoot");
  if (shape.vl5 >= 0) names.emplace_back(shape.vl5, "vl5");
  if (shape.vt6 >= 0) names.emplace_back(shape.vt6, "vt6");
  names.emplace_back(shape.neck, "vc4");
  if (shape.head >= 0) names.emplace_back(shape.head, "skullbase");
  for (int s = 0; s < 2; ++s) {
    const HumanoidShape::Side& d = shape.sides[s];
    const std::string h = s == 0 ? "l_" : "r_";
    if (d.collar >= 0) names.emplace_back(d.collar, h + "sternoclavicular");
    names.emplace_back(d.shoulder, h + "shoulder");
    names.emplace_back(d.elbow, h + "elbow");
    names.emplace_back(d.wrist, h + "wrist");
    names.emplace_back(d.hip, h + "hip");
    names.emplace_back(d.knee, h + "knee");
    names.emplace_back(d.ankle, h + "ankle");
    if (d.toe >= 0) names.emplace_back(d.toe, h + "midtarsal");
  }
  // A joint that already carries one of these names elsewhere keeps the rig unchanged: two joints of one name would
  // make every lookup ambiguous.
  std::vector<std::string> renamed = skeleton.joint_names;
  for (const auto& [joint, name] : names) renamed[static_cast<std::size_t>(joint)] = name;
  std::vector<std::string> sorted = renamed;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    return say("the H-Anim names found by shape would repeat a joint name already in the rig");
  std::string list;
  for (const auto& [joint, name] : names) {
    if (!list.empty()) list += ", ";
    list += skeleton.source_joint_names[static_cast<std::size_t>(joint)] + " -> " + name;
  }
  skeleton.joint_names = std::move(renamed);
  skeleton.warnings.push_back(skeleton.source + ": joints named " + how + ": " + list);
  if (why) why->clear();
  return true;
}

}  // namespace strata
