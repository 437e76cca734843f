// Instanced skeleton drawing (GL 4.5 core, direct state access throughout).
//
// One program draws both meshes: bones and joints differ only in mesh, instance buffer and colour. Each instance
// is a 3x4 affine transform (three vec4 rows, 48 B) rather than a mat4 (64 B): the last row is always 0 0 0 1.
// Per-instance data is re-specified every frame with glNamedBufferData (buffer orphaning). Persistent mapping
// was the alternative; it needs a ring of regions and fences to avoid overwriting data an in-flight draw still
// reads, and it only pays off for uploads far larger than ours (1,000 walkers x ~70 bones x 48 B is ~3 MB,
// a memcpy on llvmpipe). Orphaning gives the same no-stall behaviour with the driver doing the bookkeeping.
#include "render/skeleton_renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <meshoptimizer.h>
#include <glm/gtc/type_ptr.hpp>

namespace strata {

namespace {

// The child end of a bone is this fraction of the parent end's radius: the taper shows the bone's direction.
constexpr float kTipRatio = 0.55f;
constexpr int kBoneSides = 8;
constexpr int kSphereStacks = 8;
constexpr int kSphereSlices = 12;  // 168 triangles

struct MeshVertex {
  glm::vec3 position;
  glm::vec3 normal;
};

struct Mesh {
  std::vector<MeshVertex> vertices;
  std::vector<std::uint16_t> indices;

  std::uint16_t add(const glm::vec3& p, const glm::vec3& n) {
    vertices.push_back({p, glm::normalize(n)});
    return static_cast<std::uint16_t>(vertices.size() - 1);
  }
  // Emits the triangle counter-clockwise as seen from the side `outward` points to, so the generators need not
  // get every winding right by hand.
  void triangle(std::uint16_t a, std::uint16_t b, std::uint16_t c, const glm::vec3& outward) {
    const glm::vec3 n = glm::cross(vertices[b].position - vertices[a].position,
                                   vertices[c].position - vertices[a].position);
    if (glm::dot(n, outward) < 0.0f) std::swap(b, c);
    indices.insert(indices.end(), {a, b, c});
  }
};

// Tapered prism from radius 1 at y = 0 to kTipRatio at y = 1, capped at both ends. Side normals are smooth
// (per ring vertex, not per face) so the prism shades like a cone: a bone's basis may rotate about its axis from
// one frame to the next (see bone_transform) and a faceted prism would visibly flicker when it does.
Mesh make_bone_mesh() {
  Mesh mesh;
  const float slope = 1.0f - kTipRatio;  // outward normal of r(y) = 1 - slope * y is (cos, slope, sin)
  std::array<std::uint16_t, kBoneSides> bottom{}, top{};
  for (int k = 0; k < kBoneSides; ++k) {
    const float angle = 2.0f * 3.14159265f * static_cast<float>(k) / kBoneSides;
    const float c = std::cos(angle), s = std::sin(angle);
    bottom[k] = mesh.add({c, 0.0f, s}, {c, slope, s});
    top[k] = mesh.add({kTipRatio * c, 1.0f, kTipRatio * s}, {c, slope, s});
  }
  for (int k = 0; k < kBoneSides; ++k) {
    const int n = (k + 1) % kBoneSides;
    const glm::vec3 out = mesh.vertices[bottom[k]].position + mesh.vertices[bottom[n]].position;
    mesh.triangle(bottom[k], bottom[n], top[n], out);
    mesh.triangle(bottom[k], top[n], top[k], out);
  }
  // Caps get their own vertices: their normals are the axis, not the side normal.
  std::array<std::uint16_t, kBoneSides> cap_bottom{}, cap_top{};
  for (int k = 0; k < kBoneSides; ++k) {
    cap_bottom[k] = mesh.add(mesh.vertices[bottom[k]].position, {0.0f, -1.0f, 0.0f});
    cap_top[k] = mesh.add(mesh.vertices[top[k]].position, {0.0f, 1.0f, 0.0f});
  }
  for (int k = 1; k + 1 < kBoneSides; ++k) {
    mesh.triangle(cap_bottom[0], cap_bottom[k], cap_bottom[k + 1], {0.0f, -1.0f, 0.0f});
    mesh.triangle(cap_top[0], cap_top[k], cap_top[k + 1], {0.0f, 1.0f, 0.0f});
  }
  return mesh;
}

// Unit UV sphere with single pole vertices (no degenerate triangles) and smooth normals.
Mesh make_sphere_mesh() {
  Mesh mesh;
  const float pi = 3.14159265f;
  const std::uint16_t north = mesh.add({0.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.0f});
  std::vector<std::uint16_t> rings;  // (kSphereStacks - 1) rings of kSphereSlices vertices
  for (int i = 1; i < kSphereStacks; ++i) {
    const float phi = pi * static_cast<float>(i) / kSphereStacks;
    for (int j = 0; j < kSphereSlices; ++j) {
      const float theta = 2.0f * pi * static_cast<float>(j) / kSphereSlices;
      const glm::vec3 p{std::sin(phi) * std::cos(theta), std::cos(phi), std::sin(phi) * std::sin(theta)};
      rings.push_back(mesh.add(p, p));
    }
  }
  const std::uint16_t south = mesh.add({0.0f, -1.0f, 0.0f}, {0.0f, -1.0f, 0.0f});
  auto ring = [&](int i, int j) { return rings[static_cast<std::size_t>(i * kSphereSlices + j % kSphereSlices)]; };
  auto centroid = [&](std::uint16_t a, std::uint16_t b, std::uint16_t c) {
    return mesh.vertices[a].position + mesh.vertices[b].position + mesh.vertices[c].position;
  };
  for (int j = 0; j < kSphereSlices; ++j) {
    const auto a = ring(0, j), b = ring(0, j + 1);
    mesh.triangle(north, a, b, centroid(north, a, b));
    const auto c = ring(kSphereStacks - 2, j), d = ring(kSphereStacks - 2, j + 1);
    mesh.triangle(south, c, d, centroid(south, c, d));
  }
  for (int i = 0; i + 1 < kSphereStacks - 1; ++i) {
    for (int j = 0; j < kSphereSlices; ++j) {
      const auto a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j), d = ring(i + 1, j + 1);
      mesh.triangle(a, b, d, centroid(a, b, d));
      mesh.triangle(a, d, c, centroid(a, d, c));
    }
  }
  return mesh;
}

// Rows of the affine part of a transform: what the vertex shader reads per instance.
struct InstanceRows {
  glm::vec4 row[3];
};

InstanceRows to_rows(const glm::mat4& m) {
  InstanceRows r;
  for (int i = 0; i < 3; ++i) r.row[i] = glm::vec4{m[0][i], m[1][i], m[2][i], m[3][i]};
  return r;
}

bool is_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Lighting is done in view space with a fixed "headlight" a little above and to the right of the viewer, so
// every orbit angle is lit; the rim term brightens silhouettes so thin bones stand out against the ground.
constexpr const char* kMeshVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_row0;
layout(location = 3) in vec4 a_row1;
layout(location = 4) in vec4 a_row2;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_position;
out vec4 v_tint;
void main() {
  vec4 p = vec4(a_position, 1.0);
  vec3 world = vec3(dot(a_row0, p), dot(a_row1, p), dot(a_row2, p));
  // Instance transforms have mutually orthogonal columns (bones: radius, length, radius; joints: uniform), so
  // the inverse transpose is each column divided by its squared length: no per-vertex matrix inverse.
  vec3 c0 = vec3(a_row0.x, a_row1.x, a_row2.x);
  vec3 c1 = vec3(a_row0.y, a_row1.y, a_row2.y);
  vec3 c2 = vec3(a_row0.z, a_row1.z, a_row2.z);
  vec3 n = c0 * (a_normal.x / dot(c0, c0)) + c1 * (a_normal.y / dot(c1, c1)) + c2 * (a_normal.z / dot(c2, c2));
  vec4 view_position = u_view * vec4(world, 1.0);
  v_position = view_position.xyz;
  v_normal = mat3(u_view) * n;  // the view is rigid
  v_tint = vec4(0.0);
  gl_Position = u_projection * view_position;
}
)";

constexpr const char* kMeshFragmentShader = R"(#version 450 core
in vec3 v_normal;
in vec3 v_position;
in vec4 v_tint;  // a per-vertex colour blended over u_color by its alpha (the binding editor's weights)
uniform vec3 u_color;
out vec4 f_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
void main() {
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(-v_position);
  float diffuse = max(dot(n, kToLight), 0.0);
  float rim = pow(1.0 - clamp(dot(n, to_eye), 0.0, 1.0), 3.0);
  vec3 base = mix(u_color, v_tint.rgb, v_tint.a);
  f_color = vec4(base * (0.22 + 0.78 * diffuse) + vec3(0.18 * rim), 1.0);
}
)";

// Bodies arrive as six float arrays (the skin system's SoA); each is one attribute and the shader reassembles
// the vectors, so the CPU never interleaves them.
constexpr const char* kBodyVertexShader = R"(#version 450 core
layout(location = 0) in float a_px;
layout(location = 1) in float a_py;
layout(location = 2) in float a_pz;
layout(location = 3) in float a_nx;
layout(location = 4) in float a_ny;
layout(location = 5) in float a_nz;
// Per-instance offset, for the render benchmark's raw-instancing reference only; the crowd draw leaves the array
// disabled, so GL supplies the generic attribute's initial value (0, 0, 0). One shader serves both draws.
layout(location = 6) in vec3 a_offset;
// Per-vertex colour (normalised bytes), when the input has one; otherwise a disabled array whose generic value
// the renderer sets to (0, 0, 0, 0): no tint.
layout(location = 7) in vec4 a_color;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_position;
out vec4 v_tint;
void main() {
  vec4 view_position = u_view * vec4(vec3(a_px, a_py, a_pz) + a_offset, 1.0);
  v_position = view_position.xyz;
  v_tint = a_color;
  v_normal = mat3(u_view) * vec3(a_nx, a_ny, a_nz);
  gl_Position = u_projection * view_position;
}
)";

// The ground quad is generated from gl_VertexID (no vertex buffer); the core profile still needs a bound VAO.
constexpr const char* kGroundVertexShader = R"(#version 450 core
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec2 u_center;
uniform float u_half_size;
out vec3 v_world;
const vec2 kCorners[4] = vec2[](vec2(-1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, -1.0), vec2(1.0, 1.0));
void main() {
  vec2 xz = u_center + u_half_size * kCorners[gl_VertexID];
  v_world = vec3(xz.x, 0.0, xz.y);
  gl_Position = u_projection * u_view * vec4(v_world, 1.0);
}
)";

// A 1 m grid from the distance to the nearest integer line in screen-space units (fwidth), so lines stay about
// one pixel wide at any distance; they fade where a cell shrinks towards a pixel (which would alias into moire)
// and the whole quad fades into the clear colour towards its edge, hiding where it ends.
constexpr const char* kGroundFragmentShader = R"(#version 450 core
in vec3 v_world;
uniform mat4 u_view;
uniform vec3 u_ground_color;
uniform vec3 u_clear_color;
uniform vec2 u_center;
uniform float u_half_size;
out vec4 f_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
void main() {
  vec2 p = v_world.xz;
  vec2 w = max(fwidth(p), vec2(1e-5));
  vec2 g = abs(fract(p - 0.5) - 0.5) / w;
  float line = (1.0 - min(min(g.x, g.y), 1.0)) * (1.0 - smoothstep(0.1, 0.4, max(w.x, w.y)));
  float diffuse = max(dot(normalize(mat3(u_view) * vec3(0.0, 1.0, 0.0)), kToLight), 0.0);
  vec3 c = u_ground_color * (0.55 + 0.45 * diffuse);
  c = mix(c, 0.8 * c, line);
  float fade = smoothstep(0.6 * u_half_size, u_half_size, length(p - u_center));
  f_color = vec4(mix(c, u_clear_color, fade), 1.0);
}
)";

GLuint compile_shader(GLenum stage, const char* source, const char* label) {
  GLuint shader = glCreateShader(stage);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw std::runtime_error(std::string("skeleton renderer: ") + label + " shader failed to compile: " + log);
  }
  return shader;
}

GLuint link_program(const char* vs_source, const char* fs_source, const char* label) {
  const GLuint vs = compile_shader(GL_VERTEX_SHADER, vs_source, label);
  GLuint fs = 0;
  try {
    fs = compile_shader(GL_FRAGMENT_SHADER, fs_source, label);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);  // flagged; freed with the program
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw std::runtime_error(std::string("skeleton renderer: ") + label + " program failed to link: " + log);
  }
  return program;
}

struct GpuMesh {
  GLuint vao = 0, vertex_buffer = 0, index_buffer = 0, instance_buffer = 0;
  GLsizei index_count = 0;
};

GpuMesh upload_mesh(const Mesh& mesh) {
  GpuMesh gpu;
  gpu.index_count = static_cast<GLsizei>(mesh.indices.size());
  glCreateBuffers(1, &gpu.vertex_buffer);
  glNamedBufferStorage(gpu.vertex_buffer, static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(MeshVertex)),
                       mesh.vertices.data(), 0);
  glCreateBuffers(1, &gpu.index_buffer);
  glNamedBufferStorage(gpu.index_buffer, static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint16_t)),
                       mesh.indices.data(), 0);
  glCreateBuffers(1, &gpu.instance_buffer);  // storage is (re)specified per frame

  glCreateVertexArrays(1, &gpu.vao);
  glVertexArrayVertexBuffer(gpu.vao, 0, gpu.vertex_buffer, 0, sizeof(MeshVertex));
  glVertexArrayVertexBuffer(gpu.vao, 1, gpu.instance_buffer, 0, sizeof(InstanceRows));
  glVertexArrayBindingDivisor(gpu.vao, 1, 1);
  glVertexArrayElementBuffer(gpu.vao, gpu.index_buffer);
  auto attribute = [&](GLuint location, GLuint binding, GLint size, GLuint offset) {
    glEnableVertexArrayAttrib(gpu.vao, location);
    glVertexArrayAttribFormat(gpu.vao, location, size, GL_FLOAT, GL_FALSE, offset);
    glVertexArrayAttribBinding(gpu.vao, location, binding);
  };
  attribute(0, 0, 3, offsetof(MeshVertex, position));
  attribute(1, 0, 3, offsetof(MeshVertex, normal));
  for (GLuint i = 0; i < 3; ++i) attribute(2 + i, 1, 4, static_cast<GLuint>(i * sizeof(glm::vec4)));
  return gpu;
}

void destroy_mesh(GpuMesh& gpu) {
  glDeleteVertexArrays(1, &gpu.vao);
  const GLuint buffers[] = {gpu.vertex_buffer, gpu.index_buffer, gpu.instance_buffer};
  glDeleteBuffers(3, buffers);
  gpu = {};
}

}  // namespace

std::optional<glm::mat4> bone_transform(const glm::vec3& a, const glm::vec3& b, float radius) {
  if (!is_finite(a) || !is_finite(b)) return std::nullopt;
  const glm::vec3 along = b - a;
  const float length = glm::length(along);
  if (!(length > 1e-6f) || !std::isfinite(length)) return std::nullopt;
  const glm::vec3 d = along / length;
  // The helper is the world axis least aligned with the bone, so |cross(helper, d)| >= sqrt(2/3) and the basis
  // never degenerates. A fixed helper (say +Y) was rejected: it is singular exactly for upright bones, which are
  // most bones of a standing humanoid. The choice can flip between frames; the smooth-shaded mesh hides that.
  const glm::vec3 ad = glm::abs(d);
  glm::vec3 helper{0.0f, 0.0f, 1.0f};
  if (ad.x <= ad.y && ad.x <= ad.z)
    helper = {1.0f, 0.0f, 0.0f};
  else if (ad.y <= ad.z)
    helper = {0.0f, 1.0f, 0.0f};
  const glm::vec3 u = glm::normalize(glm::cross(helper, d));
  const glm::vec3 w = glm::cross(u, d);  // (u, d, w) is right-handed: det = u . (d x w) = 1
  glm::mat4 m{1.0f};
  m[0] = glm::vec4(radius * u, 0.0f);
  m[1] = glm::vec4(along, 0.0f);
  m[2] = glm::vec4(radius * w, 0.0f);
  m[3] = glm::vec4(a, 1.0f);
  return m;
}

struct SkeletonRenderer::Impl {
  int width = 0, height = 0;
  SkeletonRenderOptions options;

  GLuint mesh_program = 0, ground_program = 0;
  GLuint ground_vao = 0;
  GpuMesh bone, joint;
  GLsizei samples = 0;
  GLuint msaa_fbo = 0, msaa_color = 0, msaa_depth = 0;
  GLuint resolve_fbo = 0, resolve_color = 0;

  // Kept between frames so steady-state rendering does not allocate.
  std::vector<InstanceRows> bone_instances, joint_instances;

  // Bodies: the six component arrays re-specified per draw in one buffer (orphaning, as for instances); each
  // level's index buffer only when its topology changes, reordered once for the post-transform vertex cache
  // (meshoptimizer), which the same triangles in a different order cost nothing to get.
  struct BodySlot {
    GLuint indices = 0;
    const std::uint32_t* topology = nullptr;
    std::size_t index_count = 0, vertex_count = 0;
  };
  GLuint body_program = 0, body_vao = 0, body_components = 0, body_colors = 0;
  std::array<BodySlot, 4> body_slots{};  // one per body level drawn in the same frame
  std::vector<std::uint32_t> optimized;
  std::vector<GLsizei> body_counts;
  std::vector<const void*> body_offsets;
  std::vector<GLint> body_base_vertices;
  std::size_t triangles_drawn = 0;
  // The instanced reference: the body program with its own VAO, static mesh buffers and instance buffer.
  GLuint instanced_vao = 0, instanced_mesh = 0, instanced_offsets = 0;
  BodySlot instanced_slot{};

  static bool slot_matches(const BodySlot& slot, const BodyDrawInput& b) {
    return slot.topology == b.triangles.data() && slot.index_count == b.triangles.size() &&
           slot.vertex_count == b.vertex_count;
  }

  void create_body_vao() {
    glCreateBuffers(1, &body_components);
    glCreateBuffers(1, &body_colors);
    for (BodySlot& slot : body_slots) glCreateBuffers(1, &slot.indices);
    glCreateVertexArrays(1, &body_vao);
    for (GLuint a = 0; a < 6; ++a) {
      glEnableVertexArrayAttrib(body_vao, a);
      glVertexArrayAttribFormat(body_vao, a, 1, GL_FLOAT, GL_FALSE, 0);
      glVertexArrayAttribBinding(body_vao, a, a);
    }
    glVertexArrayAttribFormat(body_vao, 7, 4, GL_UNSIGNED_BYTE, GL_TRUE, 0);
    glVertexArrayAttribBinding(body_vao, 7, 7);
  }

  void draw_bodies(const BodyDrawInput& b, BodySlot& slot, const glm::mat4& view, const glm::mat4& projection) {
    if (b.walker_count == 0 || b.triangles.empty()) return;
    if (!slot_matches(slot, b)) {
      optimized.resize(b.triangles.size());
      meshopt_optimizeVertexCache(optimized.data(), b.triangles.data(), b.triangles.size(), b.vertex_count);
      glNamedBufferData(slot.indices, static_cast<GLsizeiptr>(optimized.size() * sizeof(std::uint32_t)),
                        optimized.data(), GL_STATIC_DRAW);
      slot.topology = b.triangles.data();
      slot.index_count = b.triangles.size();
      slot.vertex_count = b.vertex_count;
    }
    glVertexArrayElementBuffer(body_vao, slot.indices);
    const std::size_t floats = b.walker_count * b.stride;
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(floats * sizeof(float));
    glNamedBufferData(body_components, 6 * bytes, nullptr, GL_STREAM_DRAW);
    const float* arrays[6] = {b.px, b.py, b.pz, b.nx, b.ny, b.nz};
    for (GLuint a = 0; a < 6; ++a) {
      glNamedBufferSubData(body_components, a * bytes, bytes, arrays[a]);
      glVertexArrayVertexBuffer(body_vao, a, body_components, a * bytes, sizeof(float));
    }
    if (b.rgba) {
      glNamedBufferData(body_colors, static_cast<GLsizeiptr>(floats * sizeof(std::uint32_t)), b.rgba, GL_STREAM_DRAW);
      glVertexArrayVertexBuffer(body_vao, 7, body_colors, 0, sizeof(std::uint32_t));
      glEnableVertexArrayAttrib(body_vao, 7);
    } else {
      glDisableVertexArrayAttrib(body_vao, 7);
      glVertexAttrib4f(7, 0.0f, 0.0f, 0.0f, 0.0f);
    }
    // One multi-draw: the shared index list once per walker, offset by its first vertex.
    body_counts.assign(b.walker_count, static_cast<GLsizei>(b.triangles.size()));
    body_offsets.assign(b.walker_count, nullptr);
    body_base_vertices.resize(b.walker_count);
    for (std::size_t w = 0; w < b.walker_count; ++w) body_base_vertices[w] = static_cast<GLint>(w * b.stride);
    const GLuint p = body_program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
    glProgramUniform3fv(p, glGetUniformLocation(p, "u_color"), 1, glm::value_ptr(options.skin_color));
    glBindVertexArray(body_vao);
    glMultiDrawElementsBaseVertex(GL_TRIANGLES, body_counts.data(), GL_UNSIGNED_INT, body_offsets.data(),
                                  static_cast<GLsizei>(b.walker_count), body_base_vertices.data());
    triangles_drawn += b.walker_count * (b.triangles.size() / 3);
  }

  // Every piece of state a frame depends on (the caller, or a GUI, may have changed any of it), then the clears.
  void begin_frame() {
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
    glViewport(0, 0, width, height);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_BLEND);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);  // clears honour the write mask
    glClearNamedFramebufferfv(msaa_fbo, GL_COLOR, 0, glm::value_ptr(options.clear_color));
    const GLfloat far_depth = 1.0f;
    glClearNamedFramebufferfv(msaa_fbo, GL_DEPTH, 0, &far_depth);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
  }

  void create_targets() {
    glCreateRenderbuffers(1, &msaa_color);
    glCreateRenderbuffers(1, &msaa_depth);
    glCreateRenderbuffers(1, &resolve_color);
    glNamedRenderbufferStorageMultisample(msaa_color, samples, GL_RGBA8, width, height);
    glNamedRenderbufferStorageMultisample(msaa_depth, samples, GL_DEPTH_COMPONENT24, width, height);
    glNamedRenderbufferStorage(resolve_color, GL_RGBA8, width, height);

    glCreateFramebuffers(1, &msaa_fbo);
    glNamedFramebufferRenderbuffer(msaa_fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color);
    glNamedFramebufferRenderbuffer(msaa_fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
    glCreateFramebuffers(1, &resolve_fbo);
    glNamedFramebufferRenderbuffer(resolve_fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color);
    glNamedFramebufferReadBuffer(resolve_fbo, GL_COLOR_ATTACHMENT0);

    for (GLuint fbo : {msaa_fbo, resolve_fbo}) {
      const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
      if (status != GL_FRAMEBUFFER_COMPLETE) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "skeleton renderer: %dx%d framebuffer incomplete (status 0x%04X)", width,
                      height, static_cast<unsigned>(status));
        destroy_targets();
        throw std::runtime_error(buf);
      }
    }
  }

  std::vector<float> joint_radii, bone_radii;  // per joint, see size_radii

  void destroy_targets() {
    const GLuint fbos[] = {msaa_fbo, resolve_fbo};
    glDeleteFramebuffers(2, fbos);
    const GLuint rbs[] = {msaa_color, msaa_depth, resolve_color};
    glDeleteRenderbuffers(3, rbs);
    msaa_fbo = resolve_fbo = msaa_color = msaa_depth = resolve_color = 0;
  }

  void destroy_all() {
    destroy_targets();
    destroy_mesh(bone);
    destroy_mesh(joint);
    glDeleteVertexArrays(1, &body_vao);
    glDeleteBuffers(1, &body_colors);
    glDeleteBuffers(1, &body_components);
    const GLuint instanced_buffers[] = {instanced_mesh, instanced_offsets, instanced_slot.indices};
    glDeleteBuffers(3, instanced_buffers);
    glDeleteVertexArrays(1, &instanced_vao);
    instanced_vao = instanced_mesh = instanced_offsets = 0;
    instanced_slot = BodySlot{};
    for (BodySlot& slot : body_slots) {
      glDeleteBuffers(1, &slot.indices);
      slot = BodySlot{};
    }
    glDeleteProgram(body_program);
    body_vao = body_components = body_program = 0;
    glDeleteVertexArrays(1, &ground_vao);
    glDeleteProgram(mesh_program);
    glDeleteProgram(ground_program);
    ground_vao = mesh_program = ground_program = 0;
  }

  void build_instances(const SkeletonDrawInput& input) {
    bone_instances.clear();
    joint_instances.clear();
    if (input.walker_count == 0) return;
    const Skeleton& skeleton = *input.skeleton;
    const std::size_t joints = skeleton.joint_count();
    size_radii(skeleton);
    for (std::size_t w = 0; w < input.walker_count; ++w) {
      const glm::vec3* pose = input.joint_positions.data() + w * joints;
      for (std::size_t j = 0; j < joints; ++j) {
        if (!is_finite(pose[j])) continue;
        glm::mat4 m = glm::mat4(joint_radii[j]);
        m[3] = glm::vec4(pose[j], 1.0f);
        joint_instances.push_back(to_rows(m));
        const std::int32_t parent = skeleton.parents[j];
        if (parent < 0) continue;
        if (auto bone_m = bone_transform(pose[parent], pose[j], bone_radii[j]))
          bone_instances.push_back(to_rows(*bone_m));
      }
    }
  }

  // Joint and bone thickness per joint, from the rest skeleton: the configured radii, shrunk where bones are
  // short, so an 89-joint H-Anim hand reads as fingers rather than a ball of spheres. Bone j is parent -> j.
  void size_radii(const Skeleton& skeleton) {
    const std::size_t joints = skeleton.joint_count();
    std::vector<float> shortest(joints, std::numeric_limits<float>::max());
    for (std::size_t j = 0; j < joints; ++j) {
      const std::int32_t parent = skeleton.parents[j];
      if (parent < 0) continue;
      const float length = glm::length(skeleton.centers[j] - skeleton.centers[parent]);
      if (!(length > 1e-6f)) continue;
      shortest[j] = std::min(shortest[j], length);
      shortest[parent] = std::min(shortest[parent], length);
    }
    joint_radii.resize(joints);
    bone_radii.resize(joints);
    for (std::size_t j = 0; j < joints; ++j) {
      const float limit = shortest[j] == std::numeric_limits<float>::max() ? options.joint_radius : shortest[j];
      joint_radii[j] = std::min(options.joint_radius, 0.3f * limit);
      bone_radii[j] = std::min(options.bone_radius, 0.25f * limit);
    }
  }

  // Ground quad centred under the walkers, big enough to reach well past the crowd in every direction.
  void ground_extent(const SkeletonDrawInput& input, glm::vec2& center, float& half_size) const {
    glm::vec2 lo{std::numeric_limits<float>::max()}, hi{std::numeric_limits<float>::lowest()};
    const std::size_t n = input.walker_count * (input.skeleton ? input.skeleton->joint_count() : 0);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3& p = input.joint_positions[i];
      if (!is_finite(p)) continue;
      lo = glm::min(lo, glm::vec2{p.x, p.z});
      hi = glm::max(hi, glm::vec2{p.x, p.z});
    }
    if (lo.x > hi.x) {
      center = glm::vec2{0.0f};
      half_size = 25.0f;
      return;
    }
    center = 0.5f * (lo + hi);
    half_size = std::max(0.5f * std::max(hi.x - lo.x, hi.y - lo.y) + 15.0f, 25.0f);
  }
};

SkeletonRenderer::SkeletonRenderer(int width, int height, SkeletonRenderOptions options)
    : impl_(std::make_unique<Impl>()) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("skeleton renderer: size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  Impl& r = *impl_;
  r.width = width;
  r.height = height;
  r.options = options;

  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  // 4x is enough to keep thin bones from breaking up; below 2 there is no MSAA and samples = 0 makes the
  // "multisample" target an ordinary one, leaving the resolve blit a plain copy.
  r.samples = max_samples >= 2 ? std::min<GLint>(4, max_samples) : 0;

  try {
    r.mesh_program = link_program(kMeshVertexShader, kMeshFragmentShader, "mesh");
    r.ground_program = link_program(kGroundVertexShader, kGroundFragmentShader, "ground");
    r.bone = upload_mesh(make_bone_mesh());
    r.joint = upload_mesh(make_sphere_mesh());
    r.body_program = link_program(kBodyVertexShader, kMeshFragmentShader, "body");
    r.create_body_vao();
    glCreateVertexArrays(1, &r.ground_vao);
    r.create_targets();
  } catch (...) {
    r.destroy_all();
    throw;
  }
}

SkeletonRenderer::~SkeletonRenderer() {
  if (impl_) impl_->destroy_all();
}

int SkeletonRenderer::width() const { return impl_->width; }
int SkeletonRenderer::height() const { return impl_->height; }
SkeletonRenderOptions& SkeletonRenderer::options() { return impl_->options; }

void SkeletonRenderer::resize(int width, int height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("skeleton renderer: size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  if (width == impl_->width && height == impl_->height) return;
  impl_->destroy_targets();
  impl_->width = width;
  impl_->height = height;
  impl_->create_targets();
}

void SkeletonRenderer::render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                              const BodyDrawInput* bodies) {
  render(input, view, projection, bodies ? std::span<const BodyDrawInput>(bodies, 1) : std::span<const BodyDrawInput>());
}

std::size_t SkeletonRenderer::triangles_drawn() const { return impl_->triangles_drawn; }

void SkeletonRenderer::render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                              std::span<const BodyDrawInput> body_levels) {
  Impl& r = *impl_;
  if (body_levels.size() > r.body_slots.size())
    throw std::invalid_argument("skeleton renderer: at most " + std::to_string(r.body_slots.size()) + " body levels per frame");
  for (std::size_t k = 0; k < body_levels.size(); ++k) {
    const BodyDrawInput& b = body_levels[k];
    if (b.walker_count == 0) continue;
    if (!b.px || !b.py || !b.pz || !b.nx || !b.ny || !b.nz || b.stride < b.vertex_count || b.triangles.size() % 3 != 0)
      throw std::invalid_argument("skeleton renderer: body arrays/triangles do not describe " +
                                  std::to_string(b.walker_count) + " walkers of " + std::to_string(b.vertex_count) +
                                  " vertices");
    // Indices are checked when the topology changes (they are uploaded then), not every frame.
    if (!Impl::slot_matches(r.body_slots[k], b))
      for (std::uint32_t index : b.triangles)
        if (index >= b.vertex_count)
          throw std::invalid_argument("skeleton renderer: body triangle index " + std::to_string(index) +
                                      " out of range");
  }
  if (input.walker_count > 0) {
    if (!input.skeleton) throw std::invalid_argument("skeleton renderer: walkers given without a skeleton");
    if (input.skeleton->parents.size() != input.skeleton->joint_count())
      throw std::invalid_argument("skeleton renderer: skeleton parents/joint count mismatch");
    const std::size_t needed = input.walker_count * input.skeleton->joint_count();
    if (input.joint_positions.size() < needed)
      throw std::invalid_argument("skeleton renderer: " + std::to_string(input.joint_positions.size()) +
                                  " joint positions for " + std::to_string(needed) + " walker joints");
  }
  r.build_instances(input);
  const SkeletonRenderOptions& o = r.options;

  r.begin_frame();

  if (o.draw_ground) {
    glm::vec2 center;
    float half_size = 0.0f;
    r.ground_extent(input, center, half_size);
    const GLuint p = r.ground_program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
    glProgramUniform2fv(p, glGetUniformLocation(p, "u_center"), 1, glm::value_ptr(center));
    glProgramUniform1f(p, glGetUniformLocation(p, "u_half_size"), half_size);
    glProgramUniform3fv(p, glGetUniformLocation(p, "u_ground_color"), 1, glm::value_ptr(o.ground_color));
    glProgramUniform3fv(p, glGetUniformLocation(p, "u_clear_color"), 1, glm::value_ptr(o.clear_color));
    glBindVertexArray(r.ground_vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  }

  const GLuint p = r.mesh_program;
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  const GLint color_location = glGetUniformLocation(p, "u_color");
  auto draw = [&](const GpuMesh& mesh, const std::vector<InstanceRows>& instances, const glm::vec3& color) {
    if (instances.empty()) return;
    glNamedBufferData(mesh.instance_buffer, static_cast<GLsizeiptr>(instances.size() * sizeof(InstanceRows)),
                      instances.data(), GL_STREAM_DRAW);
    glProgramUniform3fv(p, color_location, 1, glm::value_ptr(color));
    glBindVertexArray(mesh.vao);
    glDrawElementsInstanced(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_SHORT, nullptr,
                            static_cast<GLsizei>(instances.size()));
  };
  if (o.draw_skeleton) {
    draw(r.bone, r.bone_instances, o.bone_color);
    draw(r.joint, r.joint_instances, o.joint_color);
  }
  r.triangles_drawn = 0;
  for (std::size_t k = 0; k < body_levels.size(); ++k) r.draw_bodies(body_levels[k], r.body_slots[k], view, projection);
  glBindVertexArray(0);

  glBlitNamedFramebuffer(r.msaa_fbo, r.resolve_fbo, 0, 0, r.width, r.height, 0, 0, r.width, r.height,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

unsigned SkeletonRenderer::output_framebuffer() const { return impl_->resolve_fbo; }

void SkeletonRenderer::read_rgba(std::vector<std::uint8_t>& out) const {
  const Impl& r = *impl_;
  const std::size_t row_bytes = static_cast<std::size_t>(r.width) * 4;
  out.resize(row_bytes * static_cast<std::size_t>(r.height));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.resolve_fbo);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glReadnPixels(0, 0, r.width, r.height, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(out.size()), out.data());
  // GL's origin is bottom-left; images are stored top row first.
  for (int y = 0; y < r.height / 2; ++y) {
    std::uint8_t* top = out.data() + static_cast<std::size_t>(y) * row_bytes;
    std::uint8_t* bottom = out.data() + static_cast<std::size_t>(r.height - 1 - y) * row_bytes;
    std::swap_ranges(top, top + row_bytes, bottom);
  }
}

void SkeletonRenderer::blit_to_default_framebuffer(int width, int height) const {
  const Impl& r = *impl_;
  const bool same_size = width == r.width && height == r.height;
  glDisable(GL_SCISSOR_TEST);  // blits honour the scissor box
  glBlitNamedFramebuffer(r.resolve_fbo, 0, 0, 0, r.width, r.height, 0, 0, width, height, GL_COLOR_BUFFER_BIT,
                         same_size ? GL_NEAREST : GL_LINEAR);
}

void SkeletonRenderer::render_instanced_reference(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets,
                                                  const glm::mat4& view, const glm::mat4& projection) {
  Impl& r = *impl_;
  if (!mesh.px || mesh.vertex_count == 0 || mesh.triangles.size() % 3 != 0)
    throw std::invalid_argument("render_instanced_reference: no mesh");
  if (r.instanced_vao == 0) {
    glCreateVertexArrays(1, &r.instanced_vao);
    glCreateBuffers(1, &r.instanced_mesh);
    glCreateBuffers(1, &r.instanced_offsets);
    glCreateBuffers(1, &r.instanced_slot.indices);
    for (GLuint a = 0; a < 6; ++a) {
      glEnableVertexArrayAttrib(r.instanced_vao, a);
      glVertexArrayAttribFormat(r.instanced_vao, a, 1, GL_FLOAT, GL_FALSE, 0);
      glVertexArrayAttribBinding(r.instanced_vao, a, a);
    }
    glEnableVertexArrayAttrib(r.instanced_vao, 6);
    glVertexArrayAttribFormat(r.instanced_vao, 6, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(r.instanced_vao, 6, 6);
    glVertexArrayBindingDivisor(r.instanced_vao, 6, 1);
    glVertexArrayElementBuffer(r.instanced_vao, r.instanced_slot.indices);
  }
  // The mesh (walker 0 of `mesh`) and its indices go up once, like any static instanced model.
  if (!Impl::slot_matches(r.instanced_slot, mesh)) {
    for (std::uint32_t index : mesh.triangles)
      if (index >= mesh.vertex_count) throw std::invalid_argument("render_instanced_reference: index out of range");
    r.optimized.resize(mesh.triangles.size());
    meshopt_optimizeVertexCache(r.optimized.data(), mesh.triangles.data(), mesh.triangles.size(), mesh.vertex_count);
    glNamedBufferData(r.instanced_slot.indices, static_cast<GLsizeiptr>(r.optimized.size() * sizeof(std::uint32_t)),
                      r.optimized.data(), GL_STATIC_DRAW);
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(mesh.vertex_count * sizeof(float));
    glNamedBufferData(r.instanced_mesh, 6 * bytes, nullptr, GL_STATIC_DRAW);
    const float* arrays[6] = {mesh.px, mesh.py, mesh.pz, mesh.nx, mesh.ny, mesh.nz};
    for (GLuint a = 0; a < 6; ++a) {
      glNamedBufferSubData(r.instanced_mesh, a * bytes, bytes, arrays[a]);
      glVertexArrayVertexBuffer(r.instanced_vao, a, r.instanced_mesh, a * bytes, sizeof(float));
    }
    r.instanced_slot.topology = mesh.triangles.data();
    r.instanced_slot.index_count = mesh.triangles.size();
    r.instanced_slot.vertex_count = mesh.vertex_count;
  }
  glNamedBufferData(r.instanced_offsets, static_cast<GLsizeiptr>(offsets.size() * sizeof(glm::vec3)), offsets.data(),
                    GL_STREAM_DRAW);
  glVertexArrayVertexBuffer(r.instanced_vao, 6, r.instanced_offsets, 0, sizeof(glm::vec3));
  r.begin_frame();
  const GLuint p = r.body_program;
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_color"), 1, glm::value_ptr(r.options.skin_color));
  glVertexAttrib4f(7, 0.0f, 0.0f, 0.0f, 0.0f);  // no per-vertex tint (attribute 7 is never enabled here)
  glBindVertexArray(r.instanced_vao);
  glDrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(mesh.triangles.size()), GL_UNSIGNED_INT, nullptr,
                          static_cast<GLsizei>(offsets.size()));
  glBindVertexArray(0);
  r.triangles_drawn = offsets.size() * (mesh.triangles.size() / 3);
  glBlitNamedFramebuffer(r.msaa_fbo, r.resolve_fbo, 0, 0, r.width, r.height, 0, 0, r.width, r.height,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void SkeletonRenderer::finish() const { glFinish(); }

}  // namespace strata
