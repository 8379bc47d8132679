#version 450
// Passes 1 and 2: the slab box's 12 triangles, outward-facing counter-clockwise, generated from the vertex index
// (no vertex buffer). The entry pipeline culls back faces, the exit pipeline front faces.
#include "frame.glsl"

layout(location = 0) out vec3 tex_pos;

const int CUBE_INDEX[36] = int[36](
    0, 4, 2, 2, 4, 6,   // -x
    1, 3, 5, 3, 7, 5,   // +x
    0, 1, 4, 1, 5, 4,   // -y
    2, 6, 3, 3, 6, 7,   // +y
    0, 2, 1, 1, 2, 3,   // -z
    4, 5, 6, 5, 7, 6    // +z
);

void main() {
    int corner = CUBE_INDEX[gl_VertexIndex];
    vec3 unit = vec3(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1));
    vec3 p = mix(frame.slab_lo.xyz, frame.slab_hi.xyz, unit);
    tex_pos = p;
    gl_Position = frame.tex_to_clip * vec4(p, 1.0);
}
