#include "systems/ik.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/euler.h"
#include "components/walker.h"

namespace strata {
namespace {

using dvec3 = glm::dvec3;
using dmat3 = glm::dmat3;

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPiDouble = 2.0 * kPi;
constexpr double kReachedTolerance = 1e-5;  // m, the kIkReached threshold
// A goal this far (m) outside the reachable shell still counts as reachable: goals made by FK in float land
// ~1e-8 m off the exact full-reach distance, and flagging them unreachable would pull them 0.01 % inward.
constexpr double kReachSlack = 1e-6;
// Unreachable goals are pulled this fraction of the full reach inside the shell (IKAN's 0.9999 * (L1 + L2)), so
// an over-stretched limb is not left exactly straight, where the swivel circle collapses to a point. Where the
// longest (shortest) reach is set by a hinge limit instead, as on the H-Anim knee, there is no singularity and
// the goal is clamped onto the shell itself.
constexpr double kReachMargin = 1e-4;
constexpr int kSwivelSamples = 72;        // 5 degree steps around the swivel circle
constexpr int kFineSwivelSamples = 360;   // 1 degree steps, only when the 5 degree pass finds nothing
constexpr int kBisectionSteps = 24;       // 5 deg / 2^24: arc ends to ~5e-9 rad
constexpr int kLocalSearchSteps = 40;     // ternary steps when no sample is feasible

bool is_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool is_finite(const glm::quat& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}

// Wraps an angle into (-pi, pi].
double wrap_radians(double a) {
  if (a > -kPi && a <= kPi) return a;
  a = std::remainder(a, kTwoPiDouble);
  return a <= -kPi ? a + kTwoPiDouble : a;
}

// Any unit vector perpendicular to unit `n`: the world axis least aligned with it, orthogonalised.
dvec3 any_perpendicular(const dvec3& n) {
  const dvec3 ax = std::abs(n.x) < 0.6 ? dvec3(1, 0, 0) : (std::abs(n.y) < 0.6 ? dvec3(0, 1, 0) : dvec3(0, 0, 1));
  return glm::normalize(ax - glm::dot(ax, n) * n);
}

// The component of `p` perpendicular to unit `n`, normalised; `fallback` (also made perpendicular) when `p` is
// (nearly) parallel to `n` or zero, and any perpendicular when both are.
dvec3 perpendicular_direction(const dvec3& p, const dvec3& n, const dvec3& fallback) {
  const dvec3 q = p - glm::dot(p, n) * n;
  const double len2 = glm::dot(q, q);
  if (len2 > 1e-18 && len2 > 1e-12 * glm::dot(p, p)) return q / std::sqrt(len2);
  const dvec3 f = fallback - glm::dot(fallback, n) * n;
  const double flen = glm::length(f);
  if (flen > 1e-9) return f / flen;
  return any_perpendicular(n);
}

// Rotation about unit `axis` by the angle whose cosine and sine are c and s (Rodrigues).
dmat3 axis_angle(const dvec3& axis, double c, double s) {
  const double k = 1.0 - c;
  const double x = axis.x, y = axis.y, z = axis.z;
  dmat3 m;
  m[0] = dvec3(c + k * x * x, k * x * y + s * z, k * x * z - s * y);
  m[1] = dvec3(k * x * y - s * z, c + k * y * y, k * y * z + s * x);
  m[2] = dvec3(k * x * z + s * y, k * y * z - s * x, c + k * z * z);
  return m;
}

// Rotation of a quaternion that need not be unit, as fk.cpp reads it (s = 2/|q|^2; the zero quaternion gives I).
dmat3 quat_matrix(double x, double y, double z, double w) {
  const double s = 2.0 / (x * x + y * y + z * z + w * w + 1e-30);
  dmat3 m;
  m[0] = dvec3(1.0 - s * (y * y + z * z), s * (x * y + w * z), s * (x * z - w * y));
  m[1] = dvec3(s * (x * y - w * z), 1.0 - s * (x * x + z * z), s * (y * z + w * x));
  m[2] = dvec3(s * (x * z + w * y), s * (y * z - w * x), 1.0 - s * (x * x + y * y));
  return m;
}
dmat3 quat_matrix(const glm::quat& q) { return quat_matrix(q.x, q.y, q.z, q.w); }

// Unit quaternion (w >= 0) of a rotation matrix: Shepperd's choice of the largest of 4w^2, 4x^2, 4y^2, 4z^2 to
// divide by, so no branch divides by a small number.
glm::quat to_quat(const dmat3& m) {
  const double tr = m[0][0] + m[1][1] + m[2][2];
  double x, y, z, w;
  if (tr >= m[0][0] && tr >= m[1][1] && tr >= m[2][2]) {
    const double r = std::sqrt(1.0 + tr) * 2.0;
    w = 0.25 * r, x = (m[1][2] - m[2][1]) / r, y = (m[2][0] - m[0][2]) / r, z = (m[0][1] - m[1][0]) / r;
  } else if (m[0][0] >= m[1][1] && m[0][0] >= m[2][2]) {
    const double r = std::sqrt(std::max(0.0, 1.0 + m[0][0] - m[1][1] - m[2][2])) * 2.0;
    x = 0.25 * r, w = (m[1][2] - m[2][1]) / r, y = (m[1][0] + m[0][1]) / r, z = (m[2][0] + m[0][2]) / r;
  } else if (m[1][1] >= m[2][2]) {
    const double r = std::sqrt(std::max(0.0, 1.0 + m[1][1] - m[0][0] - m[2][2])) * 2.0;
    y = 0.25 * r, w = (m[2][0] - m[0][2]) / r, x = (m[1][0] + m[0][1]) / r, z = (m[2][1] + m[1][2]) / r;
  } else {
    const double r = std::sqrt(std::max(0.0, 1.0 + m[2][2] - m[0][0] - m[1][1])) * 2.0;
    z = 0.25 * r, w = (m[0][1] - m[1][0]) / r, x = (m[2][0] + m[0][2]) / r, y = (m[2][1] + m[1][2]) / r;
  }
  if (w < 0.0) x = -x, y = -y, z = -z, w = -w;
  const double len = std::sqrt(x * x + y * y + z * z + w * w);
  return glm::quat(static_cast<float>(w / len), static_cast<float>(x / len), static_cast<float>(y / len),
                   static_cast<float>(z / len));
}

// limit_angles in double (components/euler.h): the search compares against limits at bisection resolution.
dvec3 euler_angles(const dmat3& m) { return limit_angles(m); }

dmat3 rotation_from_angles(const dvec3& a) {
  const double sx = std::sin(a.x), cx = std::cos(a.x), sy = std::sin(a.y), cy = std::cos(a.y);
  const double sz = std::sin(a.z), cz = std::cos(a.z);
  dmat3 m;  // columns of Rx(x) Rz(z) Ry(y)
  m[0] = dvec3(cz * cy, cx * sz * cy + sx * sy, sx * sz * cy - cx * sy);
  m[1] = dvec3(-sz, cx * cz, sx * cz);
  m[2] = dvec3(cz * sy, cx * sz * sy - sx * cy, sx * sz * sy + cx * cy);
  return m;
}

double violation(const JointLimits& limits, const dvec3& angles) {
  double total = 0.0;
  for (int a = 0; a < 3; ++a)
    total += std::max(0.0, limits.lower[a] - angles[a]) + std::max(0.0, angles[a] - limits.upper[a]);
  return total;
}

// True when some angle congruent to `x` (mod 2 pi) lies in [lo, hi].
bool angle_in_range(double x, double lo, double hi) {
  if (hi - lo >= kTwoPiDouble) return true;
  double k = std::fmod(x - lo, kTwoPiDouble);
  if (k < 0.0) k += kTwoPiDouble;
  return lo + k <= hi;
}

// The hinge's range for theta, the angle about the flexion axis. Limits are about the joint's +X, so a -X
// flexion axis mirrors them. A hinge about any other axis has no matching per-axis limit: left unlimited.
void hinge_range(const JointLimits& limits, const dvec3& axis, double& lo, double& hi) {
  lo = -kPi, hi = kPi;
  if (!limits.present) return;
  if (axis.x > 0.999)
    lo = limits.lower.x, hi = limits.upper.x;
  else if (axis.x < -0.999)
    lo = -limits.upper.x, hi = -limits.lower.x;
}

// Solves alpha cos(theta) + beta sin(theta) = g for a theta in [lo, hi]; false when neither root lies there.
// Of the two roots theta0 +- acos(g / rho), the + one is preferred: past the straightest configuration theta0,
// a growing angle flexes (the flexion axis's sign was chosen for that), the bend side a limb should keep.
// Otherwise `theta` is the hinge end nearest to a root (rounding can leave a clamped g's root just outside).
bool hinge_root(double alpha, double beta, double g, double lo, double hi, double& theta) {
  const double rho = std::sqrt(alpha * alpha + beta * beta);
  if (rho < 1e-12) {  // a zero-length bone: theta cannot change the reach
    theta = std::clamp(0.0, lo, hi);
    return false;
  }
  const double theta0 = std::atan2(beta, alpha);
  const double delta = std::acos(std::clamp(g / rho, -1.0, 1.0));
  double best_out = 1e300;
  for (double root : {theta0 + delta, theta0 - delta}) {
    double k = std::fmod(root - lo, kTwoPiDouble);
    if (k < 0.0) k += kTwoPiDouble;
    const double in = lo + k;  // the representative at or above lo
    if (in <= hi) {
      theta = in;
      return true;
    }
    const double above = in - hi, below = lo + kTwoPiDouble - in;
    if (std::min(above, below) < best_out) best_out = std::min(above, below), theta = above < below ? hi : lo;
  }
  return false;
}

// Per-solve data of the swivel search: R1(phi) = A + cos(phi) B + sin(phi) C (tech-brief 1.5, item 1), and for
// orientation goals R2(phi) = Rm^T R1(phi)^T O. R2 has the same a + cos b + sin c form, but building its three
// matrices costs six products up front, which the fast path (one evaluation) would pay for nothing.
struct SwivelFamily {
  dmat3 a, b, c;
  dmat3 hinge_t;  // Rm^T
  dmat3 desired;  // O
  const JointLimits* upper_limits = nullptr;  // null when the upper joint has no limits
  const JointLimits* lower_limits = nullptr;  // null unless an orientation goal and the lower joint has limits

  dmat3 upper(double phi) const { return a + std::cos(phi) * b + std::sin(phi) * c; }
  dmat3 lower(const dmat3& r1) const { return hinge_t * glm::transpose(r1) * desired; }
  double cost(double phi) const {
    const dmat3 r1 = upper(phi);
    double v = 0.0;
    if (upper_limits) v += violation(*upper_limits, euler_angles(r1));
    if (lower_limits) v += violation(*lower_limits, euler_angles(lower(r1)));
    return v;
  }
};

// Between an infeasible and a feasible swivel, the feasible end of the boundary.
double bisect_boundary(const SwivelFamily& f, double bad, double good) {
  for (int i = 0; i < kBisectionSteps; ++i) {
    const double mid = 0.5 * (bad + good);
    (f.cost(mid) == 0.0 ? good : bad) = mid;
  }
  return good;
}

struct SwivelChoice {
  double phi = 0.0;
  std::uint32_t flags = 0;
};

// One pass over `samples` evenly spaced swivels, walking outward from the request on both sides. At the first
// feasible sample (on either side) the arc end facing the request is refined by bisection and returned in `phi`.
// Otherwise returns false and leaves the least violating sample in best_phi/best_cost.
bool scan_swivel(const SwivelFamily& f, double requested, int samples, double& phi, double& best_phi,
                 double& best_cost) {
  const double step = kTwoPiDouble / samples;
  const int half = samples / 2;
  for (int k = 1; k <= half; ++k) {
    const double up = requested + k * step, down = requested - k * step;
    const double cu = f.cost(up);
    const double cd = k == half ? cu : f.cost(down);  // k = half is one point seen from both sides
    if (cu == 0.0 || cd == 0.0) {
      double dist = 1e300;
      if (cu == 0.0) {
        phi = bisect_boundary(f, up - step, up);
        dist = phi - requested;
      }
      if (cd == 0.0 && k != half) {
        const double b = bisect_boundary(f, down + step, down);
        if (requested - b < dist) phi = b;
      }
      return true;
    }
    if (cu < best_cost) best_cost = cu, best_phi = up;
    if (cd < best_cost) best_cost = cd, best_phi = down;
  }
  return false;
}

// Strata's simplification of IKAN's limit handling (tech-brief 1.5): keep the requested swivel when feasible;
// else scan 5-degree samples outward from it and refine the first feasible arc's end facing the request. IKAN's
// exact method intersects analytic phi-intervals per Euler angle; the sampled one is simpler and shares the limit
// test with everything else, but misses arcs narrower than its step. Those occur next to the Euler lock (upper
// joint |z| near pi/2, where x and y swing through large angles for a small change of phi), so only when the
// coarse pass finds nothing, a 1-degree pass and then a local minimisation look again before declaring the limits
// infeasible: the common feasible case stays cheap and only the rare hard one pays for the fine pass.
SwivelChoice choose_swivel(const SwivelFamily& f, double requested) {
  SwivelChoice out{requested, 0};
  if (f.upper_limits == nullptr && f.lower_limits == nullptr) return out;
  const double req_cost = f.cost(requested);
  if (req_cost == 0.0) return out;  // the fast path: walking poses land here

  double best_phi = requested, best_cost = req_cost;
  out.flags = kIkSwivelMoved;
  if (scan_swivel(f, requested, kSwivelSamples, out.phi, best_phi, best_cost)) return out;
  if (scan_swivel(f, requested, kFineSwivelSamples, out.phi, best_phi, best_cost)) return out;

  // Still nothing. The violation is continuous in phi; minimise it between the best fine sample's neighbours
  // (ternary search: it needs no derivative, and the violation's kinks at limit crossings defeat Newton).
  const double step = kTwoPiDouble / kFineSwivelSamples;
  double lo = best_phi - step, hi = best_phi + step;
  for (int i = 0; i < kLocalSearchSteps; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (f.cost(m1) <= f.cost(m2))
      hi = m2;
    else
      lo = m1;
  }
  const double local = 0.5 * (lo + hi);
  const double local_cost = f.cost(local);
  if (local_cost == 0.0) {
    // A feasible arc narrower than a degree: move to its end facing the request. The fine sample between them
    // (one step from `local`, towards the request) is infeasible, or the scan would have stopped there.
    const double towards = wrap_radians(requested - local) >= 0.0 ? 1.0 : -1.0;
    out.phi = bisect_boundary(f, local + towards * step, local);
    return out;
  }
  out.phi = local_cost < best_cost ? local : best_phi;
  out.flags = kIkLimitsInfeasible;
  return out;
}

void check_joint(const Skeleton& skeleton, std::int32_t joint, const LimbChain& limb) {
  if (joint < 0 || static_cast<std::size_t>(joint) >= skeleton.joint_count())
    throw std::invalid_argument("solve_limb: limb '" + limb.name + "' has a joint index outside the skeleton");
}

}  // namespace

std::vector<LimbChain> make_limbs(const Skeleton& skeleton) {
  struct Spec {
    const char* name;
    const char* joints[3];
    glm::vec3 axis;
    glm::vec3 pole;
  };
  // Order = LimbIndex. Knee flexion is +X and elbow flexion -X (data/default_skeleton.x3d), so a positive theta
  // flexes both; knees point forward (+Z) and elbows back (-Z).
  static const Spec kSpecs[kLimbCount] = {
      {"l_leg", {"l_hip", "l_knee", "l_ankle"}, {1, 0, 0}, {0, 0, 1}},
      {"r_leg", {"r_hip", "r_knee", "r_ankle"}, {1, 0, 0}, {0, 0, 1}},
      {"l_arm", {"l_shoulder", "l_elbow", "l_wrist"}, {-1, 0, 0}, {0, 0, -1}},
      {"r_arm", {"r_shoulder", "r_elbow", "r_wrist"}, {-1, 0, 0}, {0, 0, -1}},
  };
  std::vector<LimbChain> limbs;
  limbs.reserve(kLimbCount);
  for (const Spec& spec : kSpecs) {
    std::int32_t idx[3];
    for (int k = 0; k < 3; ++k) {
      idx[k] = skeleton.find_joint(spec.joints[k]);
      if (idx[k] < 0)
        throw std::invalid_argument("make_limbs: skeleton '" + skeleton.name + "' has no joint '" + spec.joints[k] +
                                    "' (needed for " + spec.name + ")");
    }
    // The solver's chain model needs middle under upper and lower under middle.
    for (int k = 1; k < 3; ++k)
      if (skeleton.parents[idx[k]] != idx[k - 1])
        throw std::invalid_argument(std::string("make_limbs: joint '") + spec.joints[k] + "' is not a child of '" +
                                    spec.joints[k - 1] + "'");
    limbs.push_back(LimbChain{spec.name, idx[0], idx[1], idx[2], spec.axis, spec.pole});
  }
  return limbs;
}

LimbSolveResult solve_limb(const Skeleton& skeleton, const LimbChain& limb, const LimbSolveInput& input) {
  LimbSolveResult result;
  if (input.mode == IkMode::Off) return result;
  check_joint(skeleton, limb.upper, limb);
  check_joint(skeleton, limb.middle, limb);
  check_joint(skeleton, limb.lower, limb);
  if (!is_finite(input.goal)) {
    // Nothing sensible to aim at: the rest pose, flagged. Its error against a non-finite goal is undefined;
    // report 0 rather than let a NaN or inf leave the solver.
    result.flags = kIkInvalidInput;
    return result;
  }
  std::uint32_t flags = 0;

  const dvec3 cu(skeleton.centers[limb.upper]);
  const dvec3 t = dvec3(skeleton.centers[limb.middle]) - cu;
  const dvec3 s = dvec3(skeleton.centers[limb.lower]) - dvec3(skeleton.centers[limb.middle]);
  dvec3 axis(limb.flexion_axis);
  axis = glm::length(axis) > 1e-12 ? glm::normalize(axis) : dvec3(1, 0, 0);
  double theta_lo = 0.0, theta_hi = 0.0;
  hinge_range(skeleton.limits[limb.middle], axis, theta_lo, theta_hi);

  // ---- theta from the goal distance (tech-brief 1.2, general form) ----
  // |t + Rm(theta) s|^2 = base + 2 (alpha cos theta + beta sin theta).
  const double ta = glm::dot(t, axis), as = glm::dot(axis, s);
  const double alpha = glm::dot(t, s) - ta * as;
  const double beta = glm::dot(t, glm::cross(axis, s));
  const double l1sq = glm::dot(t, t), l2sq = glm::dot(s, s);
  const double base = l1sq + l2sq + 2.0 * ta * as;
  const double rho = std::sqrt(alpha * alpha + beta * beta);

  const dvec3 goal(input.goal);
  const dvec3 d = goal - cu;
  const double dist = glm::length(d);
  const dvec3 rest_reach = t + s;
  // Direction to the goal; a goal on the upper joint has none, so keep the limb's rest direction.
  dvec3 n;
  if (dist > 1e-9)
    n = d / dist;
  else if (glm::length(rest_reach) > 1e-12)
    n = glm::normalize(rest_reach);
  else
    n = dvec3(0, -1, 0);

  // The common case first: a root inside the hinge's range. Only when there is none is the reachable shell
  // worked out, which costs the trigonometry of the hinge ends.
  double theta = 0.0;
  const double gamma_goal = 0.5 * (dist * dist - l1sq - l2sq) - ta * as;
  const bool direct = dist > 1e-9 && rho >= 1e-12 && std::abs(gamma_goal) <= rho &&
                      hinge_root(alpha, beta, gamma_goal, theta_lo, theta_hi, theta);
  if (!direct) {
    // Range of g(theta) = alpha cos + beta sin over the hinge's range: its ends, plus the extremes +-rho where
    // the straightest (theta0) and most folded (theta0 + pi) configurations fall inside.
    const double theta0 = std::atan2(beta, alpha);
    const double g_lo_end = alpha * std::cos(theta_lo) + beta * std::sin(theta_lo);
    const double g_hi_end = alpha * std::cos(theta_hi) + beta * std::sin(theta_hi);
    double g_max = std::max(g_lo_end, g_hi_end), g_min = std::min(g_lo_end, g_hi_end);
    // Whether the extreme reach is the singular straight/folded configuration rather than a hinge limit.
    const bool max_singular = angle_in_range(theta0, theta_lo, theta_hi);
    const bool min_singular = angle_in_range(theta0 + kPi, theta_lo, theta_hi);
    if (max_singular) g_max = rho;
    if (min_singular) g_min = -rho;
    const double d_max = std::sqrt(std::max(0.0, base + 2.0 * g_max));
    const double d_min = std::sqrt(std::max(0.0, base + 2.0 * g_min));
    double target = dist;
    if (dist > d_max + kReachSlack) {
      target = max_singular ? std::max(d_min, d_max - kReachMargin * d_max) : d_max;
      flags |= kIkUnreachable;
    } else if (dist < d_min - kReachSlack) {
      target = min_singular ? std::min(d_max, d_min + kReachMargin * d_max) : d_min;
      flags |= kIkUnreachable;
    } else {
      target = std::clamp(dist, d_min, d_max);
    }
    const double gamma = std::clamp(0.5 * (target * target - l1sq - l2sq) - ta * as, g_min, g_max);
    hinge_root(alpha, beta, gamma, theta_lo, theta_hi, theta);
  }
  // One sine and cosine of the half angle serve both the hinge matrix and the written quaternion.
  const double half_c = std::cos(0.5 * theta), half_s = std::sin(0.5 * theta);
  const dmat3 rm = axis_angle(axis, 1.0 - 2.0 * half_s * half_s, 2.0 * half_s * half_c);

  // ---- R1 from the swivel circle (tech-brief 1.3, 1.4) ----
  // Rest side: the lower joint direction n_r and the middle joint's offset from the upper->lower line, m_r.
  // R1 takes (n_r, m_r) to (n, e(phi)'s offset direction); this is the brief's F(e(phi), g) F(e_r, w_r)^T with
  // the lower joint as the primary axis, so the effector lands on the goal line exactly even for a straight limb,
  // where the middle joint's offset vanishes and the brief's second axis is undefined.
  const dvec3 w = t + rm * s;
  const double wlen = glm::length(w);
  const dvec3 n_r = wlen > 1e-12 ? w / wlen : (glm::length(t) > 1e-12 ? glm::normalize(t) : dvec3(0, -1, 0));
  // Straight limb: the side the middle joint moves to when the hinge flexes further, n_r x axis (knee forward,
  // elbow back at rest).
  const dvec3 m_r = perpendicular_direction(t, n_r, glm::cross(n_r, axis));
  const dvec3 k_r = glm::cross(n_r, m_r);

  // Target side: phi = 0 puts the middle joint in the (goal, pole) plane on the pole's side. A pole along the goal
  // direction (or zero, or non-finite) falls back to n x axis, the rest bend side carried along n.
  dvec3 pole(0.0);
  if (is_finite(input.pole))
    pole = dvec3(input.pole);
  else
    flags |= kIkInvalidInput;
  const dvec3 u = perpendicular_direction(pole, n, glm::cross(n, axis));
  const dvec3 v = glm::cross(n, u);

  SwivelFamily family;
  family.a = glm::outerProduct(n, n_r);
  family.b = glm::outerProduct(u, m_r) + glm::outerProduct(v, k_r);
  family.c = glm::outerProduct(v, m_r) - glm::outerProduct(u, k_r);
  if (skeleton.limits[limb.upper].present) family.upper_limits = &skeleton.limits[limb.upper];

  bool orient = input.mode == IkMode::PositionOrientation;
  dmat3 desired(1.0);
  if (orient) {
    const double qn = static_cast<double>(input.orientation.x) * input.orientation.x +
                      static_cast<double>(input.orientation.y) * input.orientation.y +
                      static_cast<double>(input.orientation.z) * input.orientation.z +
                      static_cast<double>(input.orientation.w) * input.orientation.w;
    if (!is_finite(input.orientation) || !(qn > 1e-20)) {
      flags |= kIkInvalidInput;  // no usable orientation: solve for the position only
      orient = false;
    } else {
      desired = quat_matrix(input.orientation);
    }
  }
  if (orient) {
    family.hinge_t = glm::transpose(rm);
    family.desired = desired;
    if (skeleton.limits[limb.lower].present) family.lower_limits = &skeleton.limits[limb.lower];
  }

  double requested = 0.0;
  if (std::isfinite(input.swivel_offset))
    requested = input.swivel_offset;
  else
    flags |= kIkInvalidInput;
  const SwivelChoice choice = choose_swivel(family, requested);
  flags |= choice.flags;

  const dmat3 r1 = family.upper(choice.phi);
  result.upper = to_quat(r1);
  result.middle = glm::quat(static_cast<float>(half_c), static_cast<glm::vec3>(axis * half_s));
  if (orient) {
    const dmat3 r2 = family.lower(r1);
    const JointLimits& lower_limits = skeleton.limits[limb.lower];
    // A feasible swivel already satisfied the lower joint's limits (they are part of the search's cost).
    const bool check = lower_limits.present && (choice.flags & kIkLimitsInfeasible) != 0;
    const dvec3 angles = check ? euler_angles(r2) : dvec3(0.0);
    if (check && violation(lower_limits, angles) > 0.0) {
      dvec3 clamped;
      for (int k = 0; k < 3; ++k)
        clamped[k] = std::clamp<double>(angles[k], lower_limits.lower[k], lower_limits.upper[k]);
      result.lower = to_quat(rotation_from_angles(clamped));
      flags |= kIkOrientationClamped;
    } else {
      result.lower = to_quat(r2);
    }
  }
  result.swivel = static_cast<float>(wrap_radians(choice.phi));

  // The error of what is written (the float quaternions), not of the double matrices.
  const dvec3 effector = cu + quat_matrix(result.upper) * (t + quat_matrix(result.middle) * s);
  const double error = glm::length(effector - goal);
  result.position_error = static_cast<float>(error);
  if (error < kReachedTolerance) flags |= kIkReached;
  result.flags = flags;
  return result;
}

namespace {

void ik_range(const IkJob& job, const std::int32_t* ancestors, std::size_t ancestor_count, std::size_t first,
              std::size_t last) {
  const Skeleton& skeleton = *job.skeleton;
  const std::span<const LimbChain> limbs = job.limbs;
  const std::size_t stride = job.local_rotation.stride;
  float* const local_rotation = job.local_rotation.base;
  const ColumnView<const float> rotations_in = job.local_rotation;
  // Indexed by joint; only the ancestors' entries are written and read. On the stack (48 KiB at the joint cap)
  // rather than a vector per chunk, so run() allocates nothing.
  JointFrame frames[kMaxJointsPerRig];
  for (std::size_t i = first; i < last; ++i) {
    // Parent frames of the upper joints, parents first (ancestors is in index order, parents[j] < j), each once
    // per walker however many limbs hang from it.
    for (std::size_t a = 0; a < ancestor_count; ++a) {
      const std::int32_t j = ancestors[a];
      const int p = skeleton.parents[j];
      frames[j] = joint_frame(skeleton, j, p < 0 ? JointFrame{} : frames[p], rotations_in, job.root_translation, i);
    }
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      const LimbChain& limb = limbs[k];
      const auto limb_index = static_cast<std::uint32_t>(k);
      std::uint32_t* flags_out = &job.ik_flags.at(limb_index, i);
      float* error_out = &job.ik_error.at(limb_index * kIkResultFloats + 0, i);
      JointFrame parent;
      const int p = skeleton.parents[limb.upper];
      if (p >= 0)
        parent = frames[p];
      else
        parent.g = glm::dvec3(job.root_translation.at(0, i), job.root_translation.at(1, i), job.root_translation.at(2, i));
      LimbSolveInput in;
      const LimbRequest request = limb_solve_input(limb, limb_index, parent, job.ik_goal, job.ik_mode, i, in);
      if (request != LimbRequest::Solve) {
        *flags_out = request == LimbRequest::InvalidGoal ? kIkInvalidInput : 0u, *error_out = 0.0f;
        continue;
      }
      const LimbSolveResult r = solve_limb(skeleton, limb, in);
      const std::int32_t joints[3] = {limb.upper, limb.middle, limb.lower};
      const glm::quat rotations[3] = {r.upper, r.middle, r.lower};
      for (int n = 0; n < 3; ++n) {
        float* q = local_rotation + static_cast<std::size_t>(joints[n]) * 4 * stride + i;
        q[0] = rotations[n].x, q[stride] = rotations[n].y, q[2 * stride] = rotations[n].z,
        q[3 * stride] = rotations[n].w;
      }
      *flags_out = r.flags;
      *error_out = r.position_error;
    }
  }
}

}  // namespace

JointFrame joint_frame(const Skeleton& skeleton, std::int32_t joint, const JointFrame& parent,
                       const ColumnView<const float>& local_rotation, const ColumnView<const float>& root_translation,
                       std::size_t i) {
  const auto j = static_cast<std::uint32_t>(joint);
  const dmat3 r = quat_matrix(local_rotation.at(j * 4 + 0, i), local_rotation.at(j * 4 + 1, i),
                              local_rotation.at(j * 4 + 2, i), local_rotation.at(j * 4 + 3, i));
  const dvec3 c(skeleton.centers[j]);
  JointFrame f;
  if (skeleton.parents[j] < 0) {
    const dvec3 root(root_translation.at(0, i), root_translation.at(1, i), root_translation.at(2, i));
    f.m = r;
    f.g = c - r * c + root;
  } else {
    f.m = parent.m * r;
    f.g = parent.m * (c - r * c) + parent.g;
  }
  return f;
}

LimbRequest limb_solve_input(const LimbChain& limb, std::uint32_t limb_index, const JointFrame& parent,
                             const ColumnView<const float>& ik_goal, const ColumnView<const std::int32_t>& ik_mode,
                             std::size_t i, LimbSolveInput& input) {
  auto goal_at = [&](std::uint32_t c) { return ik_goal.at(limb_index * kIkGoalFloats + c, i); };
  // Anything but 1 or 2 reads as Off.
  const std::int32_t mode_value = ik_mode.at(limb_index, i);
  IkMode mode = IkMode::Off;
  if (mode_value == static_cast<std::int32_t>(IkMode::Position))
    mode = IkMode::Position;
  else if (mode_value == static_cast<std::int32_t>(IkMode::PositionOrientation))
    mode = IkMode::PositionOrientation;
  if (mode == IkMode::Off) return LimbRequest::Off;
  const glm::vec3 goal_h(goal_at(kGoalPx), goal_at(kGoalPy), goal_at(kGoalPz));
  // Leave the limb as animation posed it: a broken goal must not snap it to rest.
  if (!is_finite(goal_h)) return LimbRequest::InvalidGoal;
  const dmat3 to_rest = glm::transpose(parent.m);  // rotation inverse
  input = LimbSolveInput{};
  input.mode = mode;
  input.goal = glm::vec3(to_rest * (dvec3(goal_h) - parent.g));
  input.swivel_offset = goal_at(kGoalSwivel);
  const glm::vec3 pole_h(goal_at(kGoalPoleX), goal_at(kGoalPoleY), goal_at(kGoalPoleZ));
  // Zero = the rig's pole, already in the parent's rest axes; a given pole is in humanoid space.
  input.pole = (pole_h == glm::vec3(0.0f)) ? limb.pole : glm::vec3(to_rest * dvec3(pole_h));
  if (mode == IkMode::PositionOrientation) {
    const glm::quat q_h(goal_at(kGoalQw), goal_at(kGoalQx), goal_at(kGoalQy), goal_at(kGoalQz));
    // A non-finite orientation goes on as it is: the solver flags it and solves for the position only.
    input.orientation = is_finite(q_h) ? to_quat(to_rest * quat_matrix(q_h)) : q_h;
  }
  return LimbRequest::Solve;
}

bool IkJob::validate() const {
  if (!skeleton || limbs.empty() || limbs.size() > kIkLimbs) return false;
  const std::size_t joints = skeleton->joint_count();
  if (joints == 0 || joints > kMaxJointsPerRig || skeleton->parents.size() != joints ||
      skeleton->centers.size() != joints || skeleton->limits.size() != joints)
    return false;
  for (std::size_t j = 0; j < joints; ++j)
    if (skeleton->parents[j] >= static_cast<int>(j)) return false;
  auto in_skeleton = [&](std::int32_t j) { return j >= 0 && static_cast<std::size_t>(j) < joints; };
  for (const LimbChain& limb : limbs)
    if (!in_skeleton(limb.upper) || !in_skeleton(limb.middle) || !in_skeleton(limb.lower) ||
        skeleton->parents[limb.middle] != limb.upper || skeleton->parents[limb.lower] != limb.middle)
      return false;
  const std::size_t n = local_rotation.count;
  if (!local_rotation.fits(n, static_cast<std::uint32_t>(joints * 4)) || !root_translation.fits(n, 3) ||
      !ik_goal.fits(n, kIkLimbs * kIkGoalFloats) || !ik_mode.fits(n, kIkLimbs) ||
      !ik_error.fits(n, kIkLimbs * kIkResultFloats) || !ik_flags.fits(n, kIkLimbs))
    return false;
  return !local_rotation.overlaps(ik_error) && !local_rotation.overlaps(ik_flags) && !ik_error.overlaps(ik_flags) &&
         !local_rotation.overlaps(ik_goal) && !local_rotation.overlaps(ik_mode) &&
         !local_rotation.overlaps(root_translation) && !ik_error.overlaps(ik_goal) && !ik_error.overlaps(ik_mode) &&
         !ik_error.overlaps(root_translation) && !ik_flags.overlaps(ik_goal) && !ik_flags.overlaps(ik_mode) &&
         !ik_flags.overlaps(root_translation);
}

bool IkJob::run() const {
  if (!validate()) return false;
  const std::size_t count = local_rotation.count;
  if (count == 0) return true;
  // The union of the upper joints' ancestors, in index order (a parent precedes its children). Limb joints'
  // own rotations are outputs, and an ancestor shared by limbs (root, spine) is composed once per walker.
  bool needed[kMaxJointsPerRig] = {};
  for (const LimbChain& limb : limbs)
    for (std::int32_t j = skeleton->parents[limb.upper]; j >= 0; j = skeleton->parents[j]) needed[j] = true;
  std::int32_t ancestors[kMaxJointsPerRig];
  std::size_t ancestor_count = 0;
  for (std::size_t j = 0; j < skeleton->joint_count(); ++j)
    if (needed[j]) ancestors[ancestor_count++] = static_cast<std::int32_t>(j);

  // 32 walkers per task: ~0.3 us per limb solve makes a task ~40 us, long enough to hide scheduling, short
  // enough to balance a few thousand walkers over the cores (fk's 256 suits its 25x cheaper per-walker work).
  constexpr std::size_t kChunk = 32;
  if (count <= kChunk) {
    ik_range(*this, ancestors, ancestor_count, 0, count);
    return true;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      ik_range(*this, ancestors, ancestor_count, r.begin(), r.end());
                    },
                    tbb::simple_partitioner());
  return true;
}

IkJob make_ik_job(const Skeleton& skeleton, std::span<const LimbChain> limbs, SoaTable& walkers) {
  const SoaTable& read = walkers;
  return {&skeleton,
          limbs,
          f32_view(read, kWalkerIkGoal),
          i32_view(read, kWalkerIkMode),
          f32_view(read, kWalkerRootTranslation),
          f32_view(walkers, kWalkerLocalRotation),
          f32_view(walkers, kWalkerIkResult),
          u32_view(walkers, kWalkerIkFlags)};
}

}  // namespace strata
