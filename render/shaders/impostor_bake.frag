#version 450 core
// The impostor bake (render/impostor_bake.cpp): body.vert's output, written as what an impostor needs to be
// dressed, lit and depth-tested later rather than as a lit colour (components/impostor_atlas.h has the encoding):
// the dress weights arrive as body.vert's per-vertex colour. The bake camera is orthographic, so view-space z is
// linear depth.
in vec3 v_normal;    // view space
in vec3 v_position;  // view space
in vec4 v_tint;  // rgb: weights of the top, the bottom and hair
uniform mat3 u_view_to_local;  // view space -> the walker's own frame (humanoid space, facing +Z)
uniform float u_center_z;      // view-space z of the cell centre
uniform float u_depth_range;   // metres mapped to the alpha range
layout(location = 0) out vec4 f_albedo;
layout(location = 1) out vec4 f_normal_depth;
void main() {
  vec3 n = normalize(u_view_to_local * normalize(v_normal));
  float depth = clamp((v_position.z - u_center_z) / u_depth_range, -1.0, 1.0);
  f_albedo = vec4(v_tint.rgb, 1.0);
  f_normal_depth = vec4(n * 0.5 + 0.5, depth * 0.5 + 0.5);
}
