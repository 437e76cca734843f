#version 450 core
// One triangle covering the viewport (3 vertices from gl_VertexID, no vertex buffer), for per-pixel passes over
// a framebuffer: render/render_target.cpp's nearest-sample depth.
void main() {
  const vec2 corner = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
