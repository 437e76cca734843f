#version 450 core
// Body pass (render/body_pass.cpp) and the benchmark's instanced reference (render/reference_pass.cpp), lit by
// lit.frag. Bodies arrive as six float arrays (the skin system's SoA); each is one attribute and the shader
// reassembles the vectors, so the CPU never interleaves them.
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
