#include "motion/cardinal_spline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>

namespace strata {
namespace {

// Sub-intervals per segment of the arc-length tables. 8 keeps the 5-point Gauss-Legendre error of |P'| below
// ~1e-5 relative even at tension 0.9, where |P'| has a near-kink at every knot.
constexpr std::size_t kSubdivisions = 8;

// 5-point Gauss-Legendre on [-1, 1]: nodes 0, +-x1, +-x2 with weights w0, w1, w2 (exact for degree 9).
constexpr double kGaussX1 = 0.5384693101056830910363144;
constexpr double kGaussX2 = 0.9061798459386639927976269;
constexpr double kGaussW0 = 0.5688888888888888888888889;
constexpr double kGaussW1 = 0.4786286704993664680412915;
constexpr double kGaussW2 = 0.2369268850561890875142640;

// One segment as a power-basis cubic P(x) = ((a x + b) x + c) x + d, the rows of M_C applied to its four control
// points. Arc length and its inversion run in double: the table accumulates over all segments, and Newton's
// stopping test compares lengths to ~1e-9 of the total, which float could not resolve on a 30 m path.
struct Cubic {
  glm::dvec3 a, b, c, d;

  glm::dvec3 point(double x) const { return ((a * x + b) * x + c) * x + d; }
  glm::dvec3 derivative(double x) const { return (3.0 * a * x + 2.0 * b) * x + c; }
  glm::dvec3 second_derivative(double x) const { return 6.0 * a * x + 2.0 * b; }
  double speed(double x) const { return glm::length(derivative(x)); }
};

Cubic make_cubic(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3, double s) {
  const glm::dvec3 q0(p0), q1(p1), q2(p2), q3(p3);
  return Cubic{-s * q0 + (2.0 - s) * q1 + (s - 2.0) * q2 + s * q3,
               2.0 * s * q0 + (s - 3.0) * q1 + (3.0 - 2.0 * s) * q2 - s * q3, s * (q2 - q0), q1};
}

// Arc length of one segment from x = lo to x = hi.
double gauss_length(const Cubic& cubic, double lo, double hi) {
  const double half = 0.5 * (hi - lo);
  const double mid = 0.5 * (hi + lo);
  const double sum = kGaussW0 * cubic.speed(mid) +
                     kGaussW1 * (cubic.speed(mid - kGaussX1 * half) + cubic.speed(mid + kGaussX1 * half)) +
                     kGaussW2 * (cubic.speed(mid - kGaussX2 * half) + cubic.speed(mid + kGaussX2 * half));
  return sum * half;
}

// The four control points of segment k. Open paths mirror the end chord into a phantom point, so the end
// tangent is s (p_1 - p_{-1}) = 2 s (p_1 - p_0): along the first chord, as in the interior.
struct Controls {
  glm::vec3 p0, p1, p2, p3;
};

Controls open_controls(const glm::vec3* points, std::size_t count, std::size_t k) {
  const glm::vec3 p1 = points[k];
  const glm::vec3 p2 = points[k + 1];
  const glm::vec3 p0 = k > 0 ? points[k - 1] : 2.0f * p1 - p2;
  const glm::vec3 p3 = k + 2 < count ? points[k + 2] : 2.0f * p2 - p1;
  return {p0, p1, p2, p3};
}

Controls closed_controls(const glm::vec3* points, std::size_t count, std::size_t k) {
  return {points[(k + count - 1) % count], points[k], points[(k + 1) % count], points[(k + 2) % count]};
}

Controls controls_of(const std::vector<glm::vec3>& points, bool closed, std::size_t k) {
  return closed ? closed_controls(points.data(), points.size(), k) : open_controls(points.data(), points.size(), k);
}

Cubic cubic_of(const Controls& c, double s) { return make_cubic(c.p0, c.p1, c.p2, c.p3, s); }

// Brings a parameter or arc length into [0, period]: clamped when open, wrapped into [0, period) when closed.
// NaN maps to 0, and so does an infinity on a closed curve (it has no position modulo the period): evaluation of
// a valid curve never returns a non-finite point, which would otherwise poison a whole pose downstream.
double normalise(double x, double period, bool wrap) {
  if (std::isnan(x)) return 0.0;
  if (!wrap) return std::clamp(x, 0.0, period);
  if (std::isinf(x)) return 0.0;
  x -= period * std::floor(x / period);
  return (x >= 0.0 && x < period) ? x : 0.0;
}

// Cumulative arc-length table: table[k * subdivisions + i] is the length up to x = i / subdivisions of segment k.
// Summed in double and stored in float; rounding each entry once keeps its error at float epsilon of the total.
template <class CubicOf>
void build_table(float* table, std::size_t segments, std::size_t subdivisions, CubicOf&& cubic_at) {
  double total = 0.0;
  table[0] = 0.0f;
  for (std::size_t k = 0; k < segments; ++k) {
    const Cubic cubic = cubic_at(k);
    for (std::size_t i = 0; i < subdivisions; ++i) {
      const double lo = static_cast<double>(i) / static_cast<double>(subdivisions);
      const double hi = static_cast<double>(i + 1) / static_cast<double>(subdivisions);
      total += gauss_length(cubic, lo, hi);
      table[k * subdivisions + i + 1] = static_cast<float>(total);
    }
  }
}

// Length from u = 0 to u (u already in [0, segments]). Integrates the partial sub-interval with Gauss-Legendre
// rather than interpolating the table linearly, so that parameter_at, which inverts this very function, agrees
// with it to the Newton tolerance instead of to the table's chord error.
template <class CubicOf>
double length_in_table(const float* table, std::size_t segments, std::size_t subdivisions, double u,
                       CubicOf&& cubic_at) {
  const std::size_t intervals = segments * subdivisions;
  if (u >= static_cast<double>(segments)) return table[intervals];
  const double scaled = u * static_cast<double>(subdivisions);
  const std::size_t j = std::min(static_cast<std::size_t>(std::max(scaled, 0.0)), intervals - 1);
  const std::size_t k = j / subdivisions;
  const double lo = static_cast<double>(j % subdivisions) / static_cast<double>(subdivisions);
  return static_cast<double>(table[j]) + gauss_length(cubic_at(k), lo, u - static_cast<double>(k));
}

struct Located {
  std::size_t segment;
  double x;  // local parameter in [0, 1]
  Cubic cubic;
};

// Inverse of length_in_table for s in [0, table[intervals]]: binary search for the sub-interval, then Newton
// steps x -= (L(x) - s) / |P'(x)| inside a bracket that shrinks with every evaluation. A step that would leave
// the bracket, including the infinite one where |P'| = 0 (knots at tension 1), becomes a bisection. Pure Newton
// was rejected for that reason; pure bisection needs ~25 evaluations of L where Newton needs 2-3.
template <class CubicOf>
Located locate_length(const float* table, std::size_t segments, std::size_t subdivisions, double s,
                      CubicOf&& cubic_at) {
  const std::size_t intervals = segments * subdivisions;
  const float* const end = table + intervals + 1;
  // First entry above s, minus one: the sub-interval [table[j], table[j + 1]] that holds s.
  // Compared in double: rounding s to float first could place it one sub-interval too far.
  const std::ptrdiff_t above =
      std::upper_bound(table, end, s, [](double value, float entry) { return value < entry; }) - table;
  const std::size_t j = std::min(static_cast<std::size_t>(std::max<std::ptrdiff_t>(above - 1, 0)), intervals - 1);
  const std::size_t k = j / subdivisions;
  const double width = 1.0 / static_cast<double>(subdivisions);
  const double start = static_cast<double>(j % subdivisions) * width;
  Located out{k, start, cubic_at(k)};

  const double base = table[j];
  const double span = static_cast<double>(table[j + 1]) - base;
  const double target = s - base;
  if (target <= 0.0 || span <= 0.0) return out;
  const double tolerance = 1e-9 * std::max(static_cast<double>(table[intervals]), 1e-6);

  double lo = start, hi = start + width;
  double x = std::min(start + width * target / span, hi);  // linear guess from the table
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double error = gauss_length(out.cubic, start, x) - target;
    if (std::abs(error) <= tolerance) break;
    (error > 0.0 ? hi : lo) = x;
    if (hi - lo <= 1e-13) break;
    double next = x - error / out.cubic.speed(x);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // also catches inf and NaN from |P'| = 0
    x = next;
  }
  out.x = x;
  return out;
}

// Unit tangent of one segment at x. Where |P'| vanishes (knots at tension 1, a cusp at tension > 1) the motion
// direction is the limit of P' / |P'|, which is +P'' just after the point and -P'' just before it; the chord is
// the last resort and is never zero because consecutive duplicate points were removed.
glm::dvec3 unit_tangent(const Cubic& cubic, double x) {
  const glm::dvec3 chord = cubic.a + cubic.b + cubic.c;  // P(1) - P(0)
  const double chord_length = glm::length(chord);
  const glm::dvec3 d = cubic.derivative(x);
  const double speed = glm::length(d);
  if (speed > 1e-7 * chord_length) return d / speed;
  const glm::dvec3 dd = x < 1.0 ? cubic.second_derivative(x) : -cubic.second_derivative(x);
  const double curvature_speed = glm::length(dd);
  if (curvature_speed > 1e-7 * chord_length) return dd / curvature_speed;
  return chord_length > 0.0 ? chord / chord_length : glm::dvec3(1.0, 0.0, 0.0);
}

bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

}  // namespace

// Hermite form: P = h00 p1 + h10 m1 + h01 p2 + h11 m2 with the Cardinal tangents m1 = s (p2 - p0) and
// m2 = s (p3 - p1). The same curve as [u^3 u^2 u 1] M_C [p0 p1 p2 p3]^T, written this way so that the end
// conditions P(0) = p1, P(1) = p2, P'(0) = m1, P'(1) = m2 can be read off.
glm::vec3 cardinal_point(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
                         float s, float u) {
  const float u2 = u * u, u3 = u2 * u;
  const float h00 = 2.0f * u3 - 3.0f * u2 + 1.0f;
  const float h10 = u3 - 2.0f * u2 + u;
  const float h01 = -2.0f * u3 + 3.0f * u2;
  const float h11 = u3 - u2;
  return h00 * p1 + h01 * p2 + (h10 * s) * (p2 - p0) + (h11 * s) * (p3 - p1);
}

glm::vec3 cardinal_derivative(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
                              float s, float u) {
  const float u2 = u * u;
  const float d00 = 6.0f * u2 - 6.0f * u;  // d01 = -d00
  const float d10 = 3.0f * u2 - 4.0f * u + 1.0f;
  const float d11 = 3.0f * u2 - 2.0f * u;
  return d00 * (p1 - p2) + (d10 * s) * (p2 - p0) + (d11 * s) * (p3 - p1);
}

// ---- CardinalSpline -----------------------------------------------------------------------------------------

CardinalSpline::CardinalSpline(std::vector<glm::vec3> points, float tension, bool closed)
    : tension_(tension), closed_(closed) {
  if (!std::isfinite(tension)) throw std::invalid_argument("CardinalSpline: tension is not finite");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) {
      throw std::invalid_argument("CardinalSpline: control point " + std::to_string(i) + " is not finite");
    }
  }
  // Exact repeats only: a zero-length segment has no direction, whereas a merely short one is still a curve.
  points.erase(std::unique(points.begin(), points.end()), points.end());
  // A closed path given with its first point repeated at the end would otherwise get a zero-length seam segment.
  if (closed) {
    while (points.size() > 1 && points.back() == points.front()) points.pop_back();
  }
  const std::size_t needed = closed ? 3 : 2;
  if (points.size() < needed) {
    throw std::invalid_argument("CardinalSpline: needs at least " + std::to_string(needed) + " distinct points" +
                                (closed ? " when closed" : "") + ", got " + std::to_string(points.size()));
  }
  points_ = std::move(points);

  const std::size_t segments = segment_count();
  const double s = 0.5 * (1.0 - static_cast<double>(tension_));
  table_.resize(segments * kSubdivisions + 1);
  build_table(table_.data(), segments, kSubdivisions,
              [&](std::size_t k) { return cubic_of(controls_of(points_, closed_, k), s); });
}

std::size_t CardinalSpline::segment_count() const {
  if (points_.empty()) return 0;
  return closed_ ? points_.size() : points_.size() - 1;
}

glm::vec3 CardinalSpline::point(float u) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return glm::vec3(0.0f);
  const double v = normalise(u, static_cast<double>(segments), closed_);
  const std::size_t k = std::min(static_cast<std::size_t>(v), segments - 1);
  const Controls c = controls_of(points_, closed_, k);
  return cardinal_point(c.p0, c.p1, c.p2, c.p3, 0.5f * (1.0f - tension_), static_cast<float>(v - k));
}

glm::vec3 CardinalSpline::derivative(float u) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return glm::vec3(0.0f);
  const double v = normalise(u, static_cast<double>(segments), closed_);
  const std::size_t k = std::min(static_cast<std::size_t>(v), segments - 1);
  const Controls c = controls_of(points_, closed_, k);
  return cardinal_derivative(c.p0, c.p1, c.p2, c.p3, 0.5f * (1.0f - tension_), static_cast<float>(v - k));
}

float CardinalSpline::length() const { return table_.empty() ? 0.0f : table_.back(); }

float CardinalSpline::length_at(float u) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return 0.0f;
  const double s = 0.5 * (1.0 - static_cast<double>(tension_));
  const double v = normalise(u, static_cast<double>(segments), closed_);
  return static_cast<float>(length_in_table(table_.data(), segments, kSubdivisions, v, [&](std::size_t k) {
    return cubic_of(controls_of(points_, closed_, k), s);
  }));
}

float CardinalSpline::parameter_at(float s_length) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return 0.0f;
  const double total = length();
  const double target = normalise(s_length, total, closed_);
  if (!closed_ && target >= total) return static_cast<float>(segments);
  const double s = 0.5 * (1.0 - static_cast<double>(tension_));
  const Located at = locate_length(table_.data(), segments, kSubdivisions, target, [&](std::size_t k) {
    return cubic_of(controls_of(points_, closed_, k), s);
  });
  return static_cast<float>(static_cast<double>(at.segment) + at.x);
}

glm::vec3 CardinalSpline::point_at_length(float s_length) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return glm::vec3(0.0f);
  const double total = length();
  const double target = normalise(s_length, total, closed_);
  if (!closed_ && target >= total) return points_.back();
  const double s = 0.5 * (1.0 - static_cast<double>(tension_));
  const Located at = locate_length(table_.data(), segments, kSubdivisions, target, [&](std::size_t k) {
    return cubic_of(controls_of(points_, closed_, k), s);
  });
  return glm::vec3(at.cubic.point(at.x));
}

glm::vec3 CardinalSpline::tangent_at_length(float s_length) const {
  const std::size_t segments = segment_count();
  if (segments == 0) return glm::vec3(1.0f, 0.0f, 0.0f);
  const double total = length();
  const double s = 0.5 * (1.0 - static_cast<double>(tension_));
  const double target = normalise(s_length, total, closed_);
  const auto cubic_at = [&](std::size_t k) { return cubic_of(controls_of(points_, closed_, k), s); };
  if (!closed_ && target >= total) return glm::vec3(unit_tangent(cubic_at(segments - 1), 1.0));
  const Located at = locate_length(table_.data(), segments, kSubdivisions, target, cubic_at);
  return glm::vec3(unit_tangent(at.cubic, at.x));
}

// ---- DistanceCurve ------------------------------------------------------------------------------------------

DistanceCurve::DistanceCurve(std::vector<float> times, std::vector<float> distances, float tension)
    : times_(std::move(times)), distances_(std::move(distances)) {
  const std::size_t n = times_.size();
  if (n != distances_.size()) throw std::invalid_argument("DistanceCurve: times and distances differ in size");
  if (n < 2) throw std::invalid_argument("DistanceCurve: needs at least 2 keys, got " + std::to_string(n));
  if (!std::isfinite(tension)) throw std::invalid_argument("DistanceCurve: tension is not finite");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(times_[i]) || !std::isfinite(distances_[i])) {
      throw std::invalid_argument("DistanceCurve: key " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(times_[i] > times_[i - 1])) {
      throw std::invalid_argument("DistanceCurve: times must increase strictly (key " + std::to_string(i) + ")");
    }
  }

  // Secants delta_k of each interval, then Cardinal slopes in distance per time. With keys at any spacing, the
  // neighbour difference over the neighbour time span is what s (p_{k+1} - p_{k-1}) becomes once the unit
  // parameter step is replaced by real seconds; the phantom end keys of the 3-D path reduce it to the end
  // secant. Rejected: the uniform-parameter tangent s (d_{k+1} - d_{k-1}) per key index, which makes the speed
  // jump at every key whose neighbouring intervals differ in length.
  std::vector<double> delta(n - 1);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    delta[k] = (static_cast<double>(distances_[k + 1]) - distances_[k]) /
               (static_cast<double>(times_[k + 1]) - times_[k]);
  }
  const double scale = 1.0 - static_cast<double>(tension);
  std::vector<double> m(n);
  m[0] = scale * delta[0];
  m[n - 1] = scale * delta[n - 2];
  for (std::size_t i = 1; i + 1 < n; ++i) {
    m[i] = scale * (static_cast<double>(distances_[i + 1]) - distances_[i - 1]) /
           (static_cast<double>(times_[i + 1]) - times_[i - 1]);
  }

  // Fritsch-Carlson limiting: a slope whose sign disagrees with an adjacent secant, or that sits at a key where
  // the secants change sign or one is flat, becomes 0; then each interval's (alpha, beta) = slopes / secant is
  // pulled into the disc of radius 3, inside the region where the Hermite cubic is monotone. Non-decreasing keys
  // thus give a non-decreasing curve (the walker never steps back) and any keys give no overshoot between keys.
  for (std::size_t i = 0; i < n; ++i) {
    const double before = i > 0 ? delta[i - 1] : delta[0];
    const double after = i + 1 < n ? delta[i] : delta[n - 2];
    if (before * after <= 0.0 || m[i] * after <= 0.0) m[i] = 0.0;
  }
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (delta[k] == 0.0) continue;  // both end slopes are already 0
    const double alpha = m[k] / delta[k], beta = m[k + 1] / delta[k];
    const double r2 = alpha * alpha + beta * beta;
    // The 0.9999 keeps the float-rounded slopes strictly inside the disc, where the cubic's derivative has no
    // root; exactly on its edge a rounding up could dip the curve by an ulp.
    if (r2 > 9.0) {
      const double tau = 0.9999 * 3.0 / std::sqrt(r2);
      m[k] = tau * alpha * delta[k];
      m[k + 1] = tau * beta * delta[k];
    }
  }
  slopes_.assign(m.begin(), m.end());
}

float DistanceCurve::start_time() const { return times_.empty() ? 0.0f : times_.front(); }
float DistanceCurve::end_time() const { return times_.empty() ? 0.0f : times_.back(); }

float DistanceCurve::distance(float t) const {
  if (times_.empty()) return 0.0f;
  if (std::isnan(t) || t <= times_.front()) return distances_.front();
  if (t >= times_.back()) return distances_.back();
  const auto above = std::upper_bound(times_.begin(), times_.end(), t);
  const std::size_t k = static_cast<std::size_t>(above - times_.begin()) - 1;
  const double h = static_cast<double>(times_[k + 1]) - times_[k];
  const double x = (static_cast<double>(t) - times_[k]) / h;
  const double x2 = x * x, x3 = x2 * x;
  const double h01 = -2.0 * x3 + 3.0 * x2;
  const double h10 = x3 - 2.0 * x2 + x;
  const double h11 = x3 - x2;
  const double d0 = distances_[k], d1 = distances_[k + 1];
  return static_cast<float>(d0 + (d1 - d0) * h01 + h * (h10 * slopes_[k] + h11 * slopes_[k + 1]));
}

float DistanceCurve::speed(float t) const {
  if (times_.empty() || std::isnan(t) || t < times_.front() || t > times_.back()) return 0.0f;
  const std::size_t last = times_.size() - 2;
  const std::size_t k = std::min(
      static_cast<std::size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1, last);
  const double h = static_cast<double>(times_[k + 1]) - times_[k];
  const double x = (static_cast<double>(t) - times_[k]) / h;
  const double x2 = x * x;
  const double d01 = -6.0 * x2 + 6.0 * x;
  const double d10 = 3.0 * x2 - 4.0 * x + 1.0;
  const double d11 = 3.0 * x2 - 2.0 * x;
  const double d0 = distances_[k], d1 = distances_[k + 1];
  return static_cast<float>((d1 - d0) * d01 / h + d10 * slopes_[k] + d11 * slopes_[k + 1]);
}

// ---- cardinal_through -----------------------------------------------------------------------------------------

glm::vec4 cardinal_through(std::span<const glm::vec4> values, float u) {
  const std::size_t n = values.size();
  if (n < 2) return n == 1 ? values[0] : glm::vec4(0.0f);
  const float x = (std::isfinite(u) ? std::clamp(u, 0.0f, 1.0f) : 0.0f) * static_cast<float>(n - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(x), n - 2);
  const float t = x - static_cast<float>(i), t2 = t * t, t3 = t2 * t;
  const glm::vec4& p0 = values[i == 0 ? 0 : i - 1];
  const glm::vec4& p1 = values[i];
  const glm::vec4& p2 = values[i + 1];
  const glm::vec4& p3 = values[std::min(i + 2, n - 1)];
  return 0.5f * (2.0f * p1 + (p2 - p0) * t + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * t2 +
                 (3.0f * p1 - p0 - 3.0f * p2 + p3) * t3);
}

}  // namespace strata
