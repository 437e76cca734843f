// Bodies and props under --quality high (body_shaded.vert, props_shaded.vert). shading.glsl is put in front of
// this file when the program is linked (render/shadow_pass.cpp link_shaded_program), which is where #version and
// shade() come from. Each vertex carries the colours on both sides of its surface cut (rig/surface_material.h);
// the interpolated distance picks one per pixel. Props have one colour and a positive distance.
in vec3 v_world;
in vec3 v_normal;
in vec3 v_albedo_above;
in vec3 v_albedo_below;
in float v_cut;
in float v_skin_above;
in float v_skin_below;
in float v_ao;
out vec4 f_color;
void main() {
  vec3 n = normalize(v_normal);
  bool above = v_cut >= 0.0;
  vec3 albedo = above ? v_albedo_above : v_albedo_below;
  float skin = above ? v_skin_above : v_skin_below;
  f_color = vec4(display(shade(v_world, n, albedo, skin, v_ao)), 1.0);
}
