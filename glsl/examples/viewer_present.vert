#version 450
// `translucent view`: one triangle that covers the window; the fragment shader reads the pixel
// it lands on, so no coordinates are passed.
void main() {
    vec2 corner = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
