#version 450 core
// The material of bones, joints and bodies (skeleton.vert and body.vert feed it). Lighting is done in view space
// with a fixed "headlight" a little above and to the right of the viewer, so every orbit angle is lit; the rim
// term brightens silhouettes so thin bones stand out against the ground.
in vec3 v_normal;
in vec3 v_position;
in vec4 v_tint;  // a per-vertex colour blended over u_color by its alpha (the binding editor's weights)
uniform vec3 u_color;
out vec4 f_color;
const vec3 kToLight = normalize(vec3(0.35, 0.6, 0.7));
void main() {
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(-v_position);
  float diffuse = max(dot(n, kToLight), 0.0);
  float rim = pow(1.0 - clamp(dot(n, to_eye), 0.0, 1.0), 3.0);
  vec3 base = mix(u_color, v_tint.rgb, v_tint.a);
  f_color = vec4(base * (0.22 + 0.78 * diffuse) + vec3(0.18 * rim), 1.0);
}
