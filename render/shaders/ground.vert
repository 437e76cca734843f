#version 450 core
// Ground pass (render/ground_pass.cpp). The quad is generated from gl_VertexID (no vertex buffer); the core
// profile still needs a bound VAO.
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
