// The ground under --quality high: ground.frag's grid and fade, lit by shading.glsl's sun (with the walkers'
// shadows) and sky, then tone mapped like the bodies. The fade mixes display colours: the clear colour is one.
in vec3 v_world;
uniform vec3 u_ground_color;  // sRGB, as in RenderOptions
uniform vec3 u_clear_color;   // sRGB
uniform vec2 u_center;
uniform float u_half_size;
uniform float u_fade_start;  // m from u_center where the fade begins (ground_pass.h GroundExtent)
out vec4 f_color;
void main() {
  vec2 p = v_world.xz;
  vec2 w = max(fwidth(p), vec2(1e-5));
  vec2 g = abs(fract(p - 0.5) - 0.5) / w;
  float line = (1.0 - min(min(g.x, g.y), 1.0)) * (1.0 - smoothstep(0.1, 0.4, max(w.x, w.y)));
  vec3 albedo = srgb_to_linear(u_ground_color) * mix(1.0, 0.8, line);
  vec3 c = display(shade(v_world, vec3(0.0, 1.0, 0.0), albedo, 0.0, 1.0));
  float fade = smoothstep(u_fade_start, u_half_size, length(p - u_center));
  f_color = vec4(mix(c, u_clear_color, fade), 1.0);
}
