#version 450
// The analytic ray setup as a compute pass (`--compute`): one invocation per pixel, 8x8 pixels per workgroup,
// writing the output image as a storage image. Same rays and march as march_analytic.frag (pixel centres at
// +0.5 like gl_FragCoord), so the two must give the same image.
#include "frame.glsl"
#include "march.glsl"
#include "analytic.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 2, binding = 0, rgba8) uniform writeonly image2D out_image;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= uint(frame.viewport.x) || px.y >= uint(frame.viewport.y)) {
        return;
    }
    imageStore(out_image, ivec2(px), analytic_pixel(vec2(px) + 0.5));
}
