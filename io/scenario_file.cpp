#include "io/scenario_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <sstream>

#include <glm/common.hpp>
#include <glm/vec2.hpp>
#include <nlohmann/json.hpp>

#include "data/embedded.h"
#include "io/load_error.h"

namespace strata {
namespace {

using Json = nlohmann::json;

constexpr double kMaxCoordinate = 1e5;           // metres; beyond this a coordinate is a typo (and floats lose cm)
constexpr float kMaxGroundSide = 10000.0f;       // metres per side of the ground rectangle
constexpr std::int64_t kMaxAgents = 1000000;     // per group and in all
constexpr std::size_t kMaxPolygonPoints = 1000;  // the simplicity check is quadratic in this
constexpr std::size_t kMaxObstacles = 10000;
constexpr std::size_t kMaxWaypoints = 1000;
constexpr std::size_t kMaxGroups = 1000;

// Twice the signed area, positive when counter-clockwise in the (x, z) plane read as a 2-D (x, y) plane.
double signed_area2(const std::vector<glm::vec2>& p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const glm::vec2 u = p[i], v = p[(i + 1) % p.size()];
    a += static_cast<double>(u.x) * v.y - static_cast<double>(v.x) * u.y;
  }
  return a;
}

double orient(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

bool on_segment(glm::dvec2 a, glm::dvec2 b, glm::dvec2 p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

// Closed segments ab and cd share a point (touching counts), in double so float inputs are exact.
bool segments_meet(glm::vec2 a32, glm::vec2 b32, glm::vec2 c32, glm::vec2 d32) {
  const glm::dvec2 a(a32), b(b32), c(c32), d(d32);
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
  return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) || (o3 == 0 && on_segment(c, d, a)) ||
         (o4 == 0 && on_segment(c, d, b));
}

bool point_in_polygon(const std::vector<glm::vec2>& poly, glm::vec2 p) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::vec2 a = poly[i], b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

float distance_to_segment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const glm::vec2 ab = b - a;
  const float len2 = ab.x * ab.x + ab.y * ab.y;
  float t = len2 > 0.0f ? ((p.x - a.x) * ab.x + (p.y - a.y) * ab.y) / len2 : 0.0f;
  t = std::clamp(t, 0.0f, 1.0f);
  const glm::vec2 q = a + t * ab - p;
  return std::sqrt(q.x * q.x + q.y * q.y);
}

// Whether a disc of radius r at p touches the polygon (inside it or within r of an edge).
bool disc_touches_polygon(const std::vector<glm::vec2>& poly, glm::vec2 p, float r) {
  if (point_in_polygon(poly, p)) return true;
  for (std::size_t i = 0; i < poly.size(); ++i)
    if (distance_to_segment(p, poly[i], poly[(i + 1) % poly.size()]) < r) return true;
  return false;
}

// Whether the rectangle [lo, hi] and the polygon overlap (one contains a point of the other, or edges cross).
bool rect_touches_polygon(const std::vector<glm::vec2>& poly, glm::vec2 lo, glm::vec2 hi) {
  const glm::vec2 corners[4] = {lo, {hi.x, lo.y}, hi, {lo.x, hi.y}};
  for (const glm::vec2& c : corners)
    if (point_in_polygon(poly, c)) return true;
  for (const glm::vec2& v : poly)
    if (v.x >= lo.x && v.x <= hi.x && v.y >= lo.y && v.y <= hi.y) return true;
  for (std::size_t i = 0; i < poly.size(); ++i)
    for (int k = 0; k < 4; ++k)
      if (segments_meet(poly[i], poly[(i + 1) % poly.size()], corners[k], corners[(k + 1) % 4])) return true;
  return false;
}

std::string pointer_escape(const std::string& key) {
  std::string out;
  for (const char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

class ScenarioParser {
 public:
  explicit ScenarioParser(const std::string& source) : source_(source) {}

  Scenario parse(std::string_view text) {
    Json root;
    try {
      root = Json::parse(text.begin(), text.end());
    } catch (const Json::exception& e) {
      // A syntax error carries "at line L, column C"; a number beyond double is an out_of_range error, reported
      // here as bad input too rather than escaping as another exception type.
      fail("", std::string("invalid JSON: ") + e.what());
    }
    object(root, "",
           {"_doc", "format", "version", "name", "ground", "walkable_obj", "obstacles", "agents", "groups", "track",
            "duration_s", "seed"});
    if (!root.contains("format") || root["format"] != "strata-scenario")
      fail("/format", "expected \"strata-scenario\"");
    if (!root.contains("version") || !root["version"].is_number_integer() || root["version"].get<std::int64_t>() != 1)
      fail("/version", "expected 1");

    Scenario s;
    s.source = source_;
    if (root.contains("name")) {
      s.name = string(root["name"], "/name");
      if (s.name.empty()) fail("/name", "expected a non-empty string");
    } else {
      s.name = std::filesystem::path(source_).stem().string();
    }
    if (root.contains("ground")) {
      const Json& g = root["ground"];
      object(g, "/ground", {"min", "max"});
      s.ground_min = vec2(required(g, "/ground", "min"), "/ground/min");
      s.ground_max = vec2(required(g, "/ground", "max"), "/ground/max");
      if (!(s.ground_min.x < s.ground_max.x && s.ground_min.y < s.ground_max.y))
        fail("/ground", "min must be below max in x and z");
      if (s.ground_max.x - s.ground_min.x > kMaxGroundSide || s.ground_max.y - s.ground_min.y > kMaxGroundSide)
        fail("/ground", "a side longer than 10000 m");
    }
    if (root.contains("walkable_obj")) {
      const std::string obj = string(root["walkable_obj"], "/walkable_obj");
      if (obj.empty()) fail("/walkable_obj", "expected a non-empty path");
      const std::filesystem::path p(obj);
      s.walkable_obj = p.is_absolute() ? p.string() : (std::filesystem::path(source_).parent_path() / p).string();
    }
    if (root.contains("agents")) s.agents = agents(root["agents"]);
    if (root.contains("duration_s")) {
      s.duration_s = number(root["duration_s"], "/duration_s");
      if (!(s.duration_s > 0.0f && s.duration_s <= 1e6f)) fail("/duration_s", "must lie in (0, 1e6]");
    }
    if (root.contains("seed")) {
      const Json& seed = root["seed"];
      if (!seed.is_number_unsigned() && !(seed.is_number_integer() && seed.get<std::int64_t>() >= 0))
        fail("/seed", "expected a non-negative integer");
      s.seed = seed.get<std::uint64_t>();
    }
    if (root.contains("obstacles")) {
      const Json& obstacles = root["obstacles"];
      if (!obstacles.is_array()) fail("/obstacles", "expected an array");
      if (obstacles.size() > kMaxObstacles) fail("/obstacles", "more than 10000 obstacles");
      for (std::size_t i = 0; i < obstacles.size(); ++i)
        s.obstacles.push_back(obstacle(obstacles[i], "/obstacles/" + std::to_string(i)));
    }
    if (root.contains("track")) {
      s.has_track = true;
      s.track = track(root["track"]);
      // The lane walk is its own world (components/scenario.h): agents, goals and obstacles would be ignored, so
      // their presence is a mistake in the file, not something to drop silently.
      for (const char* key : {"groups", "obstacles", "walkable_obj"})
        if (root.contains(key)) fail(std::string("/") + key, "not allowed with \"track\" (the lane walk has none)");
    } else {
      if (!root.contains("groups")) fail("/groups", "missing (a scenario without \"track\" needs spawn groups)");
      const Json& groups = root["groups"];
      if (!groups.is_array() || groups.empty()) fail("/groups", "expected a non-empty array of spawn groups");
      if (groups.size() > kMaxGroups) fail("/groups", "more than 1000 groups");
      std::int64_t total = 0;
      for (std::size_t i = 0; i < groups.size(); ++i) {
        SpawnGroup g = group(groups[i], "/groups/" + std::to_string(i), s);
        total += g.count;
        if (total > kMaxAgents) fail("/groups/" + std::to_string(i) + "/count", "more than 1000000 agents in all");
        s.groups.push_back(std::move(g));
      }
    }
    return s;
  }

 private:
  [[noreturn]] void fail(const std::string& pointer, const std::string& why) const {
    throw LoadError(source_ + (pointer.empty() ? "" : ": " + pointer) + ": " + why);
  }

  void object(const Json& j, const std::string& at, std::initializer_list<const char*> allowed) const {
    if (!j.is_object()) fail(at.empty() ? "/" : at, "expected an object");
    for (const auto& [key, value] : j.items()) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || key == a;
      if (!ok) fail(at + "/" + pointer_escape(key), "unknown key");
    }
  }

  const Json& required(const Json& j, const std::string& at, const char* key) const {
    if (!j.contains(key)) fail(at + "/" + key, "missing");
    return j[key];
  }

  std::string string(const Json& j, const std::string& at) const {
    if (!j.is_string()) fail(at, "expected a string");
    return j.get<std::string>();
  }

  float number(const Json& j, const std::string& at) const {
    if (!j.is_number()) fail(at, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v) || std::fabs(v) > kMaxCoordinate) fail(at, "not a finite number within +-1e5");
    return static_cast<float>(v);
  }

  float number_or(const Json& j, const std::string& at, const char* key, float fallback) const {
    return j.contains(key) ? number(j[key], at + "/" + key) : fallback;
  }

  glm::vec2 vec2(const Json& j, const std::string& at) const {
    if (!j.is_array() || j.size() != 2) fail(at, "expected [x, z], an array of 2 numbers");
    return {number(j[0], at + "/0"), number(j[1], at + "/1")};
  }

  std::int64_t count(const Json& j, const std::string& at, std::int64_t lo, std::int64_t hi) const {
    if (!j.is_number_integer()) fail(at, "expected an integer");
    if (j.is_number_unsigned() && j.get<std::uint64_t>() > static_cast<std::uint64_t>(hi))
      fail(at, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    const std::int64_t v = j.get<std::int64_t>();
    if (v < lo || v > hi) fail(at, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }

  // A simple polygon of >= 3 distinct points and non-zero area, returned counter-clockwise.
  std::vector<glm::vec2> polygon(const Json& j, const std::string& at) const {
    if (!j.is_array() || j.size() < 3) fail(at, "expected an array of at least 3 points [x, z]");
    if (j.size() > kMaxPolygonPoints) fail(at, "more than 1000 points");
    std::vector<glm::vec2> p;
    for (std::size_t i = 0; i < j.size(); ++i) p.push_back(vec2(j[i], at + "/" + std::to_string(i)));
    check_polygon(p, at);
    if (signed_area2(p) < 0.0) std::reverse(p.begin(), p.end());
    return p;
  }

  void check_polygon(const std::vector<glm::vec2>& p, const std::string& at) const {
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = i + 1; k < n; ++k)
        if (p[i] == p[k]) fail(at, "points " + std::to_string(i) + " and " + std::to_string(k) + " coincide");
    // Every pair of edges meets only where they are neighbours, and neighbours only at their shared point (two
    // neighbours that fold back onto each other overlap along a stretch).
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec2 a = p[i], b = p[(i + 1) % n];
      for (std::size_t k = i + 1; k < n; ++k) {
        const glm::vec2 c = p[k], d = p[(k + 1) % n];
        const bool next = k == i + 1, prev = (k + 1) % n == i;
        if (next || prev) {
          // Neighbours share one end; they overlap beyond it only when collinear and pointing back.
          const glm::vec2 shared = next ? b : a, u = (next ? a : b) - shared, v = (next ? d : c) - shared;
          const double cross = static_cast<double>(u.x) * v.y - static_cast<double>(u.y) * v.x;
          const double dot = static_cast<double>(u.x) * v.x + static_cast<double>(u.y) * v.y;
          if (cross == 0.0 && dot > 0.0)
            fail(at, "self-intersecting: edges " + std::to_string(i) + " and " + std::to_string(k) + " fold back");
          continue;
        }
        if (segments_meet(a, b, c, d))
          fail(at, "self-intersecting: edges " + std::to_string(i) + " and " + std::to_string(k) + " meet");
      }
    }
    if (std::fabs(signed_area2(p)) < 1e-6) fail(at, "zero area");
  }

  ScenarioPolygon obstacle(const Json& j, const std::string& at) const {
    object(j, at, {"polygon", "box"});
    if (j.contains("polygon") == j.contains("box")) fail(at, "expected exactly one of \"polygon\" and \"box\"");
    ScenarioPolygon out;
    if (j.contains("polygon")) {
      out.points = polygon(j["polygon"], at + "/polygon");
      return out;
    }
    const std::string b = at + "/box";
    const Json& box = j["box"];
    object(box, b, {"center", "size", "angle_deg"});
    const glm::vec2 center = vec2(required(box, b, "center"), b + "/center");
    const glm::vec2 size = vec2(required(box, b, "size"), b + "/size");
    if (!(size.x > 0.0f && size.y > 0.0f)) fail(b + "/size", "width and depth must be > 0");
    const float angle = number_or(box, b, "angle_deg", 0.0f) * std::numbers::pi_v<float> / 180.0f;
    const glm::vec2 ax(std::cos(angle), std::sin(angle)), az(-std::sin(angle), std::cos(angle));
    const glm::vec2 hx = 0.5f * size.x * ax, hz = 0.5f * size.y * az;
    // Counter-clockwise for any angle: a rotation keeps the orientation of the unrotated box's corners.
    out.points = {center - hx - hz, center + hx - hz, center + hx + hz, center - hx + hz};
    check_polygon(out.points, b);
    return out;
  }

  AgentParameters agents(const Json& j) const {
    const std::string at = "/agents";
    object(j, at, {"radius", "speed", "height"});
    AgentParameters a;
    a.radius = number_or(j, at, "radius", a.radius);
    if (!(a.radius > 0.0f && a.radius <= 5.0f)) fail(at + "/radius", "must lie in (0, 5] m");
    if (j.contains("speed")) {
      const std::string s = at + "/speed";
      object(j["speed"], s, {"mean", "sd", "min", "max"});
      a.speed_mean = number_or(j["speed"], s, "mean", a.speed_mean);
      a.speed_sd = number_or(j["speed"], s, "sd", a.speed_sd);
      a.speed_min = number_or(j["speed"], s, "min", a.speed_min);
      a.speed_max = number_or(j["speed"], s, "max", a.speed_max);
      if (!(a.speed_min > 0.0f)) fail(s + "/min", "must be > 0");
      if (!(a.speed_max <= 10.0f)) fail(s + "/max", "must be <= 10 m/s");
      if (!(a.speed_min <= a.speed_max)) fail(s, "min must not exceed max");
      if (!(a.speed_mean >= a.speed_min && a.speed_mean <= a.speed_max)) fail(s + "/mean", "must lie in [min, max]");
      if (!(a.speed_sd >= 0.0f && a.speed_sd <= 5.0f)) fail(s + "/sd", "must lie in [0, 5]");
    }
    if (j.contains("height")) {
      const std::string h = at + "/height";
      object(j["height"], h, {"mean", "sd"});
      a.height_mean = number_or(j["height"], h, "mean", a.height_mean);
      a.height_sd = number_or(j["height"], h, "sd", a.height_sd);
      if (!(a.height_mean >= 0.5f && a.height_mean <= 2.5f)) fail(h + "/mean", "must lie in [0.5, 2.5] m");
      if (!(a.height_sd >= 0.0f && a.height_sd <= 0.5f)) fail(h + "/sd", "must lie in [0, 0.5] m");
    }
    return a;
  }

  TrackLayout track(const Json& j) const {
    const std::string at = "/track";
    object(j, at, {"walkers", "straight", "radius", "lane_spacing", "speed_min", "speed_max"});
    TrackLayout t;
    if (j.contains("walkers"))
      t.walkers = static_cast<std::uint32_t>(count(j["walkers"], at + "/walkers", 1, kMaxAgents));
    t.straight = number_or(j, at, "straight", t.straight);
    t.radius = number_or(j, at, "radius", t.radius);
    t.lane_spacing = number_or(j, at, "lane_spacing", t.lane_spacing);
    t.speed_min = number_or(j, at, "speed_min", t.speed_min);
    t.speed_max = number_or(j, at, "speed_max", t.speed_max);
    if (!(t.straight >= 0.0f && t.straight <= 1000.0f)) fail(at + "/straight", "must lie in [0, 1000] m");
    if (!(t.radius > 0.0f && t.radius <= 1000.0f)) fail(at + "/radius", "must lie in (0, 1000] m");
    if (!(t.lane_spacing > 0.0f && t.lane_spacing <= 100.0f)) fail(at + "/lane_spacing", "must lie in (0, 100] m");
    if (!(t.speed_min > 0.0f)) fail(at + "/speed_min", "must be > 0");
    if (!(t.speed_max <= 10.0f)) fail(at + "/speed_max", "must be <= 10 m/s");
    if (!(t.speed_min <= t.speed_max)) fail(at, "speed_min must not exceed speed_max");
    return t;
  }

  void inside_ground(glm::vec2 lo, glm::vec2 hi, const Scenario& s, float inset, const std::string& at,
                     const char* what) const {
    if (lo.x < s.ground_min.x + inset || lo.y < s.ground_min.y + inset || hi.x > s.ground_max.x - inset ||
        hi.y > s.ground_max.y - inset) {
      std::ostringstream why;
      why << what << " reaches outside the ground";
      if (inset > 0.0f) why << " (inset by the agent radius, " << inset << " m)";
      fail(at, why.str());
    }
  }

  SpawnGroup group(const Json& j, const std::string& at, const Scenario& s) const {
    object(j, at, {"name", "count", "spawn", "goal"});
    SpawnGroup g;
    if (j.contains("name")) g.name = string(j["name"], at + "/name");
    g.count = static_cast<std::uint32_t>(count(required(j, at, "count"), at + "/count", 1, kMaxAgents));
    const float r = s.agents.radius;

    const std::string sp = at + "/spawn";
    const Json& spawn = required(j, at, "spawn");
    if (!spawn.is_object()) fail(sp, "expected an object");
    const std::string shape = string(required(spawn, sp, "shape"), sp + "/shape");
    if (shape == "circle") {
      object(spawn, sp, {"shape", "center", "radius"});
      g.shape = SpawnShape::Circle;
      g.center = vec2(required(spawn, sp, "center"), sp + "/center");
      g.radius = number(required(spawn, sp, "radius"), sp + "/radius");
      if (!(g.radius > 0.0f)) fail(sp + "/radius", "must be > 0");
      inside_ground(g.center - g.radius, g.center + g.radius, s, r, sp, "the spawn circle");
      // Neighbours on the circle are a chord apart; closer than two radii they would start overlapping.
      if (g.count > 1) {
        const double chord = 2.0 * g.radius * std::sin(std::numbers::pi / g.count);
        if (chord < 2.0 * r)
          fail(sp + "/radius", "too small for " + std::to_string(g.count) + " agents of radius " + std::to_string(r) +
                                   " m (neighbours closer than two radii)");
      }
    } else if (shape == "rect") {
      object(spawn, sp, {"shape", "min", "max"});
      g.shape = SpawnShape::Rect;
      g.min = vec2(required(spawn, sp, "min"), sp + "/min");
      g.max = vec2(required(spawn, sp, "max"), sp + "/max");
      if (!(g.min.x <= g.max.x && g.min.y <= g.max.y)) fail(sp, "min must not exceed max in x or z");
      g.center = 0.5f * (g.min + g.max);
      inside_ground(g.min, g.max, s, r, sp, "the spawn rectangle");
      // A grid at two radii spacing is the densest the spawner may use.
      const double cols = std::floor((g.max.x - g.min.x) / (2.0 * r)) + 1.0;
      const double rows = std::floor((g.max.y - g.min.y) / (2.0 * r)) + 1.0;
      if (cols * rows < g.count)
        fail(sp, "too small for " + std::to_string(g.count) + " agents two radii apart (room for " +
                     std::to_string(static_cast<std::int64_t>(cols * rows)) + ")");
    } else {
      fail(sp + "/shape", "expected \"circle\" or \"rect\"");
    }
    spawn_clear_of_obstacles(g, s, sp);

    g.goal = goal(required(j, at, "goal"), at + "/goal", s, g);
    return g;
  }

  // No agent may start inside an obstacle or touching one: every circle position, or the whole rectangle grown
  // by the agent radius, stays clear.
  void spawn_clear_of_obstacles(const SpawnGroup& g, const Scenario& s, const std::string& at) const {
    const float r = s.agents.radius;
    for (std::size_t o = 0; o < s.obstacles.size(); ++o) {
      const std::vector<glm::vec2>& poly = s.obstacles[o].points;
      glm::vec2 lo = poly[0], hi = poly[0];
      for (const glm::vec2& v : poly) lo = glm::min(lo, v), hi = glm::max(hi, v);
      const std::string which = "overlaps /obstacles/" + std::to_string(o);
      if (g.shape == SpawnShape::Rect) {
        if (rect_touches_polygon(poly, g.min - r, g.max + r)) fail(at, which);
        continue;
      }
      if (g.center.x + g.radius + r < lo.x || g.center.x - g.radius - r > hi.x || g.center.y + g.radius + r < lo.y ||
          g.center.y - g.radius - r > hi.y)
        continue;
      // Only the positions whose angle can reach the obstacle's box are tested, so a million agents against ten
      // thousand small obstacles stays linear in the agents rather than their product.
      const glm::vec2 glo = lo - r, ghi = hi + r;
      std::int64_t first = 0, last = static_cast<std::int64_t>(g.count) - 1;
      if (!(g.center.x >= glo.x && g.center.x <= ghi.x && g.center.y >= glo.y && g.center.y <= ghi.y)) {
        const glm::vec2 mid = 0.5f * (glo + ghi) - g.center;
        const double base = std::atan2(mid.y, mid.x);
        double amin = 0.0, amax = 0.0;
        for (const glm::vec2 c : {glo, ghi, glm::vec2(glo.x, ghi.y), glm::vec2(ghi.x, glo.y)}) {
          double d = std::atan2(c.y - g.center.y, c.x - g.center.x) - base;
          while (d > std::numbers::pi) d -= 2.0 * std::numbers::pi;
          while (d < -std::numbers::pi) d += 2.0 * std::numbers::pi;
          amin = std::min(amin, d), amax = std::max(amax, d);
        }
        const double step = 2.0 * std::numbers::pi / g.count;
        first = static_cast<std::int64_t>(std::floor((base + amin) / step)) - 1;
        last = static_cast<std::int64_t>(std::ceil((base + amax) / step)) + 1;
        last = std::min(last, first + static_cast<std::int64_t>(g.count) - 1);
      }
      for (std::int64_t k = first; k <= last; ++k) {
        const std::int64_t n = g.count;
        const std::uint32_t i = static_cast<std::uint32_t>(((k % n) + n) % n);
        const double a = 2.0 * std::numbers::pi * i / g.count;
        const glm::vec2 p = g.center + g.radius * glm::vec2(std::cos(a), std::sin(a));
        if (p.x + r < lo.x || p.x - r > hi.x || p.y + r < lo.y || p.y - r > hi.y) continue;
        if (disc_touches_polygon(poly, p, r)) fail(at, which + " (agent " + std::to_string(i) + ")");
      }
    }
  }

  ScenarioGoal goal(const Json& j, const std::string& at, const Scenario& s, const SpawnGroup& g) const {
    if (!j.is_object()) fail(at, "expected an object");
    const std::string kind = string(required(j, at, "kind"), at + "/kind");
    ScenarioGoal out;
    if (j.contains("arrive_radius")) {
      out.arrive_radius = number(j["arrive_radius"], at + "/arrive_radius");
      if (!(out.arrive_radius > 0.0f && out.arrive_radius <= 100.0f))
        fail(at + "/arrive_radius", "must lie in (0, 100] m");
    }
    auto point_inside = [&](glm::vec2 p, const std::string& where) {
      inside_ground(p, p, s, 0.0f, where, "the point");
    };
    if (kind == "point") {
      object(j, at, {"kind", "arrive_radius", "point"});
      out.kind = GoalKind::Point;
      out.points = {vec2(required(j, at, "point"), at + "/point")};
      point_inside(out.points[0], at + "/point");
    } else if (kind == "region") {
      object(j, at, {"kind", "arrive_radius", "min", "max"});
      out.kind = GoalKind::Region;
      out.region_min = vec2(required(j, at, "min"), at + "/min");
      out.region_max = vec2(required(j, at, "max"), at + "/max");
      if (!(out.region_min.x <= out.region_max.x && out.region_min.y <= out.region_max.y))
        fail(at, "min must not exceed max in x or z");
      inside_ground(out.region_min, out.region_max, s, 0.0f, at, "the goal region");
    } else if (kind == "opposite") {
      object(j, at, {"kind", "arrive_radius", "center"});
      out.kind = GoalKind::Opposite;
      out.points = {vec2(required(j, at, "center"), at + "/center")};
      // The spawn region mirrored through the centre is where the goals fall.
      const glm::vec2 c = out.points[0];
      const glm::vec2 lo = g.shape == SpawnShape::Circle ? 2.0f * c - g.center - g.radius : 2.0f * c - g.max;
      const glm::vec2 hi = g.shape == SpawnShape::Circle ? 2.0f * c - g.center + g.radius : 2.0f * c - g.min;
      inside_ground(lo, hi, s, 0.0f, at + "/center", "the spawn region mirrored through the centre");
    } else if (kind == "waypoints") {
      object(j, at, {"kind", "arrive_radius", "points"});
      out.kind = GoalKind::Waypoints;
      const Json& points = required(j, at, "points");
      const std::string p = at + "/points";
      if (!points.is_array() || points.size() < 2) fail(p, "expected an array of at least 2 points [x, z]");
      if (points.size() > kMaxWaypoints) fail(p, "more than 1000 waypoints");
      for (std::size_t i = 0; i < points.size(); ++i) {
        out.points.push_back(vec2(points[i], p + "/" + std::to_string(i)));
        point_inside(out.points.back(), p + "/" + std::to_string(i));
      }
    } else if (kind == "random") {
      object(j, at, {"kind", "arrive_radius"});
      out.kind = GoalKind::Random;
    } else {
      fail(at + "/kind", "expected \"point\", \"region\", \"opposite\", \"waypoints\" or \"random\"");
    }
    return out;
  }

  std::string source_;
};

constexpr const char* kShipped[] = {"bottleneck", "circle", "crossing", "plaza", "track"};

}  // namespace

Scenario parse_scenario(std::string_view json, const std::string& source_name) {
  return ScenarioParser(source_name).parse(json);
}

Scenario load_scenario(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path + ": cannot open the scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw LoadError(path + ": cannot read the scenario file");
  return parse_scenario(text.str(), path);
}

std::vector<std::string> shipped_scenario_names() { return {std::begin(kShipped), std::end(kShipped)}; }

Scenario shipped_scenario(const std::string& name) {
  const std::string path = "data/scenarios/" + name + ".json";
  const bool known = std::find(std::begin(kShipped), std::end(kShipped), name) != std::end(kShipped);
  const std::optional<std::string_view> bytes = known ? embedded::find(path) : std::nullopt;
  if (!bytes) {
    std::string list;
    for (const char* n : kShipped) list += (list.empty() ? "" : ", ") + std::string(n);
    throw LoadError(name + ": no shipped scenario of that name (shipped: " + list + ")");
  }
  return parse_scenario(*bytes, path);
}

Scenario resolve_scenario(const std::string& name_or_file) {
  if (std::find(std::begin(kShipped), std::end(kShipped), name_or_file) != std::end(kShipped))
    return shipped_scenario(name_or_file);
  std::error_code ec;
  if (!std::filesystem::exists(name_or_file, ec)) {
    std::string list;
    for (const char* n : kShipped) list += (list.empty() ? "" : ", ") + std::string(n);
    throw LoadError(name_or_file + ": neither a shipped scenario (" + list + ") nor a file");
  }
  return load_scenario(name_or_file);
}

}  // namespace strata
