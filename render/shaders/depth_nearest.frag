#version 450 core
// The nearest of a pixel's multisampled depths (render/render_target.h read_depth): a pixel that any surface
// touches reads that surface's depth, so sort-last compositing (dist/composite.h) keeps the antialiased edge of
// the process that drew it rather than a bare ground pixel of another's.
uniform sampler2DMS u_depth;
uniform int u_samples;
void main() {
  const ivec2 p = ivec2(gl_FragCoord.xy);
  float d = 1.0;
  for (int i = 0; i < u_samples; ++i) d = min(d, texelFetch(u_depth, p, i).r);
  gl_FragDepth = d;
}
