#include "motion/retarget.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include "components/shortest_arc.h"
#include "motion/bvh_naming.h"

namespace strata {
namespace {

// Rest position of an aim target: an H-Anim joint centre or site.
glm::vec3 hanim_point(const Skeleton& s, const std::string& name) {
  const std::int32_t j = s.find_joint(name);
  if (j >= 0) return s.centers[j];
  const std::int32_t site = s.find_site(name);
  if (site >= 0) return s.sites[site].position;
  throw std::invalid_argument("retarget: skeleton has no joint or site '" + name + "'");
}

// Where H-Anim joint h's bone points at rest: at `aim` (a joint or site) where the skeleton has it. Many real
// skeletons lack the default's sites (Joe has no l_hand_tip) or joints (Humanoid1 has no l_midtarsal): then at the
// child of h nearest its children's mean direction (the middle finger of a hand, the toe of a foot), and a joint
// with no child continues its parent's bone (a foot without one points forward, +Z).
glm::vec3 bone_aim_point(const Skeleton& s, std::int32_t h, const std::string& aim) {
  if (s.find_joint(aim) >= 0 || s.find_site(aim) >= 0) return hanim_point(s, aim);
  const glm::vec3 from = s.centers[h];
  std::vector<glm::vec3> directions;
  for (std::size_t c = static_cast<std::size_t>(h) + 1; c < s.joint_count(); ++c)
    if (s.parents[c] == h && glm::length(s.centers[c] - from) > 1e-6f) directions.push_back(s.centers[c] - from);
  if (!directions.empty()) {
    glm::vec3 mean(0.0f);
    for (const glm::vec3& d : directions) mean += glm::normalize(d);
    const glm::vec3* best = &directions[0];
    for (const glm::vec3& d : directions)
      if (glm::dot(glm::normalize(d), mean) > glm::dot(glm::normalize(*best), mean)) best = &d;
    return from + *best;
  }
  if (aim.find("forefoot_tip") != std::string::npos) return from + glm::vec3(0, 0, 0.1f);
  const std::int32_t parent = s.parents[static_cast<std::size_t>(h)];
  if (parent >= 0 && glm::length(from - s.centers[parent]) > 1e-6f) return from + (from - s.centers[parent]);
  throw std::invalid_argument("retarget: skeleton has no joint or site '" + aim + "', and joint '" +
                              s.joint_names[static_cast<std::size_t>(h)] + "' has no bone to aim along instead");
}

bool is_leg_or_root(std::string_view hanim) {
  const std::string_view c = canonical_joint_name(hanim);
  return c == "HumanoidRoot" || c.ends_with("_hip") || c.ends_with("_knee") || c.ends_with("_ankle");
}

// A point fixed to joint j's segment (rest position `rest`), in the posed humanoid space.
glm::vec3 posed_point(const Skeleton& s, std::span<const glm::quat> rot, std::span<const glm::vec3> pos, std::int32_t j,
                      const glm::vec3& rest) {
  return pos[j] + rot[j] * (rest - s.centers[j]);
}

struct SolePoints {
  std::int32_t joint_heel = -1, joint_toe = -1;
  glm::vec3 heel{0.0f}, toe{0.0f};
};

// The two points of a foot that carry it on the ground: the ball (the midtarsal centre, which lies on the sole in
// H-Anim's rest pose) and the heel's underside (the calcaneus site's x/z at the ball's rest height: the site marks
// the back of the heel, 2.6 cm above the sole in the default skeleton). The ball rather than the forefoot tip: the
// Poser foot ends 13 cm ahead of the ankle, where a real foot rolls at push-off, while H-Anim's tip is 22 cm ahead;
// with no toe joint driven, the tip of the rigid H-Anim foot dips 3-4 cm under the floor at push-off whereas the
// ball follows the capture. (A toe-break fix would bend the midtarsal there; not done.)
SolePoints sole_points(const Skeleton& s, std::int32_t ankle, char side) {
  SolePoints p;
  const std::string prefix(1, side);
  const std::int32_t midtarsal = s.find_joint(prefix + "_midtarsal");
  p.joint_toe = midtarsal >= 0 ? midtarsal : ankle;
  p.toe = midtarsal >= 0 ? s.centers[midtarsal] : s.centers[ankle];
  const std::int32_t heel = s.find_site(prefix + "_calcaneous_post_pt");
  p.joint_heel = ankle;
  p.heel = heel >= 0 ? glm::vec3(s.sites[heel].position.x, p.toe.y, s.sites[heel].position.z)
                     : glm::vec3(s.centers[ankle].x, p.toe.y, s.centers[ankle].z);
  return p;
}

}  // namespace

// The map built for a Poser file (the CMU Daz conversion) by motion/bvh_naming.cpp, onto the 25-joint H-Anim
// skeleton; the other families map the same joints under their own names:
//
//   BVH       H-Anim               bone direction (BVH / H-Anim)        notes
//   hip       HumanoidRoot         - / -                                rotation; position via the hip midpoint
//   abdomen   vl5                  - / -                                spine, neck and head: rest-relative (below)
//   chest     vt6                  - / -                                vt1 unmapped: rides on vt6 (the Poser chest
//                                                                       is one segment up to the neck)
//   neck      vc4                  - / -
//   head      skullbase            - / -
//   lCollar   l_sternoclavicular   lCollar->lShldr / l_sternoclavicular->l_shoulder (acromioclavicular unmapped)
//   lShldr    l_shoulder           lShldr->lForeArm / l_shoulder->l_elbow    the T-pose compensation is here
//   lForeArm  l_elbow              lForeArm->lHand / l_elbow->l_wrist
//   lHand     l_wrist              lHand->lMid1 / l_wrist->l_hand_tip
//   lThigh    l_hip                lThigh->lShin / l_hip->l_knee        lButtock folds into it (global rotations)
//   lShin     l_knee               lShin->lFoot / l_knee->l_ankle
//   lFoot     l_ankle              lFoot->End Site / l_ankle->l_forefoot_tip
//   lToe      l_midtarsal          (optional: absent in the CMU files, then midtarsal stays rigid with the ankle)
//   right side likewise (r prefix).
// Unmapped H-Anim joints: sacroiliac (the Poser hip is the pelvis: it drives HumanoidRoot, and the thighs hang from
// it), vt1, the acromioclavicular joints, and the midtarsals without toes. Unmapped BVH joints: the Buttocks (folded
// into the thighs), eyes and fingers (dropped: the 25-joint skeleton has no fingers).
// Spine, neck and head take the capture's rotations relative to its rest unchanged (identity alignment), unlike the
// limbs: both rest poses stand upright with the gaze level, and their spine bones point differently only because
// the joints sit differently (H-Anim's vt6 -> vc4 leans 22 deg forward along the thoracic curve, the Poser
// chest -> neck 6 deg back). Aiming the bones at each other turned that convention into posture: the chest leant
// 27 deg and the neck 20 deg back, and the walker looked at the sky. The limbs keep the bone alignment, which is
// where the rest poses really differ (T-pose arms against arms down).
// The abdomen -> vl5 choice over a sacroiliac/vl5 split: the Poser abdomen bends the spine above the pelvis, which
// is vl5's job; splitting it would invent a pelvis tilt the capture never recorded.
int FootContacts::stance_at(int leg, float t) const {
  const auto& intervals = legs[static_cast<std::size_t>(leg)];
  for (std::size_t i = 0; i < intervals.size(); ++i)
    if (t >= intervals[i].begin && t < intervals[i].end) return static_cast<int>(i);
  return -1;
}

void pose_globals(const Skeleton& skeleton, std::span<const glm::quat> local_rotations, const glm::vec3& root_translation,
                  std::span<glm::quat> global_rotations, std::span<glm::vec3> positions) {
  for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
    const std::int32_t p = skeleton.parents[j];
    if (p < 0) {
      global_rotations[j] = local_rotations[j];
      positions[j] = skeleton.centers[j] + root_translation;
    } else {
      global_rotations[j] = global_rotations[p] * local_rotations[j];
      positions[j] = positions[p] + global_rotations[p] * (skeleton.centers[j] - skeleton.centers[p]);
    }
  }
}

RetargetResult retarget_bvh(const BvhMotion& motion, const Skeleton& skeleton, const RetargetOptions& options) {
  const std::size_t skip = static_cast<std::size_t>(std::max(options.skip_frames, 0));
  if (motion.frame_count < skip + 2)
    throw std::invalid_argument("retarget: " + motion.source + " has " + std::to_string(motion.frame_count) +
                                " frames; at least 2 after skipping " + std::to_string(skip) + " are needed");
  const std::size_t hj = skeleton.joint_count();
  // The map: recognised from the names (and the file's axes with it) unless the caller gave one.
  BvhNaming naming;
  glm::mat3 axes = options.axes;
  naming.family = options.family;
  if (options.map.empty()) {
    naming = recognise_bvh_naming(motion);
    axes = naming.axes;
  }
  const std::vector<RetargetMapping>& map = options.map.empty() ? naming.map : options.map;
  // A file whose axes are not H-Anim's is turned as it is read: rest positions, End Sites, every frame's global
  // rotations (conjugated) and positions. Skipped when they agree, so such files keep their exact values.
  const bool turn = axes != glm::mat3(1.0f);
  const glm::quat turn_q = glm::quat_cast(axes);
  std::vector<glm::vec3> bvh_rest = motion.rest_positions();
  if (turn)
    for (glm::vec3& p : bvh_rest) p = axes * p;

  // Resolve the map and each row's alignment rotation once.
  std::vector<RetargetBone> bones;
  std::vector<std::string> skipped_on_rig;
  std::vector<RetargetBone> row_of(hj);
  std::vector<std::int32_t> bvh_of(hj, -1);
  for (const RetargetMapping& m : map) {
    const std::int32_t b = motion.find_joint(m.bvh);
    const std::int32_t h = skeleton.find_joint(m.hanim);
    // The rig may lack a spine, neck, collar or arm joint the 25-joint skeleton has (Humanoid1 has no vt6): that
    // row is left out, and the joints below it take the capture's global rotations through their own rows. Only
    // the root and the legs, which place the walker and carry the foot lock, are required of the rig.
    if (h < 0 && b >= 0 && !is_leg_or_root(m.hanim)) {
      skipped_on_rig.push_back(m.hanim);
      continue;
    }
    if (b < 0 || h < 0) {
      if (!m.required) continue;
      throw std::invalid_argument("retarget: map row " + m.bvh + " -> " + m.hanim + ": " +
                                  (b < 0 ? motion.source + " has no joint '" + m.bvh + "'"
                                         : "skeleton has no joint '" + m.hanim + "'"));
    }
    RetargetBone bone;
    bone.hanim = h;
    bone.bvh = b;
    if (!m.hanim_aim.empty()) {
      glm::vec3 bvh_dir;
      if (m.bvh_aim.empty()) {
        // Its End Site, else its first child joint (a foot that goes on to a toe, a hand to its fingers).
        std::int32_t child = -1;
        for (std::size_t c = static_cast<std::size_t>(b) + 1; c < motion.joint_count() && child < 0; ++c)
          if (motion.joints[c].parent == b) child = static_cast<std::int32_t>(c);
        if (motion.joints[b].has_end_site)
          bvh_dir = axes * motion.joints[b].end_site;
        else if (child >= 0)
          bvh_dir = bvh_rest[child] - bvh_rest[b];
        else
          throw std::invalid_argument("retarget: BVH joint '" + m.bvh + "' has no End Site or child to aim at");
      } else {
        const std::int32_t aim = motion.find_joint(m.bvh_aim);
        if (aim < 0) throw std::invalid_argument("retarget: " + motion.source + " has no joint '" + m.bvh_aim + "'");
        bvh_dir = bvh_rest[aim] - bvh_rest[b];
      }
      const glm::vec3 hanim_dir = bone_aim_point(skeleton, h, m.hanim_aim) - skeleton.centers[h];
      bone.align = shortest_arc(hanim_dir, bvh_dir);
      bone.aimed = true;
      bone.hanim_dir = glm::normalize(hanim_dir);
    }
    bones.push_back(bone);
    row_of[h] = bone;
    bvh_of[h] = b;
  }
  if (bvh_of[0] < 0) throw std::invalid_argument("retarget: the map does not drive the skeleton's root");

  // Units: leg length ratio (thigh + shin) of the left legs, so that the retargeted legs reach the ground.
  auto need = [&](const char* name) {
    const std::int32_t j = skeleton.find_joint(name);
    if (j < 0 || bvh_of[j] < 0) throw std::invalid_argument(std::string("retarget: no mapped joint ") + name);
    return j;
  };
  const std::int32_t l_hip = need("l_hip"), l_knee = need("l_knee"), l_ankle = need("l_ankle");
  const std::int32_t r_hip = need("r_hip"), r_ankle = need("r_ankle");
  const float hanim_leg = glm::length(skeleton.centers[l_knee] - skeleton.centers[l_hip]) +
                          glm::length(skeleton.centers[l_ankle] - skeleton.centers[l_knee]);
  const float bvh_leg = glm::length(bvh_rest[bvh_of[l_knee]] - bvh_rest[bvh_of[l_hip]]) +
                        glm::length(bvh_rest[bvh_of[l_ankle]] - bvh_rest[bvh_of[l_knee]]);
  if (!(bvh_leg > 0.0f)) throw std::invalid_argument("retarget: the BVH leg has zero length");
  const float scale = hanim_leg / bvh_leg;

  const std::size_t frames = motion.frame_count - skip;
  std::vector<std::vector<glm::quat>> locals(frames, std::vector<glm::quat>(hj));
  std::vector<glm::vec3> root(frames);
  std::vector<glm::quat> bvh_rot(motion.joint_count()), hanim_global(hj), global(hj);
  std::vector<glm::vec3> bvh_pos(motion.joint_count()), pos(hj);
  for (std::size_t k = 0; k < frames; ++k) {
    motion.pose(k + skip, bvh_rot, bvh_pos);
    if (turn) {
      for (glm::quat& q : bvh_rot) q = turn_q * q * glm::conjugate(turn_q);
      for (glm::vec3& p : bvh_pos) p = axes * p;
    }
    for (std::size_t h = 0; h < hj; ++h) {
      const std::int32_t p = skeleton.parents[h];
      const glm::quat parent = p < 0 ? glm::quat(1, 0, 0, 0) : hanim_global[p];
      hanim_global[h] = bvh_of[h] >= 0 ? glm::normalize(bvh_rot[bvh_of[h]] * row_of[h].align) : parent;
      glm::quat local = glm::normalize(glm::inverse(parent) * hanim_global[h]);
      // Keep consecutive keys in one hemisphere: the sampler slerps the short way anyway, but a track without sign
      // flips also blends correctly under plain component-wise averaging.
      if (k > 0 && glm::dot(local, locals[k - 1][h]) < 0.0f) local = -local;
      locals[k][h] = local;
    }
    // Root: with zero translation, where do the hips land? Shift so their midpoint sits on the scaled BVH thighs'.
    pose_globals(skeleton, locals[k], glm::vec3(0.0f), global, pos);
    const glm::vec3 hanim_mid = 0.5f * (pos[l_hip] + pos[r_hip]);
    const glm::vec3 bvh_mid = 0.5f * (bvh_pos[bvh_of[l_hip]] + bvh_pos[bvh_of[r_hip]]);
    root[k] = scale * bvh_mid - hanim_mid;
  }

  // Ground. The lowest sole point of each frame is a supporting foot in a walk (one foot is always down), so those
  // points sample the floor. The CMU floor is not level in the file's frame: the stance toe rises from 2.8 to 7.7
  // units over the 4 m walk (a ~1.2 % calibration tilt). A single offset would leave the feet 2-3 cm through the
  // floor at one end and above it at the other, so fit a line y = a + b * z through those points (least squares,
  // then once more without the points more than 2 cm off, which are the odd frames where no foot is planted) and
  // level it: each frame's root height drops by the floor height under the root.
  const SolePoints left_sole = sole_points(skeleton, l_ankle, 'l');
  const SolePoints right_sole = sole_points(skeleton, r_ankle, 'r');
  std::vector<glm::vec3> lowest(frames);
  for (std::size_t k = 0; k < frames; ++k) {
    pose_globals(skeleton, locals[k], root[k], global, pos);
    lowest[k] = glm::vec3(0.0f, 1e30f, 0.0f);
    for (const SolePoints* s : {&left_sole, &right_sole}) {
      for (const glm::vec3 p : {posed_point(skeleton, global, pos, s->joint_heel, s->heel),
                                posed_point(skeleton, global, pos, s->joint_toe, s->toe)})
        if (p.y < lowest[k].y) lowest[k] = p;
    }
  }
  float floor_a = 0.0f, floor_b = 0.0f;
  for (int pass = 0; pass < 2; ++pass) {
    double n = 0, sz = 0, sy = 0, szz = 0, szy = 0;
    for (const glm::vec3& p : lowest) {
      if (pass == 1 && std::abs(p.y - (floor_a + floor_b * p.z)) > 0.02f) continue;
      n += 1;
      sz += p.z;
      sy += p.y;
      szz += double(p.z) * p.z;
      szy += double(p.z) * p.y;
    }
    const double det = n * szz - sz * sz;
    if (n < 2 || std::abs(det) < 1e-12) {
      floor_b = 0.0f;
      floor_a = n > 0 ? static_cast<float>(sy / n) : 0.0f;
    } else {
      floor_b = static_cast<float>((n * szy - sz * sy) / det);
      floor_a = static_cast<float>((sy - floor_b * sz) / n);
    }
  }
  // Per leg and frame: heel underside and toe tip, after levelling.
  std::vector<std::array<glm::vec3, 4>> sole(frames);
  const glm::vec3 start(root[0].x, 0.0f, root[0].z);
  for (std::size_t k = 0; k < frames; ++k) {
    const float floor_here = floor_a + floor_b * (root[k].z + skeleton.centers[0].z);
    root[k] += glm::vec3(0.0f, -floor_here, 0.0f) - start;
    pose_globals(skeleton, locals[k], root[k], global, pos);
    sole[k] = {posed_point(skeleton, global, pos, left_sole.joint_heel, left_sole.heel),
               posed_point(skeleton, global, pos, left_sole.joint_toe, left_sole.toe),
               posed_point(skeleton, global, pos, right_sole.joint_heel, right_sole.heel),
               posed_point(skeleton, global, pos, right_sole.joint_toe, right_sole.toe)};
  }
  const float ground_offset = -floor_a;

  RetargetResult result;
  result.scale = scale;
  result.ground_offset = ground_offset;
  result.floor_slope = floor_b;
  result.skipped_frames = static_cast<int>(skip);
  result.family = naming.family;
  result.axes = axes;
  result.bones = std::move(bones);
  result.missing_on_rig = std::move(skipped_on_rig);
  const float dt = motion.frame_time;
  AnimationClip& clip = result.clip;
  clip.name = motion.source.empty() ? std::string("mocap") : motion.source;
  clip.duration = static_cast<float>(frames - 1) * dt;
  clip.loop = true;
  std::vector<float> times(frames);
  for (std::size_t k = 0; k < frames; ++k) times[k] = static_cast<float>(k) * dt;
  for (std::size_t h = 0; h < hj; ++h) {
    if (bvh_of[h] < 0) {
      result.unmapped_hanim.push_back(skeleton.joint_names[h]);
      continue;
    }
    RotationTrack track;
    track.joint = static_cast<std::int32_t>(h);
    track.times = times;
    track.values.resize(frames);
    for (std::size_t k = 0; k < frames; ++k) track.values[k] = locals[k][h];
    clip.rotations.push_back(std::move(track));
  }
  TranslationTrack root_track;
  root_track.joint = 0;
  root_track.times = times;
  root_track.values = root;
  clip.translations.push_back(std::move(root_track));
  result.root_travel = root.back() - root.front();
  result.root_travel.y = 0.0f;

  // Stance: the heel or the toe is planted, i.e. on the floor (below stance_height) and (nearly) still. Heel and
  // toe are judged separately because a walking foot rolls: the heel is the still point from heel strike to foot
  // flat, the toe from heel off to toe off, and a foot is in stance over both. The speed is the displacement over
  // +-speed_window frames: the capture's root jitters by 1-2 cm from frame to frame (its hip Z rotation jumps
  // 5 deg near frame 270), which a one-frame difference at 120 fps turns into 1-2 m/s of fake foot speed.
  const std::size_t window = static_cast<std::size_t>(std::max(options.speed_window, 1));
  for (int leg = 0; leg < 2; ++leg) {
    std::vector<bool> stance(frames, false);
    for (int point = 0; point < 2; ++point) {
      const std::size_t i = static_cast<std::size_t>(2 * leg + point);
      for (std::size_t k = 0; k < frames; ++k) {
        const std::size_t a = k >= window ? k - window : 0;
        const std::size_t b = std::min(k + window, frames - 1);
        glm::vec3 d = sole[b][i] - sole[a][i];
        d.y = 0.0f;
        const float speed = glm::length(d) / (static_cast<float>(b - a) * dt);
        if (sole[k][i].y < options.stance_height && speed < options.stance_speed) stance[k] = true;
      }
    }
    auto& intervals = result.contacts.legs[static_cast<std::size_t>(leg)];
    for (std::size_t k = 0; k < frames;) {
      if (!stance[k]) {
        ++k;
        continue;
      }
      std::size_t e = k;
      while (e < frames && stance[e]) ++e;
      const StanceInterval interval{times[k], std::min(static_cast<float>(e) * dt, clip.duration)};
      if (!intervals.empty() && interval.begin - intervals.back().end < options.merge_gap)
        intervals.back().end = interval.end;
      else
        intervals.push_back(interval);
      k = e;
    }
    std::erase_if(intervals, [&](const StanceInterval& i) { return i.end - i.begin < options.min_stance; });
  }
  return result;
}

}  // namespace strata
