#version 450 core
// Bodies under --quality high (render/body_pass.cpp), shaded by shaded.frag. The same six float arrays as
// body.vert. Each vertex finds its walker and its place in the body from gl_VertexID, which includes the draw's
// base vertex (walker w's block starts at w * u_stride): its surface classes (skin, top, bottom, shoes, hair, eyes:
// rig/surface_material.h) from one per-vertex list shared by every walker, and its colour from that walker's
// palette (render/appearance.h), so no per-walker per-vertex data is streamed.
layout(location = 0) in float a_px;
layout(location = 1) in float a_py;
layout(location = 2) in float a_pz;
layout(location = 3) in float a_nx;
layout(location = 4) in float a_ny;
layout(location = 5) in float a_nz;
layout(location = 7) in vec4 a_color;  // the binding editor's tint, as in body.vert (generic (0,0,0,0) when none)
uniform mat4 u_view_projection;
uniform int u_stride;
uniform usamplerBuffer u_materials;  // per vertex of the body, u_stride entries: two surface classes, 4 bits each
uniform samplerBuffer u_surface;     // per vertex: signed distance to the classes' cut (m), ambient occlusion
uniform samplerBuffer u_palettes;    // 7 linear colours per walker, one per surface class
out vec3 v_world;
out vec3 v_normal;
out vec3 v_albedo_above;  // the colour on the cut's positive side
out vec3 v_albedo_below;  // and on its negative side
out float v_cut;          // interpolated, then thresholded per pixel: a straight edge where classes meet
out float v_skin_above;
out float v_skin_below;
out float v_ao;
const int kClasses = 7;
void main() {
  int walker = gl_VertexID / u_stride;
  int local = gl_VertexID - walker * u_stride;
  uint classes = texelFetch(u_materials, local).r;
  vec2 surface = texelFetch(u_surface, local).rg;
  vec4 above = texelFetch(u_palettes, walker * kClasses + min(int(classes & 15u), kClasses - 1));
  vec4 below = texelFetch(u_palettes, walker * kClasses + min(int(classes >> 4), kClasses - 1));
  // Skin and cloth are not one flat colour: a small per-vertex variation (a hash of the vertex number, the same
  // on every walker and every frame) breaks up large even areas.
  float h = 0.975 + 0.05 * fract(sin(float(local) * 12.9898) * 43758.5453);
  v_albedo_above = mix(above.rgb * h, a_color.rgb, a_color.a);
  v_albedo_below = mix(below.rgb * h, a_color.rgb, a_color.a);
  v_skin_above = above.a;  // the palette's alpha says how skin-like the surface is
  v_skin_below = below.a;
  v_cut = surface.x;
  v_ao = surface.y;
  v_world = vec3(a_px, a_py, a_pz);
  v_normal = vec3(a_nx, a_ny, a_nz);
  gl_Position = u_view_projection * vec4(v_world, 1.0);
}
