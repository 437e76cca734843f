#version 450 core
// The bodies' depth into the sun's shadow map (render/shadow_pass.cpp): the same three position arrays as
// body.vert, nothing else. Props cast through props_shaded.vert with the light's matrix.
layout(location = 0) in float a_px;
layout(location = 1) in float a_py;
layout(location = 2) in float a_pz;
uniform mat4 u_view_projection;
void main() { gl_Position = u_view_projection * vec4(a_px, a_py, a_pz, 1.0); }
