#pragma once
// Locomotion system: the walk generator. For every walking walker it advances the gait clock from the cadence,
// moves the body along its path (a closed Cardinal spline on the ground), places footprints, and writes the
// goals the IK system solves: ankles (planted in stance, on a raised Cardinal swing arc in swing) and wrists
// (swinging in anti-phase with the legs), plus the pelvis (root translation, sacroiliac rotation, spine
// counter-rotation). Gait formulas: motion/gait.h; maths: ../shared/notes/tech-brief.md section 3.
//
// Gait determinants modelled: pelvis forward travel along the path; vertical oscillation, two bumps per stride,
// lowest in double support (the pelvis is as high as both legs reach with the stance knee at a normative walk's
// stance angles, kStanceKneeDeg, through loading response and mid-stance, so the knee yields and re-extends as a
// person's), plus a small loading-response drop after each heel strike; lateral sway towards the stance leg;
// pelvic rotation about the vertical (+-4 deg) and tilt (list, the swing side drops +-4 deg, lagging towards the next
// heel strike, and the subject's backward tilt); stance with three rockers: heel strike toes up rolling down
// about the heel, a flat foot, then a heel rise onto the ball (the midtarsal joint keeping the toes on the
// ground) and, once the toes bend no further, about the toe tip, as soon as the hip moving on needs it to keep
// the stance knee at the normative angle; a swing whose ankle and foot follow a normative swing's joint angles
// (kSwingHipDeg...) on the walker's own legs, clearing the ground; arms swung about the hanging pose.
// Joint-angle curves against a normative walk: systems/gait_metrics.h GaitCycleRecorder.
//
// Cadence may change at any time: phase and distance integrate it, footprints are placed once at toe-off, so a
// change never moves a planted foot or pops the pelvis.
//
// Walkers of a scenario crowd follow their steered agents instead of a path (agent mode, LocomotionColumns::agent):
// the pelvis is at the agent's position and heading, footprints land where its velocity and turn rate predict the
// pelvis at heel strike, a slower agent takes shorter steps at no less than agent_min_cadence, and an agent that
// stops brings its feet together and stands (kGaitIdle), both feet flat, with a slow weight shift.
//
//   reads:  rig (limbs, rest joint centres, reach, wrist paths), paths, style, dt, path (U32); agent and ik_flags
//           (kIkLimbs, U32: the last IK run's flags; agent mode)
//   writes: gait (kGaitFloats, read and written), time (clock component 0), placement (5), root_translation (3),
//           local_rotation of root, sacroiliac, spine and midtarsals, ik_goal (kIkLimbs*kIkGoalFloats),
//           ik_mode (kIkLimbs, I32)
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "components/skeleton.h"
#include "ecs/column_view.h"
#include "motion/cardinal_spline.h"
#include "systems/ik.h"
#include "systems/job.h"

namespace strata {

// Tuning of the walk; defaults give a natural adult walk. Angles in radians, lengths in metres at rig scale.
// The furthest an agent's body may be off its agent (m at rig scale; GaitStyle::lag_dip), about an agent's radius.
// Unbounded, lags ran to 2.7 m in the crossing (a body held back stance after stance, or pulled on by a foot landed
// beyond reach ahead); beyond this the foot drags instead of the body leaving its disc. Crowds tether each agent
// within a share of it of its body where avoidance allows (scene/crowd_agents.h CrowdAgents::tether_share).
inline constexpr float kBodyLagMax = 0.3f;

struct GaitStyle {
  float pelvis_yaw = 0.07f;          // pelvic rotation amplitude about the vertical (~4 deg)
  float pelvis_tilt = 0.07f;         // pelvic list amplitude (~4 deg), swing side down
  // The list's lag behind a sine peaking in mid single support (fraction of a cycle). The OpenSim subject's list
  // is largest around heel strike, the leading side 3-4.5 deg down (pelvis_list), so at double support the
  // trailing hip stands higher than the leading one and its knee stays straighter. 0.15 came out of the joint
  // search (below, bob_curvature); 0.25 (the subject's own timing) cost 2-3 deg of ankle RMS; 0 (as before) held
  // the longer lead's trailing knee bent (knee RMS 7.9 against 6.0).
  float pelvis_list_lag = 0.15f;
  float lateral_sway = 0.022f;       // pelvis shift towards the stance leg
  // Pelvic tilt (forward positive). Hip flexion is measured against the pelvis, and the OpenSim subject's pelvis
  // tilts 3.6-6.2 deg backwards (pelvis_tilt, +Z like hip flexion; mean 4.7): with it the walker's thighs swing
  // through the subject's world angles when its hips read the subject's. Rejected: a tilt growing forward with
  // cadence (0.0055 rad per step/min above 98), needed when the bent rest knee pushed the trailing hip to its
  // limit at 1.8 m/s; with the straight leg it only flexed the fast walkers' hips to 40-45 deg.
  float pelvis_anterior_tilt = -0.082f;
  // The pelvis' highest height above rest (m), where the legs reach: the default rest leg leans 5 deg with the ankle
  // behind the hip, so a straight leg under the hip reaches a few millimetres higher than rest.
  float pelvis_rise_max = 0.0f;  // 0.01 before the joint search
  // The pelvis holds the stance knee at the subject's stance angles (kStanceKneeDeg, its loading response
  // included) through this fraction of the stance; later the heel rise keeps it there (heel_hold_from).
  float stance_knee_until = 0.75f;
  // The pelvis height follows parabolas of this curvature (m/s^2) through the lowest heights the last and the
  // next heel strike allow, so the bob is smooth; hard reach limits alone gave ~1 cm/frame kinks.
  // 1.0 kept the pelvis ~4 cm low through mid-stance (knee 25-30 deg); 4-15 followed the legs' limits closer
  // (knee RMS 0.5-1 deg lower) but shook the pelvis 1.5x harder in steady walking. 3.7 (was 1.8) from the joint
  // search of 2026-11-27: a coordinate search of the numbers marked so here against the gait-cycle targets of
  // the default walker and every walker class (docs/motion.md); with the longer lead the pelvis has to follow
  // the double-support dip closer.
  // 4.0 from the fast walk's search (below, yaw_long_step_rise); 4.5 from the pre-swing search (heel_off).
  float bob_curvature = 4.5f;
  // The curvature falls by this fraction per reference step a long fast step runs beyond 1.05 of it (below,
  // yaw_long_step_rise): with the later heel rise (heel_off 0.65) the tallest walker at 1.8 m/s bobbed 5.2-5.3 cm
  // (target <= 5) at 4-4.5; a lower yaw/tilt/lead for that walker alone pushed its trailing hip past -25 deg.
  // 2.0 halves it at the longest steps (4.9 cm); the default walker (no excess) keeps the whole curvature.
  float bob_long_step_drop = 2.0f;
  // Footprint placed this many step lengths ahead of the pelvis at heel strike. With the heel rise below it
  // balances the leading leg at heel strike against the trailing one at toe-off: measured pelvis bob peak to
  // peak 2.2 / 5.9 / 10.7 cm at 0.8 / 1.2 / 1.6 m/s (0.5 gave 10 cm and 0.65 gave 7.8 cm at 1.2 m/s).
  // Now 0.53 with the heel and toe rockers and the straight rest leg (issue 21; searched with the stance values
  // below, 0.5-0.56): 0.6 put the foot 0.35 m ahead of the hip at heel strike, a 7 cm dip and the hip flexed 40 deg.
  // 0.58 from the joint search, with the swing's catch-up and the list's lag: footprint() places the rest ankle
  // `lead` ahead, and the default rest ankle is 7 cm behind the hip, so 0.53 left every foot 6-8 cm further back
  // under the hip than the subject's through the whole cycle (heel strike 0.26 m ahead of the hip, the subject's
  // 0.33).
  // 0.6 from the pre-swing search of 2026-11-28 (heel_off below): the foot 1.4 cm further forward under the hip
  // through stance, so the trailing hip extends as far as the subject's by toe-off without the foot rolling early.
  float footprint_lead = 0.6f;
  // The lead's fraction of the step falls by this much per step length beyond 0.7 m at rig scale, and rises by
  // lead_short_step_rise per step length below it: fast walkers' long steps dipped the pelvis 7 cm and bent their
  // terminal-stance knee 11-16 deg at 0.58; a slow walker's short step landed bent-kneed at the same lead.
  // 0.14 and 0.3 from the fast walk's search (0.1 and 0.35 before).
  // 0.18 and 0.2 since the pre-swing search (the fast and slow walkers' leads about where they were).
  float lead_long_step_drop = 0.18f;
  float lead_short_step_rise = 0.2f;
  // The fast walk: per reference step (0.7 m at rig scale) by which a step runs beyond 1.05 of it (0 for the
  // default walker at 1.2 m/s, 0.17-0.24 at 1.8 m/s), the pelvis turns (yaw) and lists (tilt) further, the foot
  // leaves the ground further rolled onto its toes (toe_off_pitch), and the swing's knots rise that fraction less
  // above the line from toe-off to heel strike. People's pelvic rotation and push-off grow with speed; here, at
  // 1.8 m/s, without them the 0.84-0.88 m steps the gait formula gives carried the trailing hip to -26..-27 deg
  // (target >= -25) and bobbed the pelvis 5.5-5.7 cm (target <= 5). The turn reaches +-12 deg on the shortest
  // walker at 1.8 m/s (4 deg at 1.2 m/s). The push-off alone (toe-off rise 0.8, the others 0) held the hip to -22
  // but left the bob; the list alone flattened the bob (0.13 rad: 5.0 cm) but lowered the swing hip so the knee
  // folded past 70 deg; the lift drop gives that back. Values from a coordinate search of these four with the
  // joint search's numbers (2026-11-27, second round), scored by every walker class's features and
  // the default walker's RMS.
  float yaw_long_step_rise = 0.6f;
  float tilt_long_step_rise = 0.14f;     // 0.1 before the pre-swing search
  float toe_off_long_step_rise = 1.3f;   // 1.1 before it
  float lift_long_step_drop = 0.8f;
  // Fraction of stance at which the heel starts to rise at the latest (~38 % of the cycle); it rises sooner when
  // the body's progress needs it (heel_hold_from). 0.6 from the joint search (was 0.59). On the old 0.53 lead,
  // 0.55 carried the trailing hip less far back (hip minimum -26.2 -> -23.7 deg) and 0.7 followed the subject's
  // pre-swing knee exactly (knee RMS 5.8) but left the hip at -28.8: the foot stayed where the rest ankle's 7 cm
  // behind the hip put every footprint.
  // 0.65 since the pre-swing search (2026-11-28), with the longer lead: the subject's heel rises slowly to ~7 deg by
  // the other foot's heel strike (48 % of the cycle) and then fast (52 deg at 64 %), where 0.6 had the foot pitched
  // 15 deg by 48 % and the ankle plantarflexing from 46 % (13 deg short of the subject's at 54-60 %); the knee then
  // bent early too. Ankle RMS 5.5 -> 4.9, knee 5.9 -> 5.7, hip 3.6 -> 3.3 deg (docs/motion.md).
  float heel_off = 0.65f;
  // From this fraction of stance (~28 % of the cycle) the heel rises as soon and as fast as the hip moving on ahead
  // needs to keep the stance knee at the subject's angle (systems/locomotion.cpp stance_pose), for the pelvis
  // as placed; the look-ahead assumes the pelvis heel_hold_height above rest. A schedule alone (heel_off and the
  // pitch curve below) left the trailing knee bent 15-35 deg in terminal stance, where the subject's is 4-7.
  float heel_hold_from = 0.5f;      // 0.45 before the joint search (bob_curvature)
  float heel_hold_height = 0.015f;  // 0.005 before it
  // Heel strike: the foot lands toes up by heel_strike_pitch and rolls down about its heel until foot flat at
  // heel_rocker of the stance (~8 % of the cycle), so the ankle is near neutral at heel strike as in a gait lab;
  // a foot landing flat left the ankle ~15 deg plantarflexed under a shin still leaning back. 0.36 (21 deg) lands
  // it 5 deg dorsiflexed at 1.2 m/s (0.44: 10; the subject 1). 0.39 and 0.155 from the joint search: 4 deg.
  // 0.36 and 0.175 from the fast walk's search: the default walker's ankle RMS 5.7 -> 5.5 deg.
  float heel_strike_pitch = 0.36f;
  float heel_rocker = 0.175f;

  // Foot pitch at toe-off by the schedule (~57 deg, the subject's): about the ball until the toes bend no further
  // (LocomotionRig::toe_limit), then about the toe tip. The heel hold may roll it further.
  float toe_off_pitch = 0.92f;  // 1.0 before the joint search
  // How fast the heel still rises at toe-off, as a fraction of the rise's mean rate. 0 (smoothstep) eased the foot
  // to rest just as the swing snatched it up, so the trailing leg's reach made a sharp dip right at toe-off that
  // the pelvis could not anticipate when the cadence changed (1.7 cm/frame^2 jolts); 0.85 rounds it (and the
  // subject's foot turns fastest there too: ankle RMS 11.6 -> 10.5 deg). It applies in full from 110 steps/min
  // and fades out below 90: a slow walker's heel then rose too late, the pelvis sank in double support and the
  // knee landed 11 deg bent at 0.8 m/s (3 deg without). 0.7 with the heel hold; 0.85 from the joint search
  // (bob_curvature); 0.9 with the longer lead.
  float heel_rise_end_slope = 0.9f;
  // The swing follows the normative swing's joint angles (kSwingHipDeg... below); its knots in
  // the middle of the swing are raised where the toe tip or heel would pass lower than this above the ground
  // (swing_clearance_min_mm in the gait report: 13 mm with 0.025; 0.035 gave 21 mm but folded the knee 2 deg
  // more than the subject's through the swing). 0.008 since the joint search: the raised knot at 75 % of the
  // swing kept the foot 3.5 cm high in late swing, the knee 10-13 deg more bent than the subject's at 84-92 % of
  // the cycle. The swing is now also sampled between the knots (make_swing), so the least clearance measured
  // over the 25-walker report is close to this (people's least toe clearance in mid-swing: 1.3 cm mean, Winter).
  float swing_clearance = 0.008f;
  // The swing's catch-up (systems/locomotion.cpp make_swing): the foot makes up its misfit against the normative
  // swing's path at toe-off over this first fraction of the swing, and the one at heel strike from
  // swing_land_from on; 0 spreads both over the whole swing as before.
  float swing_catch_up = 0.55f;  // 0.5 before the fast walk's search
  float swing_land_from = 0.55f;
  float arm_swing = 0.17f;           // wrist travel forward/back at a 0.7 m step, scaled with step length
  float cadence_rate = 25.0f;        // how fast cadence eases to its target, steps/min per second
  float speed_period = 18.0f;        // seconds per cycle of the speed schedule

  // ---- Walkers following steered agents (scenario crowds) ----
  // How fast the body turns while walking (rad/s; it faces where it wants to go), ~80 deg/s: a stance lasts ~0.7 s and
  // the body turns over a planted foot by at most ~0.5 rad either side of its footprint's heading (2.0 needed
  // 0.7, past what hip, knee and ankle twist). agent_move turns the agent at this rate and the walk predicts
  // footprints with it.
  float turn_rate = 1.4f;
  float turn_in_place_rate = 1.0f;  // rad/s standing; between the two by speed (systems/agent_move.h turn_rate_at)
  // Braking of a stopping agent (m/s^2; agent_move brakes at it, the walk predicts its last footprints with it):
  // ~1.5 stops a walker at 1.3 m/s in about two steps, as people stop. Speeding up: agent_acceleration.
  float agent_braking = 1.5f;
  // Gait initiation reaches walking speed in about three steps; 1.2 lengthened the second step past what the
  // trailing leg reaches (IK missed by 4 cm for a tenth of a second).
  float agent_acceleration = 0.8f;
  // Agents carried by avoidance at this speed (m/s) or faster, within face_side_angle (rad) of where they want to
  // go, face where they go (systems/agent_move.h facing_direction): a person edging through a crowd turns the body
  // into the gap rather than walking sideways. Carried further off (past 69 degrees), the body keeps facing its way
  // and steps across: at 1.6 rad (92 degrees) walkers caught in the crossing's other stream turned with it, their
  // wish (turned from the heading, slowed while facing away) fell to ~0.15 m/s along the stream, and they were
  // carried 10 m off for 5-8 s; every one of that run's 12 stuck agents was such a one. Over six crossing seeds
  // stuck 14.7 -> 7.3 on average, three 500-agent circles 51 -> 15, four plaza seeds 30 -> 22.5, the largest
  // slides alike; 1.4 rad gave 8.3, 26 and 30; 1.0, 5.0 stuck in the crossing but slides up to 61 / 75 mm in the
  // crossing / plaza (docs/crowds.md).
  float face_velocity_speed = 0.4f;
  float face_side_angle = 1.2f;
  // Agents carried further off their way than face_side_angle: the body turns from its wish towards the line it is
  // carried along until it goes across itself at no more than this (m/s; agent_move.h side_step_turn), and its
  // wish still turns from where it would face without that turn (wish_heading). Swept by the crossing's other
  // stream at 1.1-1.2 m/s, 70-80 degrees off its way, a walker facing its way walked sideways on a forward gait for
  // seconds, each stance leg out of reach in single support and the foot dragged (most of that run's slides over
  // 1 mm). Over five seeds each of crossing / bottleneck / plaza, stance frames sliding more than 1 mm 514 / 519 / 535
  // -> 143 / 403 / 297 on average, more than 1 cm 68 / 28 / 73 -> 3.8 / 15 / 13, stuck alike (docs/crowds.md).
  // 0.3-0.7 measured too; without wish_heading the wish followed the turned body and the plaza's stuck rose 28 -> 33.
  float face_side_speed = 0.4f;
  // Agents: the walk predicts the course turning towards the steering target while the velocity is within this
  // share of the wish's speed of the wish (systems/locomotion.cpp advance_gait_clock); straight on otherwise.
  float steering_tolerance = 0.3f;
  // Agents: the most a stance foot's heading may differ from the body's before it pivots on its contact (rad).
  float max_foot_twist = 0.5f;
  // Agents: how much faster the gait phase runs while a stance leg's goal was out of IK's reach in the last frame.
  // Avoidance moves a body sideways in a jam further than a planted foot's leg reaches before its stance ends;
  // ending that stance sooner lifts the foot and sets it down under the body, where holding it dragged it along
  // the ground (issue 16: up to 0.5 m in the scenario reports). 3 before the early lift below; with it, 6, and a leg
  // lifting early is not hurried too (largest foot slide, 3 with the lift hurried -> 6 without: crossing 210 -> 162
  // mm, bottleneck 187 -> 153, plaza 296 -> 158, but circle 218 -> 307); 10 made the steps jump a third of a cycle a
  // frame at 30 fps.
  float stance_hurry = 6.0f;
  // Agents: the most the pelvis drops below standing (m at rig scale) for a stance leg the body has moved away
  // from; beyond it the body stays back, off its agent (systems/locomotion.cpp walk_one), and the lag eases out
  // with time constant lag_release (s), no faster than lag_catch_up (m/s at rig scale), the body's velocity
  // carrying the catch-up so its footprints are planned for where it goes. The walk's own dip is 3-5 cm, so
  // none of this binds in a free walk; the pelvis never goes lower than lag_dip.
  float lag_dip = 0.08f;
  float lag_release = 0.3f;
  float lag_catch_up = 0.2f;
  // Agents moving backwards step back: the footprint lead scales by 1 + back_step_lead c for the velocity's
  // share c < 0 along the heading (systems/locomotion.cpp footprint_lead).
  float back_step_lead = 1.5f;
  // Agents: such a leg already past this fraction of its stance (its heel up, rolling onto the toes) lifts into
  // its swing now rather than at toe-off: its toe tip was what dragged (0.3 m at worst in the crossing). The swing
  // leaves from the pose the foot has and lands on time; 0 or above 1 turns it off.
  float early_lift = 0.8f;
  // Agents: such a leg, with both feet down, whose pose IK cannot hold in this very frame (its reach or its joints'
  // limits, asked of solve_limb before the IK system runs) lifts in this frame rather than the next, off IK's flags
  // (systems/locomotion.cpp stance_foot_holds). False: only the next frame's.
  bool lift_on_ik_miss = true;
  // Agents: a stance leg twisted further than this (rad) under a turning body, the foot on its ball where it cannot
  // pivot, lifts early too (same fraction, the other foot down): the legs' twist runs out near 0.9 rad, and IK's
  // orientation clamp then yawed the foot about its ball, the tip sliding 4-16 mm (arrivals turning into their
  // regions, making way). 10 turns it off.
  float lift_twist = 0.8f;
  // Agents: a body on one foot (the other swinging) turns no further than this (rad) from that foot's planted
  // heading (agent_move.h stance_limited_turn); it turns on at the next step. The stance foot cannot lift until the
  // swing lands, so lift_twist cannot help there, and a body turning past the legs' ~0.9 rad of twist had IK's
  // orientation clamp yaw the foot about its ball. Just above lift_twist, so that a foot held at it lifts early in
  // the double support that follows. 10 turns it off.
  float stance_twist = 0.85f;
  // Agents: a swinging foot re-aims at the newest footprint prediction until this fraction of its swing.
  float retarget_until = 0.8f;
  // Agents: a swinging foot lands within its leg's reach of the body (the hold's geometry, lag_dip) rather than
  // where the footprint prediction put it, when the body has fallen behind that prediction (held back by the
  // stance foot, or the swing cut short by stance_hurry): from retarget_until on, the target is moved each frame
  // to be within reach of where the body will be at heel strike, and at heel strike of where it is. False: it lands
  // on the prediction and the hold pulls the body to it, up to kBodyLagMax in one frame (bodies jumped 42 cm so).
  bool land_within_reach = true;
  // Lowest cadence of a walking agent (steps/min): at a crawl the gait formula's cadence falls to 40, slow motion;
  // people easing to a stop or turning on the spot take short steps at a near-normal rate.
  float agent_min_cadence = 80.0f;
  float stand_speed = 0.08f;        // m/s: an agent slower than this that wants no faster stands still
  float stand_feet_apart = 0.15f;   // m (rig scale): the feet are together when no further apart along the heading
  float idle_settle = 0.4f;         // s to settle into the idle stance
  float idle_release = 0.25f;       // s to leave it
  float idle_sway = 0.008f;         // m: the standing weight shift from foot to foot
  float idle_sway_period = 4.0f;    // s
};

// The swing from toe-off to heel strike in joint angles: kSwingKnots samples evenly spaced in time from the
// normative walk shipped in data/normative_gait.csv, from its toe-off (kSwingToeOffPhase of the cycle, knee 35 deg)
// to its heel strike; hip flexion, knee flexion, ankle dorsiflexion in degrees (a test checks them against the
// table). The swing ankle's knots are these angles' forward kinematics on the walker's own legs, so the hip,
// knee and ankle of a swing take a person's timing. Rejected, after measuring it (issue 21): a hand-placed arc
// walked by an eased distance curve, whose foot left toe-off at rest while the hip moved on, so the knee
// re-extended after toe-off (26 -> 15 deg) and peaked late (RMS against the subject: knee 12.1 deg; 7.3 with
// this swing alone, 5.9 with the pelvis changes below too).
inline constexpr std::size_t kSwingKnots = 9;
inline constexpr float kSwingToeOffPhase = 0.62f;
inline constexpr float kSwingHipDeg[kSwingKnots] = {-15.76f, -5.25f, 4.07f, 12.14f, 17.44f, 19.82f, 19.71f, 18.15f, 17.23f};
inline constexpr float kSwingKneeDeg[kSwingKnots] = {34.69f, 55.23f, 67.25f, 69.08f, 61.99f, 46.58f, 25.40f, 5.51f, -2.15f};
inline constexpr float kSwingAnkleDeg[kSwingKnots] = {5.21f, -8.43f, -4.97f, 0.52f, 0.28f, 0.87f, -1.67f, -3.20f, -2.03f};

// The stance knee of the same walk, kStanceKnots samples evenly spaced in time from its heel strike to its toe-off
// (degrees). The pelvis is held where the stance leg's hip-ankle distance is the one this knee angle gives on
// the walker's own leg (LocomotionRig::stance_reach), so loading response, mid-stance and pre-swing bend the knee
// as the subject's did; both legs' limits bind in double support.
inline constexpr std::size_t kStanceKnots = 16;
inline constexpr float kStanceKneeDeg[kStanceKnots] = {-1.90f, 3.02f,  13.46f, 20.99f, 23.17f, 21.23f, 17.47f, 13.62f,
                                                       10.55f, 7.93f, 5.56f,  4.30f,  4.68f,  8.95f,  18.22f, 34.69f};

// Rig-constant data the locomotion system needs, derived once from the skeleton.
struct LocomotionRig {
  std::vector<LimbChain> limbs;      // make_limbs order: left leg, right leg, left arm, right arm
  std::int32_t root = 0, sacroiliac = -1, spine = -1;   // spine: the joint that counter-rotates (vl5)
  std::int32_t ball[2] = {-1, -1};   // l/r_midtarsal: the pivot of the heel rise
  glm::vec3 sacro_center{0.0f};
  glm::vec3 ankle_rest[2], ball_rest[2], hip_rest[2], wrist_rest[2];
  glm::vec3 heel_rest[2];            // the heel's ground contact (below l/r_calcaneous_post_pt, at the ball's height)
  glm::vec3 tip_rest[2];             // the toe tip's ground contact (l/r_forefoot_tip at the ball's height)
  float toe_limit = 0.6f;            // how far the midtarsal may dorsiflex to keep the toes down (rad)
  float leg_reach[2] = {0, 0};       // |hip-knee| + |knee-ankle|
  float thigh_length[2] = {0, 0}, shin_length[2] = {0, 0};  // |hip-knee|, |knee-ankle|
  float ankle_plantarflexion_limit = 1.0f;  // the ankle's upper x limit (rad, toes down), from the skeleton
  float ankle_roll_limit = 0.35f;           // the least of the ankle's z limits (inversion / eversion, rad)
  // The rest pose's own joint angles in a gait lab's terms (radians, sagittal, left leg; flexion and dorsiflexion
  // positive): thigh against the pelvis' vertical, shin against the thigh, shin's forward lean over the flat rest
  // foot. A gait lab's zero is a standing body with vertical thigh and shin over a flat foot; a skeleton's rest
  // pose need not be (Strata's default leans the straight leg 5 deg with the ankle behind the hip; ISO 200x's
  // centres bend the knee 18 deg), so a local rotation of x reads as the lab's x + rest_*. The gait cycle's
  // curves add these; the normative swing subtracts them before driving the rig.
  float rest_hip_flexion = 0.0f, rest_knee_flexion = 0.0f, rest_ankle_dorsiflexion = 0.0f;
  // Hip -> ankle with the knee bent as at each swing knot (kSwingKneeDeg less rest_knee_flexion), humanoid axes:
  // the swing's forward kinematics less the hip's rotation, which depends on the walker's pelvis tilt and is
  // applied per frame.
  glm::vec3 swing_leg[2][kSwingKnots];
  // Hip-ankle distance with the knee at each kStanceKneeDeg (never more than the leg reaches), humanoid units.
  float stance_reach[2][kStanceKnots];
  float rig_height = 1.75f;          // stature of the rig (skull_tip, else top joint + 0.13 m)
  CardinalSpline wrist_path[2];      // closed loops in humanoid space: back, mid, front, mid
  // The skeleton itself (centres, hierarchy, limits) and each hip's ancestors, root first, for agents' stance legs
  // that ask IK before they lift (systems/locomotion.cpp stance_foot_holds).
  Skeleton skeleton;
  std::vector<std::int32_t> hip_ancestors[2];
};

// Throws std::invalid_argument when the skeleton lacks a limb joint or the midtarsal joints.
LocomotionRig make_locomotion_rig(const Skeleton& skeleton);

// The walker columns locomotion reads and writes; both jobs below have them as their first members.
struct LocomotionColumns {
  ColumnView<const std::uint32_t> path;  // 1: index into the job's paths (past the end: the last path)
  ColumnView<float> gait;                // kGaitFloats: GaitComponent / LegComponent state, read and written
  ColumnView<float> time;                // 1: the walker clock's time (s), advanced by dt
  ColumnView<float> placement;           // 5: ground position, heading, scale, written
  ColumnView<float> root_translation;    // 3: pelvis bob and sway (humanoid units), written
  ColumnView<float> local_rotation;      // joints*4: root, sacroiliac, spine, midtarsal rotations written
  ColumnView<float> ik_goal;             // kIkLimbs*kIkGoalFloats: ankle and wrist goals, written
  ColumnView<std::int32_t> ik_mode;      // kIkLimbs: legs PositionOrientation, arms Position, written
  // Agent mode when set (kAgentFloats, read): the pelvis follows the walker's steered agent (position, velocity,
  // heading) instead of a path, and the walker stands when its agent stops; `path` and the paths are not read.
  ColumnView<const float> agent;
  // Agent mode, optional (kIkLimbs, read): each limb's IkFlags from the last IK run. A stance leg whose goal IK
  // could not reach (the body pushed away from the planted foot) hurries its step: GaitStyle::stance_hurry.
  ColumnView<const std::uint32_t> ik_flags;
};
// Views of those columns over every walker of `walkers` (a walker table, components/walker.h); with
// `follow_agents` the agent and IK-flag views too.
LocomotionColumns locomotion_columns(SoaTable& walkers, bool follow_agents = false);

// Places walker `walker` at its gait distance along its path with its gait state consistent with its phase
// (both feet on their footprints, the swing foot mid-arc), so the first frame needs no settling. Reads the gait
// fields the spawner set (distance, phase, cadence, height, speed schedule) and writes the rest of the walker's
// locomotion columns, as one frame of dt = 0 would.
struct StartWalkingJob : LocomotionColumns {
  const LocomotionRig* rig = nullptr;
  std::span<const CardinalSpline> paths;
  const GaitStyle* style = nullptr;
  std::size_t walker = 0;

  // Rig (four limbs, joints inside the rotations) and style set, paths non-empty, walker in range, every view
  // with the same rows and its width, no two views overlapping; the walker's gait height positive and finite,
  // its cadence and cadence target finite (the gait formulas refuse anything else).
  bool validate() const;
  bool run() const;
};

// One frame for every walker: advances time by dt and writes placement, root translation, pelvis and spine
// rotations, and IK goals for all four limbs. Walkers are independent (oneTBB chunks, deterministic).
struct LocomotionJob : LocomotionColumns {
  const LocomotionRig* rig = nullptr;
  std::span<const CardinalSpline> paths;
  const GaitStyle* style = nullptr;
  float dt = 0.0f;

  // As StartWalkingJob's, with dt finite instead of a walker, and the gait state checked for every walker.
  bool validate() const;
  bool run() const;
};

// Simulation level of detail: the gait clock alone for walkers nobody sees in detail (impostors, culled walkers
// of a walking crowd). Advances time, cadence, phase and path distance by dt and writes the placement, exactly as
// LocomotionJob does for the same walker, so a walker keeps its place and phase whichever job moves it; writes no
// footprints, pelvis, rotations or goals. A walker going back to the whole walk restarts it with
// StartWalkingJob, which derives feet and pelvis from the phase and distance. ~15x cheaper than walking.
//
//   reads:  rig (rig height), paths, style, dt, path (U32); agent (agent mode)
//   writes: gait (time-keeping components: cadence, cadence target, phase, distance, idle), time, placement (5)
struct GaitAdvanceJob {
  ColumnView<const std::uint32_t> path;
  ColumnView<const float> agent;  // agent mode when set, as LocomotionColumns::agent
  ColumnView<float> gait;
  ColumnView<float> time;
  ColumnView<float> placement;
  const LocomotionRig* rig = nullptr;
  std::span<const CardinalSpline> paths;
  const GaitStyle* style = nullptr;
  float dt = 0.0f;

  // Rig and style set, paths non-empty, dt finite, the views their widths with the same rows and not overlapping,
  // every walker's gait state valid (as LocomotionJob's).
  bool validate() const;
  bool run() const;
};
// Over every walker of `walkers`: a walker table, wide or light (components/walker.h).
GaitAdvanceJob make_gait_advance_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths,
                                     SoaTable& walkers, float dt, const GaitStyle& style, bool follow_agents = false);

LocomotionJob make_locomotion_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths, SoaTable& walkers,
                                  float dt, const GaitStyle& style, bool follow_agents = false);
StartWalkingJob make_start_walking_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths,
                                       SoaTable& walkers, std::size_t walker, const GaitStyle& style,
                                       bool follow_agents = false);

}  // namespace strata
