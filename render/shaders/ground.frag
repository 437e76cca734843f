#version 450 core
// A 1 m grid from the distance to the nearest integer line in screen-space units (fwidth), so lines stay about
// one pixel wide at any distance; they fade where a cell shrinks towards a pixel (which would alias into moire)
// and the whole quad fades into the clear colour towards its edge, hiding where it ends.
in vec3 v_world;
uniform mat4 u_view;
uniform vec3 u_ground_color;
uniform vec3 u_clear_color;
uniform vec2 u_center;
uniform float u_half_size;
uniform float u_fade_start;  // m from u_center where the fade begins (ground_pass.h GroundExtent)
out vec4 f_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
void main() {
  vec2 p = v_world.xz;
  vec2 w = max(fwidth(p), vec2(1e-5));
  vec2 g = abs(fract(p - 0.5) - 0.5) / w;
  float line = (1.0 - min(min(g.x, g.y), 1.0)) * (1.0 - smoothstep(0.1, 0.4, max(w.x, w.y)));
  float diffuse = max(dot(normalize(mat3(u_view) * vec3(0.0, 1.0, 0.0)), kToLight), 0.0);
  vec3 c = u_ground_color * (0.55 + 0.45 * diffuse);
  c = mix(c, 0.8 * c, line);
  float fade = smoothstep(u_fade_start, u_half_size, length(p - u_center));
  f_color = vec4(mix(c, u_clear_color, fade), 1.0);
}
