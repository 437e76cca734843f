#version 450 core
// Impostors (render/impostor_pass.cpp): one camera-facing quad per far walker, drawn instanced (4 vertices from
// gl_VertexID, no vertex buffer), its image the atlas cell nearest the direction the camera sees the walker from
// at its gait phase (components/impostor_atlas.h). Per-instance attributes are the impostor table's columns, one
// float each, as the body pass streams the skin system's SoA arrays.
layout(location = 0) in float a_x;
layout(location = 1) in float a_y;
layout(location = 2) in float a_z;
layout(location = 3) in float a_heading;
layout(location = 4) in float a_scale;
layout(location = 5) in float a_phase;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_eye;
uniform ivec4 u_grid;         // phases, azimuths, elevations, unused
uniform float u_max_elevation;  // radians
uniform vec3 u_cell;          // cell width, cell height, centre height (m at scale 1)
uniform float u_depth_range;  // m at scale 1
layout(std430, binding = 0) readonly buffer CellBounds { vec4 cell_bounds[]; };
out vec2 v_uv;                // texture coordinates of the cell's pixel (layer-space, 0..1)
flat out int v_layer;         // the gait phase's layer
out vec3 v_view_position;     // of the quad point
flat out vec3 v_to_eye;       // unit, view space, from the walker's centre
flat out vec3 v_cell_to_eye;  // unit, view space: the direction the chosen cell was baked from
flat out mat3 v_local_to_view;
flat out float v_depth_scale;  // metres of baked depth range at this walker's scale
flat out float v_ahead;        // how far in front of the walker's centre the quad stands
flat out int v_walker;         // the instance: the walker's index in the batch (its palette under --quality high)
const float kTwoPi = 6.28318530718;
void main() {
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);  // (0,0) (1,0) (0,1) (1,1): a triangle strip
  vec3 center = vec3(a_x, a_y + u_cell.z * a_scale, a_z);
  vec3 to_eye = u_eye - center;
  float dist = max(length(to_eye), 1e-4);
  vec3 d = to_eye / dist;
  // The direction in the walker's own frame: heading h turns +Z to (sin h, 0, cos h), so undo it.
  float c = cos(a_heading), s = sin(a_heading);
  vec3 local = vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
  float azimuth = atan(local.x, local.z);  // 0 in front, towards +X positive
  int A = u_grid.y, E = u_grid.z;
  // Phase k of K at k / K: the nearest. Cross-fading the two neighbours was tried and rejected: where their
  // limbs differ it draws both at half coverage, a pale ghost leg beside each real one.
  v_layer = int(round(fract(a_phase) * float(u_grid.x))) % u_grid.x;
  int a = int(mod(round(azimuth / kTwoPi * float(A)), float(A)));
  float elevation = asin(clamp(local.y, -1.0, 1.0));
  int e = E > 1 ? clamp(int(round(elevation / max(u_max_elevation, 1e-4) * float(E - 1))), 0, E - 1) : 0;

  // The quad faces the eye, its up the world's up projected onto it, as the bake's orthographic camera was; it
  // covers only the part of the cell the walker covers (cell_bounds), so empty texels are not shaded.
  vec3 right = cross(vec3(0.0, 1.0, 0.0), d);
  right = length(right) > 1e-4 ? normalize(right) : vec3(1.0, 0.0, 0.0);
  vec3 up = cross(d, right);
  vec4 b = cell_bounds[(v_layer * E + e) * A + a];
  vec2 in_cell = mix(b.xy, b.zw, corner);
  // The quad stands in front of the walker, by the atlas's depth range, and shrinks by as much as the move would
  // enlarge it on screen: every baked depth is then behind the quad, so the fragment shader's depth only ever
  // grows (depth_greater) and the rasteriser may still reject hidden fragments before shading them.
  float ahead = min(u_depth_range * a_scale, 0.9 * dist);
  float shrink = (dist - ahead) / dist;
  vec3 p_world = center + ahead * d + shrink * ((in_cell.x - 0.5) * u_cell.x * a_scale * right +
                                                (in_cell.y - 0.5) * u_cell.y * a_scale * up);
  v_ahead = ahead;
  v_uv = (vec2(a, e) + in_cell) / vec2(A, E);
  vec4 view_position = u_view * vec4(p_world, 1.0);
  v_view_position = view_position.xyz;
  v_to_eye = normalize(mat3(u_view) * d);
  // The direction the cell was baked from, in view space: the image shows the walker from there, so the
  // view-dependent rim term is taken against it (see impostor.frag).
  float cell_azimuth = kTwoPi * float(a) / float(A);
  float cell_elevation = E > 1 ? u_max_elevation * float(e) / float(E - 1) : 0.0;
  vec3 cell_local = vec3(sin(cell_azimuth) * cos(cell_elevation), sin(cell_elevation), cos(cell_azimuth) * cos(cell_elevation));
  vec3 cell_world = vec3(c * cell_local.x + s * cell_local.z, cell_local.y, -s * cell_local.x + c * cell_local.z);
  v_cell_to_eye = normalize(mat3(u_view) * cell_world);
  // The walker's frame (heading about +Y) to view space, once per walker rather than per fragment.
  v_local_to_view = mat3(u_view) * mat3(vec3(c, 0.0, -s), vec3(0.0, 1.0, 0.0), vec3(s, 0.0, c));
  v_depth_scale = u_depth_range * a_scale;
  v_walker = gl_InstanceID;
  gl_Position = u_projection * view_position;
}
