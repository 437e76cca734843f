#version 450 core
// Impostors: the atlas texel's albedo, normal and depth, lit exactly as lit.frag lights a mesh (the same headlight
// and rim term; keep the two in step), and a depth written from the baked surface so impostors sort correctly
// against meshes and each other. Coverage goes to alpha-to-coverage over the 4x multisampled target: soft edges
// without blending or sorting.
in vec2 v_uv;
flat in int v_layer;
in vec3 v_view_position;
flat in vec3 v_to_eye;
flat in vec3 v_cell_to_eye;
flat in float v_heading;
flat in float v_scale;
uniform sampler2DArray u_color_atlas;
uniform sampler2DArray u_normal_atlas;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_depth_range;
out vec4 f_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
void main() {
  vec4 c = texture(u_color_atlas, vec3(v_uv, v_layer));
  if (c.a < 0.04) discard;
  vec4 nd = texture(u_normal_atlas, vec3(v_uv, v_layer));
  nd /= c.a;  // both images are premultiplied by the same coverage
  vec3 albedo = c.rgb / c.a;
  vec3 local = nd.rgb * 2.0 - 1.0;
  float h = v_heading;
  vec3 world = vec3(cos(h) * local.x + sin(h) * local.z, local.y, -sin(h) * local.x + cos(h) * local.z);
  vec3 n = normalize(mat3(u_view) * world);
  float depth = (nd.a * 2.0 - 1.0) * u_depth_range * v_scale;
  vec3 surface = v_view_position + v_to_eye * depth;
  float diffuse = max(dot(n, kToLight), 0.0);
  // The rim term against the direction the cell was baked from, not the real one: the image is the walker seen
  // from there, and its silhouette normals are perpendicular to that direction. Against the real view, up to 11
  // degrees away, half the silhouette faced away from the eye and the cubic term drew a white outline round every
  // impostor that meshes do not have.
  float rim = pow(1.0 - clamp(dot(n, v_cell_to_eye), 0.0, 1.0), 3.0);
  f_color = vec4(albedo * (0.22 + 0.78 * diffuse) + vec3(0.18 * rim), c.a);
  vec4 clip = u_projection * vec4(surface, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
