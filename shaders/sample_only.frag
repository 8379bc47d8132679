#version 450
// The sample-only micro-benchmark of `volcast bench`: K trilinear 3D-texture samples per pixel along a fixed
// direction and nothing else (no colormap, no compositing), so its rate is the device's raw sampling limit that
// the march's rate is stated against. The samples are summed into the output so none can be optimised away.
layout(std140, set = 0, binding = 0) uniform Params {
    vec4 start;     // xy: texture-space origin of pixel (0, 0); z: start depth; w: span of the image in texture space
    vec4 step;      // xyz: one step in texture space; w: samples per pixel (K)
    vec4 viewport;  // xy: target size in pixels
} params;
layout(set = 0, binding = 1) uniform texture3D volume_tex;
layout(set = 0, binding = 2) uniform sampler linear_smp;

layout(location = 0) out vec4 out_color;

void main() {
    vec2 uv = gl_FragCoord.xy / params.viewport.xy;
    vec3 p = vec3(params.start.xy + uv * params.start.w, params.start.z);
    int samples = int(params.step.w);
    float sum = 0.0;
    for (int k = 0; k < samples; k++) {
        sum += textureLod(sampler3D(volume_tex, linear_smp), p, 0.0).r;
        p += params.step.xyz;
    }
    out_color = vec4(sum / float(max(samples, 1)), 0.0, 0.0, 1.0);
}
