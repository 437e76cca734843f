#include "render/props_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace strata {
namespace {

constexpr float kPi = 3.14159265358979f;
const glm::vec3 kUp(0.0f, 1.0f, 0.0f);

// One triangle facing `outward` (its winding flipped if need be, so it is counter-clockwise seen from outside).
void triangle(std::vector<PropVertex>& out, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec4 color,
              glm::vec3 outward) {
  glm::vec3 n = glm::cross(b - a, c - a);
  const float len = glm::length(n);
  if (!(len > 1e-12f)) return;  // degenerate: nothing to light or see
  n /= len;
  if (glm::dot(n, outward) < 0.0f) {
    std::swap(b, c);
    n = -n;
  }
  out.push_back({a, n, color});
  out.push_back({b, n, color});
  out.push_back({c, n, color});
}

// Ear clipping of a simple counter-clockwise polygon (seen from above) into triangles of its top face. Obstacles
// are a few to a few dozen points, so the quadratic clipper costs nothing.
std::vector<std::size_t> triangulate(const std::vector<glm::vec2>& p) {
  std::vector<std::size_t> idx(p.size()), out;
  for (std::size_t i = 0; i < p.size(); ++i) idx[i] = i;
  auto cross = [](glm::vec2 a, glm::vec2 b, glm::vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); };
  std::size_t guard = 0;
  while (idx.size() > 3 && guard++ < 10000) {
    bool clipped = false;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::size_t a = idx[(k + idx.size() - 1) % idx.size()], b = idx[k], c = idx[(k + 1) % idx.size()];
      if (cross(p[a], p[b], p[c]) <= 0.0f) continue;  // reflex (or flat) corner: not an ear
      bool inside = false;
      for (const std::size_t q : idx) {
        if (q == a || q == b || q == c) continue;
        if (cross(p[a], p[b], p[q]) > 0.0f && cross(p[b], p[c], p[q]) > 0.0f && cross(p[c], p[a], p[q]) > 0.0f) {
          inside = true;
          break;
        }
      }
      if (inside) continue;
      out.insert(out.end(), {a, b, c});
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
      break;
    }
    if (!clipped) break;  // not simple after all: draw the rest as a fan rather than nothing
  }
  for (std::size_t k = 1; k + 1 < idx.size(); ++k) out.insert(out.end(), {idx[0], idx[k], idx[k + 1]});
  return out;
}

void disc(std::vector<PropVertex>& out, glm::vec2 at, float radius, float height, glm::vec4 color) {
  constexpr int kSides = 24;
  for (int k = 0; k < kSides; ++k) {
    const float a0 = 2.0f * kPi * static_cast<float>(k) / kSides, a1 = 2.0f * kPi * static_cast<float>(k + 1) / kSides;
    const glm::vec3 c(at.x, height, at.y);
    const glm::vec3 p0(at.x + radius * std::cos(a0), height, at.y + radius * std::sin(a0));
    const glm::vec3 p1(at.x + radius * std::cos(a1), height, at.y + radius * std::sin(a1));
    const glm::vec3 radial(std::cos(0.5f * (a0 + a1)), 0.0f, std::sin(0.5f * (a0 + a1)));
    triangle(out, c, p1, p0, color, kUp);
    triangle(out, p0, p1, glm::vec3(p1.x, 0.0f, p1.z), color, radial);
    triangle(out, p0, glm::vec3(p1.x, 0.0f, p1.z), glm::vec3(p0.x, 0.0f, p0.z), color, radial);
  }
}

}  // namespace

glm::vec4 group_color(std::size_t group) {
  static const glm::vec4 kColors[] = {{0.85f, 0.33f, 0.25f, 1.0f}, {0.22f, 0.50f, 0.85f, 1.0f},
                                      {0.30f, 0.70f, 0.35f, 1.0f}, {0.90f, 0.70f, 0.20f, 1.0f},
                                      {0.60f, 0.35f, 0.75f, 1.0f}, {0.20f, 0.70f, 0.70f, 1.0f}};
  return kColors[group % std::size(kColors)];
}

std::vector<PropVertex> scenario_props(const Scenario& scenario, float obstacle_height) {
  std::vector<PropVertex> out;
  const glm::vec4 stone(0.55f, 0.53f, 0.50f, 1.0f);
  for (const ScenarioPolygon& poly : scenario.obstacles) {
    const std::vector<glm::vec2>& p = poly.points;
    if (p.size() < 3) continue;
    // Sides face away from the polygon: the edge's normal on the side of the polygon's outside (a signed-area
    // test gives the winding, so the rule holds whichever way the loader left it).
    float area2 = 0.0f;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const glm::vec2 a = p[i], b = p[(i + 1) % p.size()];
      area2 += a.x * b.y - b.x * a.y;
    }
    const float outside = area2 > 0.0f ? 1.0f : -1.0f;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const glm::vec2 a = p[i], b = p[(i + 1) % p.size()];
      const glm::vec3 a0(a.x, 0.0f, a.y), b0(b.x, 0.0f, b.y), a1(a.x, obstacle_height, a.y), b1(b.x, obstacle_height, b.y);
      // (dz, -dx) is to the right of a->b in (x, z); for a positive signed area the interior is on the left.
      const glm::vec3 out_normal = outside * glm::vec3(b.y - a.y, 0.0f, -(b.x - a.x));
      triangle(out, a0, b1, b0, stone, out_normal);
      triangle(out, a0, a1, b1, stone, out_normal);
    }
    // The clipper wants a positive signed area in (x, z).
    std::vector<glm::vec2> ccw(p.begin(), p.end());
    if (area2 < 0.0f) std::reverse(ccw.begin(), ccw.end());
    const std::vector<std::size_t> top = triangulate(ccw);
    for (std::size_t t = 0; t + 2 < top.size(); t += 3) {
      const glm::vec2 a = ccw[top[t]], b = ccw[top[t + 1]], c = ccw[top[t + 2]];
      triangle(out, {a.x, obstacle_height, a.y}, {c.x, obstacle_height, c.y}, {b.x, obstacle_height, b.y},
               glm::vec4(glm::vec3(stone) * 1.1f, 1.0f), kUp);
    }
  }
  for (std::size_t g = 0; g < scenario.groups.size(); ++g) {
    const ScenarioGoal& goal = scenario.groups[g].goal;
    const glm::vec4 color = group_color(g);
    switch (goal.kind) {
      case GoalKind::Point:
      case GoalKind::Waypoints:
        for (const glm::vec2& at : goal.points) disc(out, at, std::max(goal.arrive_radius, 0.25f), 0.03f, color);
        break;
      case GoalKind::Region: {
        const glm::vec2 lo = goal.region_min, hi = goal.region_max;
        const float y = 0.015f;
        const glm::vec4 faint = glm::mix(glm::vec4(0.8f, 0.8f, 0.8f, 1.0f), color, 0.5f);
        triangle(out, {lo.x, y, lo.y}, {hi.x, y, hi.y}, {hi.x, y, lo.y}, faint, kUp);
        triangle(out, {lo.x, y, lo.y}, {lo.x, y, hi.y}, {hi.x, y, hi.y}, faint, kUp);
        break;
      }
      case GoalKind::Opposite:
      case GoalKind::Random:
        break;  // every agent's own point: the agents themselves show where they go
    }
  }
  return out;
}

PropsPass::PropsPass()
    : program_(link_program("render/shaders/props.vert", "render/shaders/lit.frag")),
      vao_(GlKind::kVertexArray),
      buffer_(GlKind::kBuffer) {
  const GLuint vao = vao_.id();
  glVertexArrayVertexBuffer(vao, 0, buffer_.id(), 0, sizeof(PropVertex));
  glEnableVertexArrayAttrib(vao, 0);
  glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(PropVertex, position));
  glVertexArrayAttribBinding(vao, 0, 0);
  glEnableVertexArrayAttrib(vao, 1);
  glVertexArrayAttribFormat(vao, 1, 3, GL_FLOAT, GL_FALSE, offsetof(PropVertex, normal));
  glVertexArrayAttribBinding(vao, 1, 0);
  glEnableVertexArrayAttrib(vao, 2);
  glVertexArrayAttribFormat(vao, 2, 4, GL_FLOAT, GL_FALSE, offsetof(PropVertex, color));
  glVertexArrayAttribBinding(vao, 2, 0);
}

void PropsPass::upload(std::uint64_t key, std::span<const PropVertex> triangles) {
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument("props: " + std::to_string(triangles.size()) + " vertices is not whole triangles");
  if (key == key_ && count_ == triangles.size()) return;
  key_ = key;
  count_ = triangles.size();
  if (count_ == 0) return;
  // A new buffer name each time: glNamedBufferStorage is immutable, and props change only with the scenario.
  buffer_ = GlObject(GlKind::kBuffer);
  glNamedBufferStorage(buffer_.id(), static_cast<GLsizeiptr>(count_ * sizeof(PropVertex)), triangles.data(), 0);
  glVertexArrayVertexBuffer(vao_.id(), 0, buffer_.id(), 0, sizeof(PropVertex));
}

void PropsPass::clear() {
  count_ = 0;
  key_ = 0;
}

void PropsPass::draw_shadow(const ShadowPass& shadow) {
  if (count_ == 0) return;
  if (!depth_program_) depth_program_ = link_program("render/shaders/props_shaded.vert", "render/shaders/shadow.frag");
  const GLuint p = depth_program_.id();
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE,
                            glm::value_ptr(shadow.light_view_projection()));
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(count_));
}

void PropsPass::draw(const glm::mat4& view, const glm::mat4& projection, const ShadedFrame* shading) {
  if (count_ == 0) return;
  if (shading) {
    if (!shaded_program_)
      shaded_program_ = link_shaded_program("render/shaders/props_shaded.vert", "render/shaders/shaded.frag");
    const GLuint p = shaded_program_.id();
    shading->apply(p);
    glUseProgram(p);
    const glm::mat4 view_projection = projection * view;
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE,
                              glm::value_ptr(view_projection));
    glBindVertexArray(vao_.id());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(count_));
    return;
  }
  const GLuint p = program_.id();
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform3f(p, glGetUniformLocation(p, "u_color"), 0.5f, 0.5f, 0.5f);
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(count_));
}

}  // namespace strata
