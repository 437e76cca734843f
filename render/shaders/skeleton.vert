#version 450 core
// Skeleton pass (render/skeleton_pass.cpp): bones and joints, instanced. One program draws both meshes; they
// differ only in mesh, instance buffer and colour. Each instance is a 3x4 affine transform read as three vec4
// rows (48 B) rather than a mat4 (64 B): the last row is always 0 0 0 1. Lit by lit.frag.
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
