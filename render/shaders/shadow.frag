#version 450 core
// Depth only: the shadow map stores gl_FragCoord.z; there is no colour attachment to write.
void main() {}
