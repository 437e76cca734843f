#version 450 core
// Scenario props under --quality high (render/props_pass.cpp), shaded by shaded.frag like the bodies; their
// colours are sRGB bytes, made linear here.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
uniform mat4 u_view_projection;
out vec3 v_world;
out vec3 v_normal;
out vec3 v_albedo_above;
out vec3 v_albedo_below;
out float v_cut;
out float v_skin_above;
out float v_skin_below;
out float v_ao;
void main() {
  v_world = a_position;
  v_normal = a_normal;
  v_albedo_above = pow(a_color.rgb, vec3(2.2));
  v_albedo_below = v_albedo_above;
  v_cut = 1.0;
  v_skin_above = 0.0;
  v_skin_below = 0.0;
  v_ao = 1.0;
  gl_Position = u_view_projection * vec4(a_position, 1.0);
}
