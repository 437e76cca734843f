#version 450 core
// Scenario props (render/props_pass.cpp): obstacles and goal markers, static triangles with a colour each, lit by
// lit.frag like the bodies so they sit in the same light.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_position;
out vec4 v_tint;
void main() {
  vec4 view_position = u_view * vec4(a_position, 1.0);
  v_position = view_position.xyz;
  v_tint = a_color;
  v_normal = mat3(u_view) * a_normal;
  gl_Position = u_projection * view_position;
}
