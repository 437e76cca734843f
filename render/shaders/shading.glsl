#version 450 core
// The lighting of --quality high (render/lighting.h sets these uniforms), put in front of the fragment shaders
// that use it (shaded.frag, ground_shaded.frag) when their programs are linked. Colours are linear until
// display(): a sun with a shadow map, a sky-and-ground ambient, ACES tone mapping, then sRGB encoding, so the
// 8-bit image is what a display expects (the low-quality shaders write their colours as they are).
uniform vec3 u_sun_dir;     // towards the sun, world space, unit
uniform vec3 u_sun_color;   // linear irradiance of the sun on a surface facing it
uniform vec3 u_sky_color;   // ambient from above
uniform vec3 u_bounce_color;  // ambient from below (light the ground reflects)
uniform vec3 u_eye;         // camera position, world
uniform float u_exposure;
uniform mat4 u_light_matrix;  // world -> shadow map coordinates in [0, 1]^3
uniform sampler2DShadow u_shadow_map;
uniform float u_shadow_texel;   // one shadow map texel in map coordinates
uniform float u_shadow_world;   // one shadow map texel in metres (the normal offset's unit)
uniform int u_shadows;          // 0: no shadow map this frame

// Fraction of the sun that reaches `world`: four taps a texel apart, each a hardware 2x2 percentage-closer
// comparison with bilinear weights (the map's GL_LINEAR compare mode), so a 3x3-texel soft edge for four lookups;
// sixteen taps cost llvmpipe a third more on the ground pass for an edge one can hardly tell apart. The lookup is
// moved out along the normal by about a texel (normal-offset shadows: no acne on surfaces grazing the light, and
// no peter-panning of the feet off the ground the way a large constant depth bias would).
float sun_visibility(vec3 world, vec3 n) {
  if (u_shadows == 0) return 1.0;
  float facing = clamp(dot(n, u_sun_dir), 0.0, 1.0);
  vec3 p = world + n * (1.5 * u_shadow_world * (1.0 - 0.5 * facing));
  vec4 s = u_light_matrix * vec4(p, 1.0);
  if (s.x <= 0.0 || s.y <= 0.0 || s.x >= 1.0 || s.y >= 1.0 || s.z >= 1.0) return 1.0;
  float sum = 0.0;
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x)
      sum += texture(u_shadow_map, vec3(s.xy + (vec2(x, y) - 0.5) * u_shadow_texel, s.z - 0.0005));
  return 0.25 * sum;
}

vec3 ambient_light(vec3 n) { return mix(u_bounce_color, u_sky_color, 0.5 + 0.5 * n.y); }

// Narkowicz's fit of the ACES filmic curve: highlights roll off instead of clipping to white.
vec3 tone_map(vec3 c) {
  c *= u_exposure;
  return clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
}
vec3 linear_to_srgb(vec3 c) {
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec3 srgb_to_linear(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}
vec3 display(vec3 linear) { return linear_to_srgb(tone_map(linear)); }

// A surface lit by the sun and the sky. `skin` (0..1) turns on the skin response: wrap lighting, the light that
// scatters under the skin past the shadow terminator coming back reddish (the cheap stand-in for subsurface
// scattering), and a soft sheen; cloth (0) is Lambert with a faint highlight. `ao` darkens the ambient only.
vec3 shade(vec3 world, vec3 n, vec3 albedo, float skin, float ao) {
  vec3 to_eye = normalize(u_eye - world);
  float ndl = dot(n, u_sun_dir);
  float lambert = max(ndl, 0.0);
  const float wrap = 0.45;
  float wrapped = max((ndl + wrap) / (1.0 + wrap), 0.0);
  vec3 diffuse = vec3(lambert) + skin * (wrapped - lambert) * vec3(0.75, 0.30, 0.20);
  float visible = sun_visibility(world, n);
  vec3 half_vector = normalize(u_sun_dir + to_eye);
  float gloss = mix(12.0, 28.0, skin);
  float specular = mix(0.015, 0.08, skin) * pow(max(dot(n, half_vector), 0.0), gloss) * step(0.0, ndl);
  // Fresnel-like sky sheen at grazing angles keeps silhouettes readable against the ground.
  float rim = pow(1.0 - clamp(dot(n, to_eye), 0.0, 1.0), 4.0) * mix(0.06, 0.12, skin);
  vec3 light = u_sun_color * diffuse * visible + ambient_light(n) * ao;
  return albedo * light + u_sun_color * specular * visible + u_sky_color * rim * ao;
}
