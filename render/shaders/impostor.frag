// Impostors: the atlas texel's dress weights, normal and depth (components/impostor_atlas.h), lit as a mesh is,
// and a depth written from the baked surface so impostors sort correctly against meshes and each other. Coverage
// goes to alpha-to-coverage over the 4x multisampled target: soft edges without blending or sorting.
// Linked twice (render/impostor_pass.cpp): as it is after a #version line, lit exactly as lit.frag lights a mesh
// in the skin colour (the same headlight and rim term; keep the two in step); and with SHADED defined after
// shading.glsl, dressed in the walker's palette and lit by the sun, sky and shadow map as the shaded bodies are.
in vec2 v_uv;
flat in int v_layer;
in vec3 v_view_position;
flat in vec3 v_to_eye;
flat in vec3 v_cell_to_eye;
flat in mat3 v_local_to_view;
flat in float v_depth_scale;
flat in float v_ahead;
flat in int v_walker;
uniform sampler2DArray u_color_atlas;
uniform sampler2DArray u_normal_atlas;
uniform mat4 u_projection;
out vec4 f_color;
// The quad stands in front of every baked surface (impostor.vert): the depth written is never nearer than the
// quad's, which lets the rasteriser test depth before shading.
layout(depth_greater) out float gl_FragDepth;
#ifdef SHADED
uniform mat4 u_view_inverse;    // view -> world
uniform samplerBuffer u_palettes;  // 7 linear colours per walker (render/appearance.h), by surface class
#else
uniform vec3 u_skin_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
#endif
void main() {
  vec4 c = texture(u_color_atlas, vec3(v_uv, v_layer));
  if (c.a < 0.04) discard;
  vec4 nd = texture(u_normal_atlas, vec3(v_uv, v_layer)) / c.a;  // both images premultiplied by the coverage
  vec3 n = normalize(v_local_to_view * (nd.rgb * 2.0 - 1.0));
  // Baked depth: + towards the viewer from the walker's centre; the quad is v_ahead in front of the centre.
  float behind_quad = v_ahead - (nd.a * 2.0 - 1.0) * v_depth_scale;
  vec3 surface = v_view_position - v_to_eye * max(behind_quad, 0.0);
#ifdef SHADED
  // Weights of the top, the bottom (shoes count as trousers at this size) and hair; skin takes the rest.
  vec3 w = clamp(c.rgb / c.a, 0.0, 1.0);
  float skin = max(1.0 - w.r - w.g - w.b, 0.0);
  int base = v_walker * 7;
  vec3 albedo = skin * texelFetch(u_palettes, base + 0).rgb + w.r * texelFetch(u_palettes, base + 1).rgb +
                w.g * texelFetch(u_palettes, base + 2).rgb + w.b * texelFetch(u_palettes, base + 4).rgb;
  vec3 world = (u_view_inverse * vec4(surface, 1.0)).xyz;
  f_color = vec4(display(shade(world, mat3(u_view_inverse) * n, albedo, skin, 1.0)), c.a);
#else
  vec3 albedo = u_skin_color;
  float diffuse = max(dot(n, kToLight), 0.0);
  // The rim term against the direction the cell was baked from, not the real one: the image is the walker seen
  // from there, and its silhouette normals are perpendicular to that direction. Against the real view, up to 6-12
  // degrees away, half the silhouette faced away from the eye and the cubic term drew a white outline round every
  // impostor that meshes do not have.
  float facing = 1.0 - clamp(dot(n, v_cell_to_eye), 0.0, 1.0);
  f_color = vec4(albedo * (0.22 + 0.78 * diffuse) + vec3(0.18 * facing * facing * facing), c.a);
#endif
  vec4 clip = u_projection * vec4(surface, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
