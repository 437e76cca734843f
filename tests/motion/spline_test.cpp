// Cardinal splines, arc-length reparameterisation and distance curves (motion/cardinal_spline.h). Every expected
// value comes from an independent route: the M_C matrix form evaluated here in double, brute-force polylines,
// circle and straight-line geometry, finite differences, or the keys themselves.
#include "motion/cardinal_spline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace {

using glm::dvec3;
using glm::vec3;
using strata::CardinalSpline;
using strata::DistanceCurve;

constexpr double kPi = 3.14159265358979323846;

// A wiggly 3-D path with chords of 1-1.4 m.
std::vector<vec3> wiggly_points() {
  return {{0.0f, 0.0f, 0.0f},  {1.0f, 0.5f, 0.0f},  {2.2f, 0.3f, 0.4f}, {3.0f, 1.5f, 0.2f},
          {3.5f, 2.5f, -0.3f}, {2.8f, 3.4f, 0.0f}, {1.5f, 3.8f, 0.5f}, {0.3f, 3.0f, 0.1f}};
}

// Reference spline: P(u) = [x^3 x^2 x 1] M_C [p_{k-1} p_k p_{k+1} p_{k+2}]^T in double, phantom ends or wrapping
// written out separately from the library.
struct Reference {
  std::vector<dvec3> pts;
  double s;
  bool closed;

  Reference(const std::vector<vec3>& points, double tension, bool is_closed)
      : s((1.0 - tension) / 2.0), closed(is_closed) {
    for (const vec3& p : points) pts.emplace_back(p);
  }
  int count() const { return static_cast<int>(pts.size()); }
  int segments() const { return closed ? count() : count() - 1; }
  dvec3 control(int i) const {
    const int n = count();
    if (closed) return pts[static_cast<std::size_t>(((i % n) + n) % n)];
    if (i < 0) return 2.0 * pts[0] - pts[1];
    if (i >= n) return 2.0 * pts[static_cast<std::size_t>(n - 1)] - pts[static_cast<std::size_t>(n - 2)];
    return pts[static_cast<std::size_t>(i)];
  }
  dvec3 point(double u) const {
    const int k = std::min(static_cast<int>(std::floor(u)), segments() - 1);
    const double x = u - k;
    const double m[4][4] = {{-s, 2.0 - s, s - 2.0, s},
                            {2.0 * s, s - 3.0, 3.0 - 2.0 * s, -s},
                            {-s, 0.0, s, 0.0},
                            {0.0, 1.0, 0.0, 0.0}};
    const double powers[4] = {x * x * x, x * x, x, 1.0};
    dvec3 out(0.0);
    for (int row = 0; row < 4; ++row) {
      for (int col = 0; col < 4; ++col) out += powers[row] * m[row][col] * control(k - 1 + col);
    }
    return out;
  }
  // Brute force: a polyline through `samples` equally spaced parameter values.
  double polyline_length(int samples) const {
    double total = 0.0;
    dvec3 previous = point(0.0);
    for (int i = 1; i <= samples; ++i) {
      const dvec3 p = point(static_cast<double>(segments()) * i / samples);
      total += glm::length(p - previous);
      previous = p;
    }
    return total;
  }
};

double distance(const vec3& a, const vec3& b) { return glm::length(dvec3(a) - dvec3(b)); }

// ---- Segment building blocks --------------------------------------------------------------------------------

TEST(CardinalSegment, EndConditionsAreTheCardinalOnes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-3.0f, 3.0f);
  const auto random_point = [&] { return vec3(coord(rng), coord(rng), coord(rng)); };
  for (int trial = 0; trial < 50; ++trial) {
    const vec3 p0 = random_point(), p1 = random_point(), p2 = random_point(), p3 = random_point();
    const float s = std::uniform_real_distribution<float>(-0.5f, 1.0f)(rng);
    EXPECT_LT(distance(strata::cardinal_point(p0, p1, p2, p3, s, 0.0f), p1), 1e-5);
    EXPECT_LT(distance(strata::cardinal_point(p0, p1, p2, p3, s, 1.0f), p2), 1e-5);
    EXPECT_LT(distance(strata::cardinal_derivative(p0, p1, p2, p3, s, 0.0f), s * (p2 - p0)), 1e-5);
    EXPECT_LT(distance(strata::cardinal_derivative(p0, p1, p2, p3, s, 1.0f), s * (p3 - p1)), 1e-5);
  }
}

TEST(CardinalSegment, MatchesMatrixFormForAnyTension) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> coord(-3.0f, 3.0f), unit(0.0f, 1.0f);
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<vec3> pts = {{coord(rng), coord(rng), coord(rng)}, {coord(rng), coord(rng), coord(rng)},
                                   {coord(rng), coord(rng), coord(rng)}, {coord(rng), coord(rng), coord(rng)}};
    const float tension = std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng);
    const float s = 0.5f * (1.0f - tension);
    const float u = unit(rng);
    // The open reference over 4 points has 3 segments; segment 1 uses exactly pts[0..3] as its neighbours.
    const Reference ref(pts, tension, false);
    const vec3 got = strata::cardinal_point(pts[0], pts[1], pts[2], pts[3], s, u);
    EXPECT_LT(glm::length(dvec3(got) - ref.point(1.0 + u)), 2e-5) << "u=" << u << " tension=" << tension;
  }
}

TEST(CardinalSegment, TensionZeroIsCatmullRom) {
  // Catmull-Rom in its textbook matrix form 0.5 [[-1 3 -3 1] [2 -5 4 -1] [-1 0 1 0] [0 2 0 0]].
  const vec3 p0(0.0f, 0.0f, 0.0f), p1(1.0f, 2.0f, 0.0f), p2(3.0f, 2.5f, 1.0f), p3(4.0f, 0.5f, 2.0f);
  for (int i = 0; i <= 20; ++i) {
    const double u = i / 20.0;
    const dvec3 q0(p0), q1(p1), q2(p2), q3(p3);
    const dvec3 expected =
        0.5 * (u * u * u * (-q0 + 3.0 * q1 - 3.0 * q2 + q3) + u * u * (2.0 * q0 - 5.0 * q1 + 4.0 * q2 - q3) +
               u * (-q0 + q2) + 2.0 * q1);
    const vec3 got = strata::cardinal_point(p0, p1, p2, p3, 0.5f, static_cast<float>(u));
    EXPECT_LT(glm::length(dvec3(got) - expected), 1e-5) << "u=" << u;
  }
}

TEST(CardinalSegment, DerivativeMatchesFiniteDifference) {
  const vec3 p0(0.0f, 0.0f, 0.0f), p1(1.0f, 2.0f, 0.0f), p2(3.0f, 2.5f, 1.0f), p3(4.0f, 0.5f, 2.0f);
  const float h = 1e-3f;
  for (float s : {0.5f, 0.05f, 0.8f}) {
    for (int i = 1; i < 20; ++i) {
      const float u = i / 20.0f;
      const vec3 numeric = (strata::cardinal_point(p0, p1, p2, p3, s, u + h) -
                            strata::cardinal_point(p0, p1, p2, p3, s, u - h)) /
                           (2.0f * h);
      EXPECT_LT(distance(strata::cardinal_derivative(p0, p1, p2, p3, s, u), numeric), 2e-3);
    }
  }
}

// ---- CardinalSpline: interpolation and continuity -----------------------------------------------------------

TEST(CardinalSpline, PassesThroughEveryControlPoint) {
  const std::vector<vec3> pts = wiggly_points();
  for (bool closed : {false, true}) {
    for (float tension : {0.0f, 0.5f, 0.9f, -0.5f}) {
      const CardinalSpline spline(pts, tension, closed);
      ASSERT_EQ(spline.segment_count(), closed ? pts.size() : pts.size() - 1);
      for (std::size_t k = 0; k < pts.size(); ++k) {
        EXPECT_LT(distance(spline.point(static_cast<float>(k)), pts[k]), 1e-5)
            << "k=" << k << " closed=" << closed << " tension=" << tension;
      }
    }
  }
}

TEST(CardinalSpline, KnotTangentIsSTimesNeighbourDifference) {
  const std::vector<vec3> pts = wiggly_points();
  const std::size_t n = pts.size();
  for (float tension : {0.0f, 0.3f, -0.4f}) {
    const float s = 0.5f * (1.0f - tension);
    const CardinalSpline open(pts, tension, false);
    for (std::size_t k = 1; k + 1 < n; ++k) {
      EXPECT_LT(distance(open.derivative(static_cast<float>(k)), s * (pts[k + 1] - pts[k - 1])), 1e-5);
    }
    // Phantom ends p_{-1} = 2 p_0 - p_1 and p_n = 2 p_{n-1} - p_{n-2}.
    EXPECT_LT(distance(open.derivative(0.0f), 2.0f * s * (pts[1] - pts[0])), 1e-5);
    EXPECT_LT(distance(open.derivative(static_cast<float>(n - 1)), 2.0f * s * (pts[n - 1] - pts[n - 2])), 1e-5);

    const CardinalSpline closed(pts, tension, true);
    for (std::size_t k = 0; k < n; ++k) {
      const vec3 expected = s * (pts[(k + 1) % n] - pts[(k + n - 1) % n]);
      EXPECT_LT(distance(closed.derivative(static_cast<float>(k)), expected), 1e-5) << "k=" << k;
    }
  }
}

TEST(CardinalSpline, TensionZeroMatchesReferenceEverywhere) {
  const std::vector<vec3> pts = wiggly_points();
  for (bool closed : {false, true}) {
    const CardinalSpline spline(pts, 0.0f, closed);
    const Reference ref(pts, 0.0, closed);
    for (int i = 0; i <= 700; ++i) {
      const double u = ref.segments() * i / 700.0;
      EXPECT_LT(glm::length(dvec3(spline.point(static_cast<float>(u))) - ref.point(std::min(
                                                                             u, ref.segments() - 1e-9))),
                1e-5)
          << "u=" << u << " closed=" << closed;
    }
  }
}

TEST(CardinalSpline, C1AcrossSegments) {
  const std::vector<vec3> pts = wiggly_points();
  for (float tension : {0.0f, 0.5f, -0.5f}) {
    const CardinalSpline spline(pts, tension, false);
    for (std::size_t k = 1; k + 1 < pts.size(); ++k) {
      const float u = static_cast<float>(k);
      // Analytic: the last derivative of segment k-1 against the first of segment k.
      const vec3 left = spline.derivative(std::nextafter(u, 0.0f));
      const vec3 right = spline.derivative(u);
      EXPECT_LT(distance(left, right), 1e-4 * glm::length(right)) << "k=" << k;
      // Numerical: one-sided difference quotients of the positions agree to O(h) (a kink would differ by O(1)).
      const float h = 2e-3f;
      const vec3 back = (spline.point(u) - spline.point(u - h)) / h;
      const vec3 ahead = (spline.point(u + h) - spline.point(u)) / h;
      EXPECT_LT(distance(back, ahead), 0.02 * glm::length(right)) << "k=" << k << " tension=" << tension;
      EXPECT_LT(distance(0.5f * (back + ahead), right), 0.01 * glm::length(right));
    }
  }
}

// ---- Arc length ---------------------------------------------------------------------------------------------

TEST(CardinalSpline, CircleLengthIsCircumference) {
  const double radius = 2.0;
  for (int count : {32, 128}) {
    std::vector<vec3> pts;
    for (int i = 0; i < count; ++i) {
      const double a = 2.0 * kPi * i / count;
      pts.emplace_back(static_cast<float>(radius * std::cos(a)), 0.5f, static_cast<float>(radius * std::sin(a)));
    }
    const CardinalSpline spline(pts, 0.0f, true);
    EXPECT_NEAR(spline.length(), 2.0 * kPi * radius, 0.005 * 2.0 * kPi * radius) << count << " points";
    // The curve stays on the circle between the knots too.
    for (int i = 0; i < 1000; ++i) {
      const vec3 p = spline.point_at_length(spline.length() * i / 1000.0f);
      EXPECT_NEAR(std::hypot(p.x, p.z), radius, 0.005 * radius);
      EXPECT_NEAR(p.y, 0.5f, 1e-5);
    }
  }
}

TEST(CardinalSpline, CollinearPointsGiveThePolylineLength) {
  // Gaps with neighbour ratios below 2, so the Catmull-Rom curve moves monotonically along the line.
  const vec3 dir = glm::normalize(vec3(1.0f, 2.0f, 2.0f));
  const std::vector<float> gaps = {1.0f, 1.5f, 2.0f, 1.2f, 0.8f, 1.0f};
  std::vector<vec3> pts = {vec3(0.5f, -1.0f, 0.25f)};
  double polyline = 0.0;
  for (float gap : gaps) {
    pts.push_back(pts.back() + gap * dir);
    polyline += distance(pts[pts.size() - 1], pts[pts.size() - 2]);
  }
  const CardinalSpline spline(pts, 0.0f, false);
  EXPECT_NEAR(spline.length(), polyline, 1e-5 * polyline);
  // Arc length along a line is distance from the start point.
  for (int i = 0; i <= 100; ++i) {
    const float s = static_cast<float>(polyline * i / 100.0);
    EXPECT_NEAR(distance(spline.point_at_length(s), pts[0]), s, 2e-5);
  }
}

TEST(CardinalSpline, TensionOneIsThePolyline) {
  // s = 0: each segment is p_k + (p_{k+1} - p_k) h01(x), the straight chord with zero speed at both knots.
  const std::vector<vec3> pts = wiggly_points();
  const CardinalSpline spline(pts, 1.0f, false);
  double polyline = 0.0;
  for (std::size_t k = 1; k < pts.size(); ++k) polyline += distance(pts[k], pts[k - 1]);
  EXPECT_NEAR(spline.length(), polyline, 1e-5 * polyline);
  double walked = 0.0;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const double chord = distance(pts[k + 1], pts[k]);
    const vec3 along = glm::normalize(pts[k + 1] - pts[k]);
    for (double f : {0.1, 0.5, 0.9}) {
      const float s = static_cast<float>(walked + f * chord);
      EXPECT_LT(distance(spline.point_at_length(s), pts[k] + static_cast<float>(f * chord) * along), 2e-5);
      EXPECT_LT(distance(spline.tangent_at_length(s), along), 1e-4);
    }
    walked += chord;
  }
}

TEST(CardinalSpline, LengthMatchesFineBruteForcePolyline) {
  const std::vector<vec3> pts = wiggly_points();
  for (bool closed : {false, true}) {
    for (float tension : {0.0f, 0.5f, 0.9f, -0.5f}) {
      const CardinalSpline spline(pts, tension, closed);
      const double brute = Reference(pts, tension, closed).polyline_length(100000);
      EXPECT_NEAR(spline.length(), brute, 1e-4 * brute) << "closed=" << closed << " tension=" << tension;
      // And per segment: length_at at each knot against the same brute force on the prefix.
      const Reference ref(pts, tension, closed);
      double prefix = 0.0;
      dvec3 previous = ref.point(0.0);
      const int per_segment = 10000;
      for (int k = 1; k <= ref.segments(); ++k) {
        for (int i = 1; i <= per_segment; ++i) {
          const dvec3 p = ref.point(std::min(k - 1 + static_cast<double>(i) / per_segment, ref.segments() - 1e-12));
          prefix += glm::length(p - previous);
          previous = p;
        }
        if (closed && k == ref.segments()) break;  // length_at wraps u = segments back to 0
        EXPECT_NEAR(spline.length_at(static_cast<float>(k)), prefix, 1e-4 * brute) << "knot " << k;
      }
    }
  }
}

TEST(CardinalSpline, ParameterAtInvertsLengthAt) {
  const std::vector<vec3> pts = wiggly_points();
  std::mt19937 rng(7);
  for (bool closed : {false, true}) {
    for (float tension : {0.0f, 0.5f, 0.9f, 1.0f, -0.5f}) {
      const CardinalSpline spline(pts, tension, closed);
      const float total = spline.length();
      std::uniform_real_distribution<float> pick(0.0f, total);
      for (int i = 0; i < 2000; ++i) {
        const float s = pick(rng);
        const float u = spline.parameter_at(s);
        ASSERT_TRUE(std::isfinite(u));
        ASSERT_GE(u, 0.0f);
        ASSERT_LE(u, static_cast<float>(spline.segment_count()));
        EXPECT_NEAR(spline.length_at(u), s, 1e-5) << "closed=" << closed << " tension=" << tension;
      }
      // The knots themselves, where tension 1 has zero speed.
      for (std::size_t k = 0; k < spline.segment_count(); ++k) {
        const float s = spline.length_at(static_cast<float>(k));
        EXPECT_NEAR(spline.parameter_at(s), static_cast<float>(k), 1e-3) << "tension=" << tension;
      }
    }
  }
}

TEST(CardinalSpline, ArcLengthParameterisationHasUnitSpeed) {
  // Independent of length_at: equal steps in s must give equal chords between consecutive points.
  const std::vector<vec3> pts = wiggly_points();
  for (float tension : {0.0f, 0.9f, -0.5f}) {
    const CardinalSpline spline(pts, tension, false);
    const int steps = 2000;
    const double step = spline.length() / steps;
    double walked = 0.0;
    vec3 previous = spline.point_at_length(0.0f);
    EXPECT_LT(distance(previous, pts.front()), 1e-6);
    for (int i = 1; i <= steps; ++i) {
      const vec3 p = spline.point_at_length(static_cast<float>(step * i));
      const double chord = distance(p, previous);
      // A chord never exceeds its arc, so a step that runs fast shows here at any tension. At tension 0.9 the
      // knots are near-corners where even an exact step's chord is shorter than the arc, so only there is the
      // lower bound left to the total below.
      EXPECT_LE(chord, step * (1.0 + 2e-3)) << "i=" << i << " tension=" << tension;
      if (tension < 0.5f) {
        EXPECT_GE(chord, step * (1.0 - 2e-3)) << "i=" << i << " tension=" << tension;
      }
      walked += chord;
      previous = p;
    }
    EXPECT_LT(distance(previous, pts.back()), 1e-5);
    EXPECT_NEAR(walked, spline.length(), 1e-4 * spline.length());
  }
}

TEST(CardinalSpline, TangentIsUnitAndFollowsTheCurve) {
  const std::vector<vec3> pts = wiggly_points();
  for (float tension : {0.0f, 0.9f}) {
    const CardinalSpline spline(pts, tension, false);
    // Small h: near the tension-0.9 knots the curvature changes fast and a wider central difference turns.
    const float h = 2e-4f;
    for (int i = 1; i < 500; ++i) {
      const float s = spline.length() * i / 500.0f;
      const vec3 t = spline.tangent_at_length(s);
      EXPECT_NEAR(glm::length(t), 1.0f, 1e-5);
      const vec3 numeric = glm::normalize(spline.point_at_length(s + h) - spline.point_at_length(s - h));
      EXPECT_LT(distance(t, numeric), 5e-3) << "s=" << s << " tension=" << tension;
    }
  }
}

TEST(CardinalSpline, TangentIsFiniteAtZeroSpeedKnots) {
  // Tension 1 stops the curve dead at every knot: P' = 0 there, and the tangent must come from elsewhere.
  const std::vector<vec3> pts = wiggly_points();
  for (bool closed : {false, true}) {
    const CardinalSpline spline(pts, 1.0f, closed);
    ASSERT_LT(glm::length(spline.derivative(1.0f)), 1e-6f);
    for (std::size_t k = 0; k <= spline.segment_count(); ++k) {
      const float s = k == spline.segment_count() ? spline.length() : spline.length_at(static_cast<float>(k));
      const vec3 t = spline.tangent_at_length(s);
      ASSERT_TRUE(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z)) << "knot " << k;
      EXPECT_NEAR(glm::length(t), 1.0f, 1e-5);
      // The tension-1 curve is the polyline, so the tangent at a knot is one of the two adjacent chords.
      const std::size_t n = pts.size();
      const std::size_t here = k % n;
      const bool has_next = closed || here + 1 < n;
      const bool has_prev = closed || here > 0;
      double best = 1.0;
      if (has_next) best = std::min(best, distance(t, glm::normalize(pts[(here + 1) % n] - pts[here])));
      if (has_prev) best = std::min(best, distance(t, glm::normalize(pts[here] - pts[(here + n - 1) % n])));
      EXPECT_LT(best, 1e-4) << "knot " << k << " closed=" << closed;
    }
  }
}

// ---- Closed and open ends -----------------------------------------------------------------------------------

TEST(CardinalSpline, ClosedWrapsAndIsContinuousAtTheSeam) {
  const std::vector<vec3> pts = wiggly_points();
  for (float tension : {0.0f, 0.6f}) {
    const CardinalSpline spline(pts, tension, true);
    const float total = spline.length();
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> pick(0.0f, total);
    for (int i = 0; i < 200; ++i) {
      const float s = pick(rng);
      const vec3 p = spline.point_at_length(s);
      EXPECT_LT(distance(spline.point_at_length(s + total), p), 1e-4);
      EXPECT_LT(distance(spline.point_at_length(s - total), p), 1e-4);
      EXPECT_LT(distance(spline.point_at_length(s + 3.0f * total), p), 2e-4);
    }
    const float segs = static_cast<float>(spline.segment_count());
    EXPECT_LT(distance(spline.point(segs), pts[0]), 1e-6);
    EXPECT_LT(distance(spline.point(segs + 1.0f), pts[1]), 1e-5);
    EXPECT_LT(distance(spline.point(-1.0f), pts.back()), 1e-5);
    // Across the seam: position and derivative just before u = segments equal those at u = 0.
    const float before = std::nextafter(segs, 0.0f);
    EXPECT_LT(distance(spline.point(before), spline.point(0.0f)), 1e-5);
    EXPECT_LT(distance(spline.derivative(before), spline.derivative(0.0f)), 1e-4);
    const float eps = 1e-3f;
    EXPECT_NEAR(distance(spline.point_at_length(total - eps), spline.point_at_length(eps)), 2.0 * eps, 1e-4);
    EXPECT_LT(distance(spline.tangent_at_length(total - 1e-5f), spline.tangent_at_length(0.0f)), 1e-3);
    EXPECT_NEAR(spline.parameter_at(total + 0.25f * total), spline.parameter_at(0.25f * total), 1e-4);
  }
}

TEST(CardinalSpline, OpenClampsOutsideTheRange) {
  const std::vector<vec3> pts = wiggly_points();
  const CardinalSpline spline(pts, 0.2f, false);
  const float total = spline.length();
  EXPECT_LT(distance(spline.point_at_length(-3.0f), pts.front()), 1e-6);
  EXPECT_LT(distance(spline.point_at_length(total + 5.0f), pts.back()), 1e-6);
  EXPECT_FLOAT_EQ(spline.parameter_at(total + 1.0f), static_cast<float>(spline.segment_count()));
  EXPECT_FLOAT_EQ(spline.parameter_at(-1.0f), 0.0f);
  EXPECT_FLOAT_EQ(spline.length_at(100.0f), total);
  EXPECT_FLOAT_EQ(spline.length_at(-2.0f), 0.0f);
  EXPECT_LT(distance(spline.point(-2.0f), pts.front()), 1e-6);
  EXPECT_LT(distance(spline.point(50.0f), pts.back()), 1e-6);
}

// ---- Degenerate input ---------------------------------------------------------------------------------------

TEST(CardinalSpline, ConsecutiveDuplicatesAreRemoved) {
  const vec3 a(0.0f, 0.0f, 0.0f), b(1.0f, 0.0f, 0.0f), c(1.5f, 1.0f, 0.0f), d(2.0f, 1.0f, 1.0f);
  const CardinalSpline with_repeats({a, a, b, c, c, c, d}, 0.0f, false);
  const CardinalSpline clean({a, b, c, d}, 0.0f, false);
  ASSERT_EQ(with_repeats.points().size(), 4u);
  EXPECT_EQ(with_repeats.segment_count(), 3u);
  EXPECT_FLOAT_EQ(with_repeats.length(), clean.length());
  for (int i = 0; i <= 50; ++i) {
    const float s = clean.length() * i / 50.0f;
    EXPECT_EQ(with_repeats.point_at_length(s), clean.point_at_length(s));
  }
  // Closed: a first point repeated at the end would be a zero-length seam segment.
  const CardinalSpline loop({a, b, c, a}, 0.0f, true);
  EXPECT_EQ(loop.points().size(), 3u);
  EXPECT_EQ(loop.segment_count(), 3u);
  // Non-consecutive repeats are a legitimate path that revisits a point.
  const CardinalSpline revisit({a, b, a, c}, 0.0f, false);
  EXPECT_EQ(revisit.points().size(), 4u);
}

TEST(CardinalSpline, TwoPointOpenPathIsAStraightLine) {
  const vec3 a(1.0f, 2.0f, 3.0f), b(4.0f, 6.0f, 3.0f);  // 5 m apart
  for (float tension : {0.0f, 0.7f, -0.5f}) {
    const CardinalSpline spline({a, b}, tension, false);
    EXPECT_EQ(spline.segment_count(), 1u);
    EXPECT_NEAR(spline.length(), 5.0, 1e-5);
    for (int i = 0; i <= 20; ++i) {
      const float s = 5.0f * i / 20.0f;
      EXPECT_LT(distance(spline.point_at_length(s), a + s * glm::normalize(b - a)), 1e-5) << "tension=" << tension;
      EXPECT_LT(distance(spline.tangent_at_length(s), glm::normalize(b - a)), 1e-5);
    }
  }
}

TEST(CardinalSpline, RejectsTooFewOrNonFinitePoints) {
  const vec3 a(0.0f), b(1.0f, 0.0f, 0.0f), c(0.0f, 1.0f, 0.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_THROW(CardinalSpline({}, 0.0f, false), std::invalid_argument);
  EXPECT_THROW(CardinalSpline({a}, 0.0f, false), std::invalid_argument);
  EXPECT_THROW(CardinalSpline({a, a, a}, 0.0f, false), std::invalid_argument);  // one distinct point
  EXPECT_THROW(CardinalSpline({a, b}, 0.0f, true), std::invalid_argument);
  EXPECT_THROW(CardinalSpline({a, b, a}, 0.0f, true), std::invalid_argument);  // two distinct once closed
  EXPECT_THROW(CardinalSpline({a, vec3(nan, 0.0f, 0.0f), c}, 0.0f, false), std::invalid_argument);
  EXPECT_THROW(CardinalSpline({a, b, vec3(0.0f, inf, 0.0f)}, 0.0f, false), std::invalid_argument);
  EXPECT_THROW(CardinalSpline({a, b, c}, nan, false), std::invalid_argument);
  EXPECT_NO_THROW(CardinalSpline({a, b}, 0.0f, false));
  EXPECT_NO_THROW(CardinalSpline({a, b, c}, 0.0f, true));
}

TEST(CardinalSpline, NonFiniteQueriesGiveFiniteResults) {
  const std::vector<vec3> pts = wiggly_points();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const auto finite = [](const vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); };
  for (bool closed : {false, true}) {
    const CardinalSpline spline(pts, 0.0f, closed);
    for (float q : {nan, inf, -inf}) {
      EXPECT_TRUE(finite(spline.point_at_length(q)));
      EXPECT_TRUE(finite(spline.tangent_at_length(q)));
      EXPECT_TRUE(finite(spline.point(q)));
      EXPECT_TRUE(std::isfinite(spline.parameter_at(q)));
      EXPECT_TRUE(std::isfinite(spline.length_at(q)));
    }
    // NaN is treated as the start.
    EXPECT_EQ(spline.point_at_length(nan), spline.point_at_length(0.0f));
  }
  const CardinalSpline open(pts, 0.0f, false);
  EXPECT_LT(distance(open.point_at_length(inf), pts.back()), 1e-6);
  EXPECT_LT(distance(open.point_at_length(-inf), pts.front()), 1e-6);
}

TEST(CardinalSpline, DefaultConstructedIsEmptyAndSafe) {
  const CardinalSpline empty;
  EXPECT_EQ(empty.segment_count(), 0u);
  EXPECT_EQ(empty.length(), 0.0f);
  EXPECT_EQ(empty.length_at(1.0f), 0.0f);
  EXPECT_EQ(empty.parameter_at(1.0f), 0.0f);
  EXPECT_EQ(empty.point_at_length(1.0f), vec3(0.0f));
  EXPECT_EQ(empty.point(0.5f), vec3(0.0f));
}

// ---- DistanceCurve (the double interpolant's timing) --------------------------------------------------------

// Ease in, cruise, ease out over non-uniform key times.
const std::vector<float> kEaseTimes = {0.0f, 0.5f, 1.7f, 2.0f, 3.1f};
const std::vector<float> kEaseDistances = {0.0f, 0.2f, 2.5f, 3.1f, 3.4f};

TEST(DistanceCurve, HitsTheKeys) {
  for (float tension : {0.0f, 0.5f}) {
    const DistanceCurve curve(kEaseTimes, kEaseDistances, tension);
    EXPECT_FLOAT_EQ(curve.start_time(), 0.0f);
    EXPECT_FLOAT_EQ(curve.end_time(), 3.1f);
    for (std::size_t i = 0; i < kEaseTimes.size(); ++i) {
      EXPECT_NEAR(curve.distance(kEaseTimes[i]), kEaseDistances[i], 1e-6) << "key " << i;
    }
  }
}

TEST(DistanceCurve, MonotoneNonNegativeSpeedAndClamped) {
  const DistanceCurve curve(kEaseTimes, kEaseDistances);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> pick(-1.0f, 4.0f);
  std::vector<float> ts(10000);
  for (float& t : ts) t = pick(rng);
  std::sort(ts.begin(), ts.end());
  float previous = -1.0f;
  for (float t : ts) {
    const float d = curve.distance(t);
    EXPECT_GE(d, previous) << "t=" << t;
    EXPECT_GE(curve.speed(t), 0.0f) << "t=" << t;
    previous = d;
  }
  EXPECT_EQ(curve.distance(-0.5f), 0.0f);
  EXPECT_EQ(curve.distance(10.0f), 3.4f);
  EXPECT_EQ(curve.speed(-0.5f), 0.0f);
  EXPECT_EQ(curve.speed(10.0f), 0.0f);
  EXPECT_EQ(curve.distance(std::numeric_limits<float>::quiet_NaN()), 0.0f);
}

TEST(DistanceCurve, SpeedIsTheDerivative) {
  const DistanceCurve curve(kEaseTimes, kEaseDistances);
  const float h = 1e-3f;
  for (int i = 1; i < 300; ++i) {
    const float t = 3.1f * i / 300.0f;
    const double numeric = (static_cast<double>(curve.distance(t + h)) - curve.distance(t - h)) / (2.0 * h);
    EXPECT_NEAR(curve.speed(t), numeric, 2e-3) << "t=" << t;
  }
}

TEST(DistanceCurve, UnlimitedSlopesAreCardinalInTime) {
  // Keys gentle enough that no slope limiting applies: the curve is the Hermite cubic with slopes
  // (1 - tension) (d_{i+1} - d_{i-1}) / (t_{i+1} - t_{i-1}) inside and (1 - tension) times the end secants.
  const std::vector<double> t = {0.0, 1.0, 2.5, 3.0}, d = {0.0, 1.0, 2.8, 3.5};
  for (double tension : {0.0, 0.3}) {
    const DistanceCurve curve(std::vector<float>(t.begin(), t.end()), std::vector<float>(d.begin(), d.end()),
                              static_cast<float>(tension));
    const double c = 1.0 - tension;
    const std::vector<double> m = {c * (d[1] - d[0]) / (t[1] - t[0]), c * (d[2] - d[0]) / (t[2] - t[0]),
                                   c * (d[3] - d[1]) / (t[3] - t[1]), c * (d[3] - d[2]) / (t[3] - t[2])};
    for (int i = 0; i <= 300; ++i) {
      const double time = 3.0 * i / 300.0;
      const std::size_t k = std::min<std::size_t>(time < 1.0 ? 0 : time < 2.5 ? 1 : 2, 2);
      const double h = t[k + 1] - t[k], x = (time - t[k]) / h;
      const double expected = (2 * x * x * x - 3 * x * x + 1) * d[k] + (x * x * x - 2 * x * x + x) * h * m[k] +
                              (-2 * x * x * x + 3 * x * x) * d[k + 1] + (x * x * x - x * x) * h * m[k + 1];
      EXPECT_NEAR(curve.distance(static_cast<float>(time)), expected, 1e-5) << "t=" << time;
    }
  }
}

TEST(DistanceCurve, StopAndGoNeverMovesBackward) {
  // A plain Cardinal curve through a stop (0, 0) (1, 0) then a start to 5 has slope 2.5 at t = 1 and dips below
  // 0 on [0, 1]; a steep step after a slow one overshoots the same way.
  const DistanceCurve stop_go({0.0f, 1.0f, 2.0f, 3.0f}, {0.0f, 0.0f, 5.0f, 5.0f});
  const DistanceCurve steep({0.0f, 1.0f, 2.0f, 3.0f}, {0.0f, 0.1f, 10.0f, 10.1f});
  for (const DistanceCurve* curve : {&stop_go, &steep}) {
    float previous = curve->distance(0.0f);
    for (int i = 1; i <= 3000; ++i) {
      const float t = 3.0f * i / 3000.0f;
      const float d = curve->distance(t);
      EXPECT_GE(d, previous) << "t=" << t;
      EXPECT_GE(curve->speed(t), 0.0f) << "t=" << t;
      previous = d;
    }
  }
  // Standing still means standing still: flat between equal keys.
  for (int i = 0; i <= 100; ++i) {
    EXPECT_EQ(stop_go.distance(i / 100.0f), 0.0f);
    EXPECT_EQ(stop_go.distance(2.0f + i / 100.0f), 5.0f);
  }
  // The steep interval still reaches its keys.
  EXPECT_NEAR(steep.distance(1.0f), 0.1f, 1e-6);
  EXPECT_NEAR(steep.distance(2.0f), 10.0f, 1e-5);
}

TEST(DistanceCurve, NonMonotoneKeysDoNotOvershoot) {
  const std::vector<float> t = {0.0f, 1.0f, 1.5f, 3.0f}, d = {0.0f, 2.0f, 1.0f, 3.0f};
  const DistanceCurve curve(t, d);
  for (std::size_t k = 0; k + 1 < t.size(); ++k) {
    const float lo = std::min(d[k], d[k + 1]), hi = std::max(d[k], d[k + 1]);
    for (int i = 0; i <= 100; ++i) {
      const float v = curve.distance(t[k] + (t[k + 1] - t[k]) * i / 100.0f);
      EXPECT_GE(v, lo - 1e-6f);
      EXPECT_LE(v, hi + 1e-6f);
    }
  }
}

TEST(DistanceCurve, RejectsBadKeys) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(DistanceCurve({0.0f}, {0.0f}), std::invalid_argument);
  EXPECT_THROW(DistanceCurve({0.0f, 1.0f}, {0.0f}), std::invalid_argument);
  EXPECT_THROW(DistanceCurve({0.0f, 0.0f}, {0.0f, 1.0f}), std::invalid_argument);
  EXPECT_THROW(DistanceCurve({0.0f, 2.0f, 1.0f}, {0.0f, 1.0f, 2.0f}), std::invalid_argument);
  EXPECT_THROW(DistanceCurve({0.0f, 1.0f}, {0.0f, nan}), std::invalid_argument);
  EXPECT_THROW(DistanceCurve({0.0f, std::numeric_limits<float>::infinity()}, {0.0f, 1.0f}), std::invalid_argument);
  EXPECT_NO_THROW(DistanceCurve({0.0f, 1.0f}, {0.0f, 1.0f}));
}

TEST(DoubleInterpolant, WalkerTravelsTheScheduledDistance) {
  // Q(S(t)): the distance actually walked along the path (a fine polyline of the positions over time) is S(t),
  // and the walker's speed is S'(t), even though Q's own parameter speed varies along the path.
  const CardinalSpline path(wiggly_points(), 0.3f, false);
  const float total = path.length();
  const DistanceCurve schedule({0.0f, 1.0f, 3.0f, 4.0f}, {0.0f, 0.1f * total, 0.9f * total, total});
  const double dt = 1e-3;
  double walked = 0.0;
  vec3 previous = path.point_at_length(schedule.distance(0.0f));
  for (int i = 1; i <= 4000; ++i) {
    const float t = static_cast<float>(i * dt);
    const vec3 p = path.point_at_length(schedule.distance(t));
    const double step = distance(p, previous);
    walked += step;
    previous = p;
    EXPECT_NEAR(walked, schedule.distance(t), 1e-4 * total) << "t=" << t;
    if (i % 50 == 0) {
      const float mid = static_cast<float>((i - 0.5) * dt);
      EXPECT_NEAR(step / dt, schedule.speed(mid), 2e-3 * total) << "t=" << t;
    }
  }
  EXPECT_LT(distance(previous, wiggly_points().back()), 1e-5);
  EXPECT_NEAR(walked, total, 1e-4 * total);
}

// ---- cardinal_through -----------------------------------------------------------------------------------------

TEST(CardinalThrough, PassesThroughEveryValueAtItsTimeAndClamps) {
  const std::vector<glm::vec4> v = {{0, 0, 0, 0}, {1, 2, 0, 0.5f}, {2, 1, 1, -0.2f}, {4, 0, 1, 0}, {5, 3, 2, 1}};
  for (std::size_t k = 0; k < v.size(); ++k) {
    const glm::vec4 p = strata::cardinal_through(v, static_cast<float>(k) / 4.0f);
    EXPECT_LT(glm::length(p - v[k]), 1e-6f) << "value " << k;
  }
  EXPECT_EQ(strata::cardinal_through(v, -1.0f), v.front());
  EXPECT_EQ(strata::cardinal_through(v, 2.0f), v.back());
  EXPECT_EQ(strata::cardinal_through(v, std::numeric_limits<float>::quiet_NaN()), v.front());
  EXPECT_EQ(strata::cardinal_through(std::span<const glm::vec4>(v.data(), 1), 0.5f), v.front());
}

TEST(CardinalThrough, ReproducesEvenlySpacedLinearValuesAwayFromTheEnds) {
  // Catmull-Rom reproduces a straight line at even speed wherever both neighbours are real knots.
  std::vector<glm::vec4> v;
  for (int k = 0; k < 6; ++k) v.emplace_back(2.0f * k, -1.0f * k, 0.5f * k, 3.0f);
  for (int i = 0; i <= 100; ++i) {
    const float u = 0.2f + 0.6f * static_cast<float>(i) / 100.0f;  // segments 1 to 3 of 5
    const glm::vec4 expected(10.0f * u, -5.0f * u, 2.5f * u, 3.0f);
    EXPECT_LT(glm::length(strata::cardinal_through(v, u) - expected), 1e-5f) << "u=" << u;
  }
  // At the ends the repeated value slows the curve down but it stays between its neighbours.
  const glm::vec4 first = strata::cardinal_through(v, 0.1f);
  EXPECT_GT(first.x, 0.0f);
  EXPECT_LT(first.x, 2.0f);
}

}  // namespace
