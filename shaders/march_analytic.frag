#version 450
// The analytic ray setup as a fullscreen fragment pass (see analytic.glsl).
#include "frame.glsl"
#include "march.glsl"
#include "analytic.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    out_color = analytic_pixel(gl_FragCoord.xy);
}
