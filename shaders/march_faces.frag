#version 450
// Pass 3 of the entry/exit method: the ray segment comes from the two position targets.
#include "frame.glsl"
#include "march.glsl"

layout(set = 2, binding = 0) uniform texture2D entry_tex;
layout(set = 2, binding = 1) uniform texture2D exit_tex;
layout(set = 2, binding = 2) uniform sampler point_smp;

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 exit_pos = texelFetch(sampler2D(exit_tex, point_smp), px, 0);
    if (exit_pos.a == 0.0) {
        out_color = output_pixel(background_pixel(), 0u);
        return;
    }
    vec4 entry_pos = texelFetch(sampler2D(entry_tex, point_smp), px, 0);
    // No front face here but a back face: the near plane clipped the front face away (or the eye is inside),
    // so the ray starts on the near plane. This is what keeps a camera inside the volume free of holes.
    vec3 a = entry_pos.a > 0.0 ? entry_pos.xyz : near_point(gl_FragCoord.xy);
    out_color = march(a, exit_pos.xyz, gl_FragCoord.xy);
}
