#version 450 core
// Impostors into the sun's shadow map (render/impostor_pass.cpp draw_shadow): impostor.vert run with the sun as
// the eye, so each quad faces the sun and shows the atlas cell nearest the sun's direction in the walker's frame,
// which is the walker's silhouette seen from there (to the nearest of the atlas's azimuths and elevations). The
// depth written is the baked surface's, as impostor.frag writes it for the camera: a walker's sunlit side is then
// not behind its own shadow caster.
in vec2 v_uv;
flat in int v_layer;
in vec3 v_view_position;
flat in vec3 v_to_eye;
flat in float v_depth_scale;
flat in float v_ahead;
uniform sampler2DArray u_color_atlas;
uniform sampler2DArray u_normal_atlas;
uniform mat4 u_projection;
layout(depth_greater) out float gl_FragDepth;
void main() {
  vec4 c = texture(u_color_atlas, vec3(v_uv, v_layer));
  // Half coverage: a depth map has no partial texels, and the filtered lookup softens the edge.
  if (c.a < 0.5) discard;
  float baked = texture(u_normal_atlas, vec3(v_uv, v_layer)).a / c.a;
  float behind_quad = v_ahead - (baked * 2.0 - 1.0) * v_depth_scale;
  vec3 surface = v_view_position - v_to_eye * max(behind_quad, 0.0);
  vec4 clip = u_projection * vec4(surface, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
