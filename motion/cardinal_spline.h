#pragma once
// Cardinal splines with tension, arc-length reparameterisation, and the double interpolant (a distance curve over
// time drives the position along a path; Steketee & Badler 1985). Maths: ../shared/notes/tech-brief.md section 3.
//
// Segment k runs from p_k to p_{k+1} using neighbours p_{k-1}, p_{k+2}; s = (1 - tension) / 2;
// P(0) = p_k, P(1) = p_{k+1}, P'(0) = s (p_{k+1} - p_{k-1}), P'(1) = s (p_{k+2} - p_k). Tension 0 is Catmull-Rom,
// tension -> 1 approaches the polyline (zero speed at the knots). Open paths use phantom end points
// p_{-1} = 2 p_0 - p_1 and p_{n} = 2 p_{n-1} - p_{n-2}; closed paths wrap indices.
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace strata {

// One segment from its four control points (allocation-free building blocks for per-frame curves).
glm::vec3 cardinal_point(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
                         float s, float u);
glm::vec3 cardinal_derivative(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
                              float s, float u);

// A Cardinal spline through `points` with an arc-length table, built once; evaluation allocates nothing.
// Parameter u runs over [0, segment_count()]; arc length s over [0, length()].
class CardinalSpline {
 public:
  CardinalSpline() = default;
  // Throws std::invalid_argument for fewer than 2 points (3 when closed) or non-finite points. Repeated
  // consecutive points are removed (they would make zero-length segments whose tangent is undefined).
  CardinalSpline(std::vector<glm::vec3> points, float tension = 0.0f, bool closed = false);

  std::size_t segment_count() const;
  bool closed() const { return closed_; }
  float tension() const { return tension_; }
  const std::vector<glm::vec3>& points() const { return points_; }

  glm::vec3 point(float u) const;       // P(u); u is clamped (open) or wrapped (closed)
  glm::vec3 derivative(float u) const;  // dP/du

  float length() const;                       // total arc length
  float length_at(float u) const;             // arc length from u = 0 to u
  float parameter_at(float s) const;          // inverse of length_at; s clamped (open) or wrapped (closed)
  glm::vec3 point_at_length(float s) const;   // Q(u(s))
  glm::vec3 tangent_at_length(float s) const; // unit tangent at arc length s (finite even where |dP/du| = 0)
  // A NaN u or s reads as 0, and so does an infinite one on a closed spline (open ones clamp it): queries on a
  // valid spline always return finite values. A default-constructed spline is empty: lengths 0, points (0,0,0).

 private:
  std::vector<glm::vec3> points_;
  float tension_ = 0.0f;
  bool closed_ = false;
  // Cumulative arc length at sub-interval boundaries: kSubdivisions per segment, 5-point Gauss-Legendre each.
  std::vector<float> table_;
};

// The distance curve S(t) of the double interpolant: a 1-D Cardinal spline through (time, distance) keys with
// strictly increasing times. Ease-in/out lives here; retiming never moves the path. Distances should be
// non-decreasing; the curve is made monotone (no backward motion between keys) by limiting the knot slopes.
class DistanceCurve {
 public:
  DistanceCurve() = default;
  // Throws std::invalid_argument for fewer than 2 keys, non-increasing times or non-finite values.
  DistanceCurve(std::vector<float> times, std::vector<float> distances, float tension = 0.0f);
  float distance(float t) const;  // clamped to the first/last key outside the time range (NaN t: the first)
  float speed(float t) const;     // dS/dt; 0 outside the time range
  float start_time() const;
  float end_time() const;

 private:
  std::vector<float> times_, distances_, slopes_;
};

// Uniform Cardinal interpolation (tension 0, Catmull-Rom) through `values` evenly spaced over u in [0, 1] (u
// clamped; the end values repeat as the outer control points), for curves rebuilt every frame and walked by time,
// not by arc length: a swinging foot's knots, evenly spaced in time (systems/locomotion.cpp). No allocation.
// Needs at least 2 values (one is returned as is).
glm::vec4 cardinal_through(std::span<const glm::vec4> values, float u);

}  // namespace strata
