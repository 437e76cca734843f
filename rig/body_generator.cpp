#include "rig/body_generator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <tbb/parallel_for.h>

#include "io/hanim_loader.h"
#include "rig/body_cache.h"
#include "rig/surface_simplify.h"

namespace strata {
namespace {

// ---- Primitives ---------------------------------------------------------------------------------------------

enum class Shape : std::uint8_t { Cone, Ellipsoid, Box, Loft };

// One primitive of the left half or the midline. `axes` maps local to world (columns), so a local point is
// transpose(axes) * (p - center).
struct Prim {
  Shape shape = Shape::Ellipsoid;
  glm::vec3 a{0.0f}, b{0.0f};  // Cone: end centres
  float ra = 0.0f, rb = 0.0f;  // Cone: end radii; Box: rounding in ra
  glm::vec3 center{0.0f};
  glm::mat3 axes{1.0f};
  glm::vec3 radii{1.0f};       // Ellipsoid radii / Box half extents, along axes' columns
  std::uint16_t part = 0;      // part for x >= 0 (the mirror side maps l* to r*)
  glm::vec3 lo{0.0f}, hi{0.0f};  // world bounding box of the surface
};

float smin(float a, float b, float k) {
  if (k <= 0.0f) return std::min(a, b);
  const float h = std::max(k - std::abs(a - b), 0.0f) / k;
  return std::min(a, b) - h * h * k * 0.25f;
}
float smax(float a, float b, float k) { return -smin(-a, -b, k); }
float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Capsule with a linearly varying radius. Not the exact round-cone distance, but the limbs' radius slopes are
// under 0.1, where the difference is below a millimetre; the exact form costs three square roots more.
float sd_cone(const Prim& s, const glm::vec3& p) {
  const glm::vec3 ba = s.b - s.a, pa = p - s.a;
  const float h = std::clamp(glm::dot(pa, ba) / glm::dot(ba, ba), 0.0f, 1.0f);
  return glm::length(pa - ba * h) - (s.ra + (s.rb - s.ra) * h);
}

// Ellipsoid: the usual first-order estimate k0 (k0 - 1) / k1, exact on the surface and never far off nearby.
float sd_ellipsoid(const Prim& s, const glm::vec3& p) {
  const glm::vec3 q = glm::transpose(s.axes) * (p - s.center);
  const float k0 = glm::length(q / s.radii);
  const float k1 = glm::length(q / (s.radii * s.radii));
  if (k1 < 1e-12f) return -std::min(s.radii.x, std::min(s.radii.y, s.radii.z));
  return k0 * (k0 - 1.0f) / k1;
}

float sd_box(const Prim& s, const glm::vec3& p) {
  const glm::vec3 q = glm::abs(glm::transpose(s.axes) * (p - s.center)) - (s.radii - glm::vec3(s.ra));
  return glm::length(glm::max(q, glm::vec3(0.0f))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0f) - s.ra;
}

// ---- The trunk loft: anthropometry.md section 2, MH rows (hip-aligned, so y is H-Anim y) -----------------------
struct Slice {
  float y, width, back, front;
};
// Widths are capped at 0.32 from the crotch up to the waist, narrower than ANSUR's 0.346 hip breadth: the H-Anim
// wrists and forearms hang at x = +-0.2 with their inner skin at x ~ +-0.17, and a hip that touches them fuses arm
// and trunk into one surface (measured: with 0.356 the level meshes had genus 4 and the fused patches stretched
// 28x and flipped in the walk, 164 inverted triangles at level 2). 0.32 keeps a gap of over 1 cm. Above the axilla the MH rows include the
// A-posed deltoids; those rows are replaced by a narrowing shoulder girdle, the deltoids being arm primitives.
constexpr Slice kSlices[] = {
    {0.790f, 0.310f, -0.080f, 0.090f}, {0.830f, 0.318f, -0.096f, 0.107f}, {0.860f, 0.320f, -0.109f, 0.112f},
    {0.890f, 0.320f, -0.117f, 0.123f}, {0.920f, 0.320f, -0.120f, 0.131f}, {0.950f, 0.320f, -0.111f, 0.136f},
    {0.980f, 0.320f, -0.098f, 0.139f}, {1.010f, 0.318f, -0.079f, 0.140f}, {1.040f, 0.310f, -0.060f, 0.138f},
    {1.070f, 0.293f, -0.049f, 0.137f}, {1.100f, 0.268f, -0.041f, 0.142f}, {1.138f, 0.254f, -0.033f, 0.148f},
    {1.160f, 0.253f, -0.033f, 0.153f}, {1.190f, 0.259f, -0.037f, 0.157f}, {1.220f, 0.266f, -0.043f, 0.155f},
    {1.252f, 0.280f, -0.051f, 0.155f}, {1.280f, 0.295f, -0.057f, 0.147f}, {1.310f, 0.312f, -0.061f, 0.133f},
    {1.340f, 0.326f, -0.071f, 0.121f}, {1.370f, 0.330f, -0.076f, 0.108f}, {1.400f, 0.318f, -0.075f, 0.093f},
    {1.430f, 0.270f, -0.068f, 0.076f}, {1.460f, 0.180f, -0.058f, 0.062f}, {1.490f, 0.120f, -0.045f, 0.062f},
};
constexpr float kLoftBottom = 0.80f, kLoftTop = 1.49f;

struct Loft {
  // Back skin z per slice after the spine rule; front and width as tabulated.
  std::vector<Slice> slices;
};

Slice loft_at(const Loft& loft, float y) {
  const auto& s = loft.slices;
  if (y <= s.front().y) return s.front();
  if (y >= s.back().y) return s.back();
  std::size_t i = 1;
  while (s[i].y < y) ++i;
  const float t = (y - s[i - 1].y) / (s[i].y - s[i - 1].y);
  auto mix = [t](float a, float b) { return a + (b - a) * t; };
  return {y, mix(s[i - 1].width, s[i].width), mix(s[i - 1].back, s[i].back), mix(s[i - 1].front, s[i].front)};
}

// Superellipse |X|^2.5 + |Z|^2.5 = 1 per slice: a trunk section is boxier than an ellipse (flat back, broad
// chest). The distance is F / |grad F|, exact on the contour; the y variation of the profile is ignored.
float sd_loft(const Loft& loft, const glm::vec3& p) {
  const Slice s = loft_at(loft, p.y);
  const float a = 0.5f * s.width, b = 0.5f * (s.front - s.back), cz = 0.5f * (s.front + s.back);
  const float X = std::abs(p.x) / a, Z = std::abs(p.z - cz) / b;
  const float sx = std::sqrt(X), sz = std::sqrt(Z);
  const float F = X * X * sx + Z * Z * sz - 1.0f;
  const float gx = 2.5f * X * sx / a, gz = 2.5f * Z * sz / b;
  const float g = std::sqrt(gx * gx + gz * gz);
  const float d2 = std::max(F / std::max(g, 1e-6f), -std::min(a, b));
  return smax(smax(d2, kLoftBottom - p.y, 0.03f), p.y - kLoftTop, 0.02f);
}

// ---- The body model ---------------------------------------------------------------------------------------

enum Finger { Thumb, Index, Mid, Ring, Pinky };

struct BodyModel {
  Loft loft;
  std::vector<Prim> prims;
  // Index ranges into prims for each group (see evaluate()).
  int loft_part_hip = 0, loft_part_abdomen = 0, loft_part_chest = 0;
  std::vector<int> torso, head, eyes, upper_arm, forearm, palm, thigh, shin, foot;
  std::array<std::array<int, 3>, 5> finger{};
  std::vector<std::uint16_t> mirror_part;  // part index -> its other-side part (itself for midline parts)
};

std::uint16_t part_index(const std::string& name) {
  const auto& names = paper_part_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::logic_error("body_generator: unknown part " + name);
  return static_cast<std::uint16_t>(it - names.begin());
}

glm::mat3 frame_from(glm::vec3 along, glm::vec3 forward) {
  // Columns: lateral-ish u, along the bone v, forward w (right-handed: u = v x w).
  const glm::vec3 v = glm::normalize(along);
  glm::vec3 w = forward - v * glm::dot(forward, v);
  w = glm::normalize(w);
  const glm::vec3 u = glm::cross(v, w);
  return glm::mat3(u, v, w);
}

class ModelBuilder {
 public:
  explicit ModelBuilder(BodyModel& m) : m_(m) {}

  int cone(glm::vec3 a, glm::vec3 b, float ra, float rb, const std::string& part) {
    Prim s;
    s.shape = Shape::Cone;
    s.a = a;
    s.b = b;
    s.ra = ra;
    s.rb = rb;
    const float r = std::max(ra, rb);
    s.lo = glm::min(a, b) - glm::vec3(r);
    s.hi = glm::max(a, b) + glm::vec3(r);
    return add(s, part);
  }
  int ellipsoid(glm::vec3 c, const glm::mat3& axes, glm::vec3 radii, const std::string& part) {
    Prim s;
    s.shape = Shape::Ellipsoid;
    s.center = c;
    s.axes = axes;
    s.radii = radii;
    bounds_of_oriented(s);
    return add(s, part);
  }
  int box(glm::vec3 c, const glm::mat3& axes, glm::vec3 half, float rounding, const std::string& part) {
    Prim s;
    s.shape = Shape::Box;
    s.center = c;
    s.axes = axes;
    s.radii = half;
    s.ra = rounding;
    bounds_of_oriented(s);
    return add(s, part);
  }
  int loft(const std::string& part) {
    Prim s;
    s.shape = Shape::Loft;
    s.lo = glm::vec3(-0.2f, kLoftBottom - 0.01f, -0.15f);
    s.hi = glm::vec3(0.2f, kLoftTop + 0.01f, 0.17f);
    return add(s, part);
  }

 private:
  static void bounds_of_oriented(Prim& s) {
    glm::vec3 ext(0.0f);
    for (int k = 0; k < 3; ++k) ext += glm::abs(s.axes[k]) * s.radii[k];
    s.lo = s.center - ext;
    s.hi = s.center + ext;
  }
  int add(Prim s, const std::string& part) {
    s.part = part_index(part);
    m_.prims.push_back(s);
    return static_cast<int>(m_.prims.size()) - 1;
  }
  BodyModel& m_;
};

glm::vec3 joint(const Skeleton& sk, const char* name) {
  const std::int32_t j = sk.find_joint(name);
  if (j < 0) throw std::runtime_error(std::string("body_generator: skeleton has no joint ") + name);
  return sk.centers[static_cast<std::size_t>(j)];
}
glm::vec3 site_or(const Skeleton& sk, const char* name, glm::vec3 fallback) {
  const std::int32_t s = sk.find_site(name);
  return s < 0 ? fallback : sk.sites[static_cast<std::size_t>(s)].position;
}

BodyModel build_model(const Skeleton& sk) {
  BodyModel m;
  ModelBuilder add(m);
  const glm::vec3 fwd(0.0f, 0.0f, 1.0f);

  // Trunk: tabulated front and width; the back goes at least 1.5 cm behind the H-Anim spine, whose lumbar joints
  // lie outside the MH back (anthropometry.md 6.3), which also deepens the slim MH trunk towards ANSUR's.
  std::vector<glm::vec2> spine;  // (y, z) of the spine joints, by height
  for (const char* name : {"HumanoidRoot", "sacroiliac", "vl5", "vt6", "vt1", "vc4"}) {
    const glm::vec3 c = joint(sk, name);
    spine.emplace_back(c.y, c.z);
  }
  std::sort(spine.begin(), spine.end(), [](glm::vec2 p, glm::vec2 q) { return p.x < q.x; });
  auto spine_z = [&](float y) {
    if (y <= spine.front().x) return spine.front().y;
    for (std::size_t i = 1; i < spine.size(); ++i)
      if (y <= spine[i].x) {
        const float t = (y - spine[i - 1].x) / (spine[i].x - spine[i - 1].x);
        return spine[i - 1].y + (spine[i].y - spine[i - 1].y) * t;
      }
    return spine.back().y;
  };
  for (Slice s : kSlices) {
    s.back = std::min(s.back, spine_z(s.y) - 0.015f);
    m.loft.slices.push_back(s);
  }
  m.loft_part_hip = part_index("hip");
  m.loft_part_abdomen = part_index("abdomen");
  m.loft_part_chest = part_index("chest");

  const glm::mat3 I(1.0f);
  m.torso.push_back(add.loft("chest"));
  // Buttocks and pectorals: the loft is a stack of convex slices, these give the gluteal fold and the chest relief.
  m.torso.push_back(add.ellipsoid({0.058f, 0.905f, -0.050f}, I, {0.075f, 0.095f, 0.072f}, "hip"));
  const Slice nipple = loft_at(m.loft, 1.262f);
  m.torso.push_back(add.ellipsoid({0.062f, 1.272f, nipple.front - 0.032f}, I, {0.072f, 0.058f, 0.040f}, "chest"));
  const float skull_tip_y = site_or(sk, "skull_tip", glm::vec3(0.0f, 1.7504f, 0.0f)).y;
  const glm::vec3 skullbase = joint(sk, "skullbase");
  const glm::vec3 vt1 = joint(sk, "vt1");
  // Neck: 1.2 x MH's minimum (ANSUR), its back 1.5 cm behind vt1.
  m.torso.push_back(add.cone({0.0f, vt1.y - 0.05f, vt1.z + 0.05f}, {0.0f, skullbase.y - 0.04f, vt1.z + 0.072f},
                             0.060f, 0.055f, "neck"));
  // Trapezius / clavicle: from the neck base to the acromion, lifting the shoulder line to ~1.47.
  const glm::vec3 l_shoulder = joint(sk, "l_shoulder");
  m.torso.push_back(add.cone({0.03f, l_shoulder.y + 0.035f, -0.015f},
                             {l_shoulder.x - 0.02f, l_shoulder.y + 0.008f, l_shoulder.z - 0.002f}, 0.042f, 0.036f,
                             "lCollar"));

  // Head: skull ellipsoid hanging from the skull tip, jaw, nose, ears, eyeballs slightly proud of the skull.
  const float head_ry = 0.11f;
  const glm::vec3 head_c(0.0f, skull_tip_y - head_ry, 0.045f);
  m.head.push_back(add.ellipsoid(head_c, I, {0.077f, head_ry, 0.100f}, "head"));
  m.head.push_back(add.ellipsoid(head_c + glm::vec3(0.0f, -0.092f, 0.030f), frame_from({0, 1, 0.35f}, fwd),
                                 {0.056f, 0.046f, 0.064f}, "head"));
  m.head.push_back(add.cone(head_c + glm::vec3(0.0f, -0.018f, 0.093f), head_c + glm::vec3(0.0f, -0.055f, 0.113f),
                            0.008f, 0.013f, "head"));
  m.head.push_back(add.ellipsoid(head_c + glm::vec3(0.076f, -0.033f, -0.035f), I, {0.013f, 0.030f, 0.020f}, "head"));
  m.eyes.push_back(add.ellipsoid(head_c + glm::vec3(0.032f, -0.017f, 0.083f), I, glm::vec3(0.0125f), "lEye"));

  // Arm: deltoid, upper arm with biceps and triceps, forearm with its muscle belly.
  const glm::vec3 elbow = joint(sk, "l_elbow"), wrist = joint(sk, "l_wrist");
  const glm::mat3 ua = frame_from(elbow - l_shoulder, fwd);
  auto along = [](glm::vec3 a, glm::vec3 b, float f) { return a + (b - a) * f; };
  m.upper_arm.push_back(add.ellipsoid(l_shoulder + glm::vec3(0.012f, -0.030f, 0.002f), ua,
                                      {0.052f, 0.085f, 0.058f}, "lShldr"));
  m.upper_arm.push_back(add.cone(l_shoulder, elbow, 0.045f, 0.036f, "lShldr"));
  m.upper_arm.push_back(add.ellipsoid(along(l_shoulder, elbow, 0.50f) + ua[2] * 0.014f, ua,
                                      {0.036f, 0.085f, 0.034f}, "lShldr"));
  m.upper_arm.push_back(add.ellipsoid(along(l_shoulder, elbow, 0.38f) - ua[2] * 0.016f, ua,
                                      {0.038f, 0.100f, 0.034f}, "lShldr"));
  const glm::mat3 fa = frame_from(wrist - elbow, fwd);
  m.forearm.push_back(add.cone(elbow, wrist, 0.036f, 0.024f, "lForeArm"));
  m.forearm.push_back(add.ellipsoid(along(elbow, wrist, 0.28f), fa, {0.040f, 0.090f, 0.041f}, "lForeArm"));

  // Hand, hanging with the palm towards the thigh: e_d down the fingers, e_t towards the thumb (forward), e_m
  // medial (palm side). It sits 1.5 cm lateral of the wrist centre so the palm clears the hip by ~2 cm.
  const glm::vec3 tip = site_or(sk, "l_hand_tip", wrist + glm::vec3(0.0f, -0.19f, 0.0f));
  const float hand_len = glm::length(tip - wrist), sc = hand_len / 0.19f;
  const glm::vec3 e_d = glm::normalize(tip - wrist);
  const glm::vec3 e_t = glm::normalize(fwd - e_d * glm::dot(fwd, e_d));
  const glm::vec3 e_m = glm::cross(e_d, e_t);
  const glm::vec3 hand_o = wrist - e_m * 0.015f;
  const glm::mat3 hand_axes(e_t, e_d, e_m);
  m.palm.push_back(add.box(hand_o + e_d * (0.052f * sc) + e_t * 0.002f, hand_axes,
                           glm::vec3(0.042f, 0.048f * sc, 0.0135f), 0.011f, "lHand"));
  m.palm.push_back(add.ellipsoid(hand_o + e_d * (0.045f * sc) + e_t * 0.024f + e_m * 0.006f, hand_axes,
                                 {0.020f, 0.034f * sc, 0.014f}, "lHand"));  // thenar eminence
  struct FingerSpec {
    const char* name;
    float mcp_d, mcp_t, length, radius, splay;
  };
  constexpr FingerSpec fingers[] = {{"Index", 0.097f, 0.029f, 0.075f, 0.0092f, 0.15f},
                                    {"Mid", 0.101f, 0.0095f, 0.085f, 0.0095f, 0.04f},
                                    {"Ring", 0.097f, -0.010f, 0.081f, 0.0089f, -0.07f},
                                    {"Pinky", 0.088f, -0.029f, 0.062f, 0.0080f, -0.20f}};
  constexpr float seg_frac[3] = {0.45f, 0.30f, 0.25f};
  constexpr float curl[3] = {0.10f, 0.22f, 0.32f};
  for (int f = 0; f < 4; ++f) {
    const FingerSpec& spec = fingers[f];
    glm::vec3 p = hand_o + e_d * (spec.mcp_d * sc) + e_t * spec.mcp_t;
    const glm::vec3 dir0 = std::cos(spec.splay) * e_d + std::sin(spec.splay) * e_t;
    float r = spec.radius;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 dir = std::cos(curl[k]) * dir0 + std::sin(curl[k]) * e_m;
      const glm::vec3 q = p + dir * (spec.length * seg_frac[k] * sc);
      const float r_end = r * (k == 2 ? 0.86f : 0.93f);
      m.finger[f + 1][k] =
          add.cone(p, q, r, r_end, std::string("l") + spec.name + std::to_string(k + 1));
      p = q;
      r = r_end;
    }
  }
  // Thumb: in front of the palm, nearly in its plane; a thumb folded medially would touch the thigh.
  {
    glm::vec3 p = hand_o + e_d * (0.030f * sc) + e_t * 0.030f + e_m * 0.004f;
    const glm::vec3 dirs[3] = {glm::normalize(0.80f * e_d + 0.58f * e_t + 0.12f * e_m),
                               glm::normalize(0.86f * e_d + 0.48f * e_t + 0.10f * e_m),
                               glm::normalize(0.92f * e_d + 0.38f * e_t + 0.08f * e_m)};
    const float lens[3] = {0.046f, 0.034f, 0.029f};
    const float radii[4] = {0.0125f, 0.0108f, 0.0098f, 0.0085f};
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 q = p + dirs[k] * (lens[k] * sc);
      m.finger[Thumb][k] = add.cone(p, q, radii[k], radii[k + 1], "lThumb" + std::to_string(k + 1));
      p = q;
    }
  }

  // Leg: thigh with quadriceps and hamstrings, knee cap, shin with calf.
  const glm::vec3 hip = joint(sk, "l_hip"), knee = joint(sk, "l_knee"), ankle = joint(sk, "l_ankle");
  const glm::mat3 th = frame_from(knee - hip, fwd);
  m.thigh.push_back(add.cone(hip, knee, 0.084f, 0.050f, "lThigh"));
  m.thigh.push_back(add.ellipsoid(along(hip, knee, 0.42f) + th[2] * 0.020f, th, {0.068f, 0.17f, 0.062f}, "lThigh"));
  m.thigh.push_back(add.ellipsoid(along(hip, knee, 0.36f) - th[2] * 0.022f, th, {0.064f, 0.16f, 0.056f}, "lThigh"));
  m.thigh.push_back(add.ellipsoid(knee + th[2] * 0.036f + th[1] * 0.01f, th, {0.030f, 0.035f, 0.020f}, "lThigh"));
  const glm::mat3 sh = frame_from(ankle - knee, fwd);
  m.shin.push_back(add.cone(knee, ankle, 0.049f, 0.033f, "lShin"));
  m.shin.push_back(add.ellipsoid(along(knee, ankle, 0.30f) - sh[2] * 0.024f + sh[0] * 0.004f, sh,
                                 {0.050f, 0.12f, 0.047f}, "lShin"));

  // Foot along heel -> forefoot tip (toe-out included); the sole is cut flat at y = 0 in evaluate().
  const glm::vec3 heel = site_or(sk, "l_calcaneous_post_pt", ankle + glm::vec3(-0.013f, -0.04f, -0.044f));
  const glm::vec3 toe_tip = site_or(sk, "l_forefoot_tip", ankle + glm::vec3(0.025f, -0.064f, 0.221f));
  glm::vec3 w = toe_tip - heel;
  w.y = 0.0f;
  const float foot_len = glm::length(w);
  w /= foot_len;
  const glm::mat3 ft = frame_from({0.0f, 1.0f, 0.0f}, w);  // columns: u (lateral), up, w (along the foot)
  const glm::vec3 heel0(heel.x, 0.0f, heel.z);
  auto on_foot = [&](float f, float y) { return heel0 + w * (f * foot_len) + glm::vec3(0.0f, y, 0.0f); };
  m.foot.push_back(add.ellipsoid(on_foot(0.14f, 0.034f), I, glm::vec3(0.036f), "lFoot"));  // heel
  m.foot.push_back(add.ellipsoid(on_foot(0.40f, 0.030f), ft, {0.042f, 0.046f, 0.115f}, "lFoot"));
  m.foot.push_back(add.box(on_foot(0.70f, 0.022f), ft, {0.049f, 0.024f, 0.042f}, 0.020f, "lFoot"));
  m.foot.push_back(add.box(on_foot(0.895f, 0.016f) - ft[0] * 0.003f, ft, {0.046f, 0.017f, 0.028f}, 0.015f, "lToe"));

  // Part mirror table: l* <-> r*.
  const auto& names = paper_part_names();
  m.mirror_part.resize(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::string other = names[i];
    if (other.size() > 1 && (other[0] == 'l' || other[0] == 'r') && std::isupper(static_cast<unsigned char>(other[1])))
      other[0] = other[0] == 'l' ? 'r' : 'l';
    m.mirror_part[i] = part_index(other);
  }
  return m;
}

// ---- Evaluation -------------------------------------------------------------------------------------------

float eval_prim(const BodyModel& m, const Prim& s, const glm::vec3& q) {
  switch (s.shape) {
    case Shape::Cone: return sd_cone(s, q);
    case Shape::Ellipsoid: return sd_ellipsoid(s, q);
    case Shape::Box: return sd_box(s, q);
    case Shape::Loft: return sd_loft(m.loft, q);
  }
  return 1.0f;
}

// Primitives within this distance of a point's box always take part; others read as "far" (kFar), which is
// exact for the union wherever the result is below kActiveMargin - the largest blend radius.
constexpr float kActiveMargin = 0.06f, kFar = 1.0f;

// Signed distance at q (x >= 0 side; callers mirror). `active` marks the primitives near q.
float evaluate(const BodyModel& m, const glm::vec3& q, const std::vector<std::uint8_t>& active) {
  auto P = [&](int i) { return active[static_cast<std::size_t>(i)] ? eval_prim(m, m.prims[i], q) : kFar; };
  auto blend = [&](const std::vector<int>& ids, float k) {
    float d = kFar;
    for (int i : ids) d = smin(d, P(i), k);
    return d;
  };
  float body = blend(m.torso, 0.035f);
  body = smin(body, blend(m.head, 0.02f), 0.03f);
  body = smin(body, blend(m.eyes, 0.0f), 0.004f);

  // Arm: the blend with the trunk fades out below the armpit so forearm and hand never melt into the hips.
  const float upper = blend(m.upper_arm, 0.03f);
  const float fore = blend(m.forearm, 0.025f);
  const float palm = blend(m.palm, 0.012f);
  // Each finger blends with the palm on its own and the fingers join by a hard min: a running smooth union would
  // also blend neighbouring fingers into each other.
  float hand = kFar;
  for (int f = 0; f < 5; ++f) {
    float d = kFar;
    for (int k = 0; k < 3; ++k) d = smin(d, P(m.finger[f][k]), 0.004f);
    hand = std::min(hand, smin(palm, d, f == Thumb ? 0.016f : 0.008f));
  }
  const float arm = smin(smin(upper, fore, 0.025f), hand, 0.02f);

  const float leg_upper = smin(blend(m.thigh, 0.04f), blend(m.shin, 0.03f), 0.03f);
  // The sole is cut flat by a smooth max: a sharp sole edge makes meshoptimizer fold triangles over it.
  const float leg = smax(smin(leg_upper, blend(m.foot, 0.025f), 0.03f), -q.y, 0.012f);
  body = smin(body, leg, 0.035f * smoothstep(0.70f, 0.86f, q.y));
  // Below the armpit the trunk and legs are carved back to kArmClearance from the arm, so a hanging hand or wrist
  // never touches a hip or thigh. Touching (as real hands do) fused arm and body into one surface: the levels had
  // genus 4, and the fused patches stretched up to 28x and flipped as the arm swung. The carve fades out towards
  // the shoulder, where the arm does join the trunk.
  constexpr float kArmClearance = 0.012f;
  const float carve = kArmClearance * (1.0f - smoothstep(1.16f, 1.26f, q.y));
  body = std::max(body, carve - arm);
  return smin(body, arm, 0.03f * smoothstep(1.22f, 1.34f, q.y));
}

// Part of the primitive nearest to q (smallest own distance); the loft splits by height.
std::uint16_t part_at(const BodyModel& m, glm::vec3 p) {
  const bool right = p.x < 0.0f;
  const glm::vec3 q(std::abs(p.x), p.y, p.z);
  float best = std::numeric_limits<float>::max();
  std::uint16_t part = 0;
  for (const Prim& s : m.prims) {
    float d = eval_prim(m, s, q);
    if (&s == &m.prims[static_cast<std::size_t>(m.eyes[0])]) d -= 0.004f;  // the eye wins its whole bulge
    if (d < best) {
      best = d;
      part = s.part;
      if (s.shape == Shape::Loft)
        part = q.y < 1.0f ? m.loft_part_hip : (q.y < 1.2f ? m.loft_part_abdomen : m.loft_part_chest);
    }
  }
  return right ? m.mirror_part[part] : part;
}

// ---- Grid and marching tetrahedra ---------------------------------------------------------------------------

struct Grid {
  glm::vec3 origin{0.0f};
  float cell = 0.0f;
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> value;
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * ny + j) * nx + i;
  }
  glm::vec3 point(int i, int j, int k) const { return origin + glm::vec3(i, j, k) * cell; }
};

Grid sample(const BodyModel& m, float cell) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const Prim& s : m.prims) {
    lo = glm::min(lo, s.lo);
    hi = glm::max(hi, s.hi);
  }
  Grid g;
  g.cell = cell;
  // Mirror-symmetric samples (a column at x = 0) so the two halves are extracted identically, and y = 0 (the sole
  // plane) between two layers so no sample sits exactly on the cut.
  const float half_x = std::max(hi.x, -lo.x) + 2.0f * cell;
  const int half_nx = static_cast<int>(std::ceil(half_x / cell));
  g.nx = 2 * half_nx + 1;
  g.origin.x = -half_nx * cell;
  const int below = 2;
  g.origin.y = -(below + 0.5f) * cell;
  g.ny = static_cast<int>(std::ceil((hi.y - g.origin.y) / cell)) + 3;
  g.origin.z = lo.z - 2.0f * cell;
  g.nz = static_cast<int>(std::ceil((hi.z - g.origin.z) / cell)) + 3;
  g.value.assign(static_cast<std::size_t>(g.nx) * g.ny * g.nz, kFar);

  // Blocks of B^3 samples: the centre decides whether the block can hold surface at all (the distance estimate is
  // at worst ~2-Lipschitz here), and the primitives near the block are listed once for all its samples.
  constexpr int B = 8;
  const int bx = (g.nx + B - 1) / B, by = (g.ny + B - 1) / B, bz = (g.nz + B - 1) / B;
  const float half_diag = 0.5f * std::sqrt(3.0f) * (B - 1) * cell;
  tbb::parallel_for(0, bx * by * bz, [&](int b) {
    const int i0 = (b % bx) * B, j0 = ((b / bx) % by) * B, k0 = (b / (bx * by)) * B;
    const int i1 = std::min(i0 + B, g.nx), j1 = std::min(j0 + B, g.ny), k1 = std::min(k0 + B, g.nz);
    // Work in the x >= 0 half: the block's mirrored box.
    glm::vec3 blo = g.point(i0, j0, k0), bhi = g.point(i1 - 1, j1 - 1, k1 - 1);
    glm::vec3 qlo = blo, qhi = bhi;
    qlo.x = (blo.x <= 0.0f && bhi.x >= 0.0f) ? 0.0f : std::min(std::abs(blo.x), std::abs(bhi.x));
    qhi.x = std::max(std::abs(blo.x), std::abs(bhi.x));
    std::vector<std::uint8_t> active(m.prims.size(), 0);
    bool any = false;
    for (std::size_t p = 0; p < m.prims.size(); ++p) {
      const Prim& s = m.prims[p];
      const bool hit = glm::all(glm::lessThanEqual(s.lo - kActiveMargin, qhi)) &&
                       glm::all(glm::greaterThanEqual(s.hi + kActiveMargin, qlo));
      active[p] = hit;
      any |= hit;
    }
    if (!any) return;  // stays kFar: outside, far from the surface
    const glm::vec3 c = 0.5f * (blo + bhi);
    const float dc = evaluate(m, {std::abs(c.x), c.y, c.z}, active);
    const float skip = 2.0f * half_diag + 2.0f * cell;
    for (int k = k0; k < k1; ++k)
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i) {
          float d = dc;
          if (std::abs(dc) <= skip) {
            const glm::vec3 p = g.point(i, j, k);
            d = evaluate(m, {std::abs(p.x), p.y, p.z}, active);
          }
          // Samples within a tenth of a cell of the surface are pushed off it (keeping their side): otherwise
          // several edge vertices land on one sample and their slivers mislead the simplifier's fold checks.
          const float nudge = 0.1f * cell;
          if (std::abs(d) < nudge) d = d < 0.0f ? -nudge : nudge;
          g.value[g.index(i, j, k)] = d;
        }
  });
  return g;
}

struct RawMesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> triangles;
};

// Marching tetrahedra over the Kuhn split of each cube (six tetrahedra around the 0-7 diagonal, the same in every
// cube, so neighbouring cubes agree on their shared face diagonals). A sample is inside iff its value < 0; the
// piecewise-linear isosurface of such a split never has a non-manifold edge or vertex.
RawMesh extract(const Grid& g) {
  RawMesh out;
  std::unordered_map<std::uint64_t, std::uint32_t> edge_vertex;
  edge_vertex.reserve(1 << 20);
  const int corner_offset[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  const int perms[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};

  for (int k = 0; k + 1 < g.nz; ++k)
    for (int j = 0; j + 1 < g.ny; ++j)
      for (int i = 0; i + 1 < g.nx; ++i) {
        float v[8];
        int inside = 0;
        for (int c = 0; c < 8; ++c) {
          v[c] = g.value[g.index(i + corner_offset[c][0], j + corner_offset[c][1], k + corner_offset[c][2])];
          inside += v[c] < 0.0f;
        }
        if (inside == 0 || inside == 8) continue;
        auto vertex_on = [&](int c0, int c1) {  // c0's bits are a subset of c1's
          const std::size_t g0 = g.index(i + corner_offset[c0][0], j + corner_offset[c0][1], k + corner_offset[c0][2]);
          const std::uint64_t key = static_cast<std::uint64_t>(g0) * 8 + static_cast<std::uint64_t>(c1 ^ c0);
          const auto [it, fresh] = edge_vertex.try_emplace(key, static_cast<std::uint32_t>(out.positions.size()));
          if (fresh) {
            const float t = std::clamp(v[c0] / (v[c0] - v[c1]), 0.02f, 0.98f);
            const glm::vec3 p0 = g.point(i + corner_offset[c0][0], j + corner_offset[c0][1], k + corner_offset[c0][2]);
            const glm::vec3 p1 = g.point(i + corner_offset[c1][0], j + corner_offset[c1][1], k + corner_offset[c1][2]);
            out.positions.push_back(p0 + (p1 - p0) * t);
          }
          return it->second;
        };
        auto corner_pos = [&](int c) {
          return glm::vec3(corner_offset[c][0], corner_offset[c][1], corner_offset[c][2]);
        };
        // Emits a triangle over edges (e0, e1, e2) so that its normal points from `in` towards `out` (corners).
        // Orientation is decided on the edge midpoints, where the triangle is never degenerate.
        auto emit = [&](const int (*e)[2], glm::vec3 in_pt, glm::vec3 out_pt) {
          glm::vec3 mid[3];
          for (int t = 0; t < 3; ++t) mid[t] = 0.5f * (corner_pos(e[t][0]) + corner_pos(e[t][1]));
          const bool flip = glm::dot(glm::cross(mid[1] - mid[0], mid[2] - mid[0]), out_pt - in_pt) < 0.0f;
          std::uint32_t idx[3];
          for (int t = 0; t < 3; ++t) {
            const int a = e[t][0], b = e[t][1];
            idx[t] = (a & b) == a ? vertex_on(a, b) : vertex_on(b, a);
          }
          if (flip) std::swap(idx[1], idx[2]);
          out.triangles.insert(out.triangles.end(), {idx[0], idx[1], idx[2]});
        };
        for (const auto& perm : perms) {
          const int tet[4] = {0, perm[0], perm[0] | perm[1], 7};
          int in[4], out_c[4], n_in = 0, n_out = 0;
          for (int c : tet) (v[c] < 0.0f ? in[n_in++] : out_c[n_out++]) = c;
          if (n_in == 0 || n_out == 0) continue;
          glm::vec3 cin(0.0f), cout(0.0f);
          for (int t = 0; t < n_in; ++t) cin += corner_pos(in[t]) / float(n_in);
          for (int t = 0; t < n_out; ++t) cout += corner_pos(out_c[t]) / float(n_out);
          if (n_in == 1 || n_out == 1) {
            const int lone = n_in == 1 ? in[0] : out_c[0];
            const int* others = n_in == 1 ? out_c : in;
            const int e[3][2] = {{lone, others[0]}, {lone, others[1]}, {lone, others[2]}};
            emit(e, cin, cout);
          } else {
            // Quad over edges in0-out0, in0-out1, in1-out1, in1-out0, split along one diagonal.
            const int e1[3][2] = {{in[0], out_c[0]}, {in[0], out_c[1]}, {in[1], out_c[1]}};
            const int e2[3][2] = {{in[0], out_c[0]}, {in[1], out_c[1]}, {in[1], out_c[0]}};
            emit(e1, cin, cout);
            emit(e2, cin, cout);
          }
        }
      }
  return out;
}

Mesh to_mesh(const BodyModel& m, SimplifiedSurface s, const std::string& name) {
  return body_level_mesh(std::move(s), name, [&](std::size_t, const glm::vec3& p) { return part_at(m, p); });
}

}  // namespace

float body_signed_distance(const Skeleton& skeleton, const glm::vec3& p) {
  const BodyModel m = build_model(skeleton);
  const std::vector<std::uint8_t> all(m.prims.size(), 1);
  return evaluate(m, {std::abs(p.x), p.y, p.z}, all);
}

BodyLevels generate_default_body(const Skeleton& skeleton, const BodyOptions& options) {
  const BodyModel model = build_model(skeleton);
  const Grid grid = sample(model, options.grid_cell);
  const RawMesh raw = extract(grid);
  BodyLevels out;
  SimplifiedSurface prev{raw.positions, raw.triangles, {}};
  // Each level is simplified from the previous one: the finest pass does the heavy lifting once.
  for (int l = 0; l < 3; ++l) {
    SimplifiedSurface s = simplify_surface(prev.positions, prev.triangles,
                                           options.level_vertices[static_cast<std::size_t>(l)], kSkinnedMinQuality);
    prev = s;
    out.levels[static_cast<std::size_t>(l)] = to_mesh(model, std::move(s), "default_body_L" + std::to_string(l));
  }
  // The cage keeps the plain collapse: it is not drawn as it is but Loop-refined, which smooths slivers away, and
  // at 1,800 vertices the sliver limit cost accuracy (level 0 deviated from the refined cage by up to 17 mm at
  // rest with it, 11 mm without; strata report subdiv).
  out.cage =
      to_mesh(model, simplify_surface(prev.positions, prev.triangles, options.cage_vertices, 0.0), "default_body_cage");
  return out;
}

const BodyLevels& default_body() {
  static const BodyLevels body = [] {
    // Bump when the generator's output changes, so stale cache files are ignored.
    constexpr std::uint32_t kGeneratorVersion = 5;
    const Skeleton skeleton = load_default_humanoid().skeleton;
    const BodyOptions options;
    return cached_body_levels("default_body", body_cache_key(skeleton, options, kGeneratorVersion),
                              [&] { return generate_default_body(skeleton, options); });
  }();
  return body;
}

}  // namespace strata
