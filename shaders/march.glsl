// The march shared by both ray setups: samples the segment a -> b (texture space) front to back.
// The rules are written out in RenderSettings (src/settings.rs); the CPU reference follows the same ones.
layout(set = 1, binding = 0) uniform texture3D volume_tex;
layout(set = 1, binding = 1) uniform sampler linear_smp;
layout(set = 1, binding = 2) uniform texture2D lut_tex;

// The colormap at c in [0,1]: linear interpolation between the table's 256 entries. Done by hand from two
// fetches because lavapipe filters RGBA8 textures with 8-bit weights, which costs up to 1/255 per sample.
vec3 colormap(float c) {
    float u = c * 255.0;
    int i0 = min(int(u), 254);
    vec3 a = texelFetch(sampler2D(lut_tex, linear_smp), ivec2(i0, 0), 0).rgb;
    vec3 b = texelFetch(sampler2D(lut_tex, linear_smp), ivec2(i0 + 1, 0), 0).rgb;
    return mix(a, b, u - float(i0));
}

// Pixel `frag`'s ray direction in texture space (see ray_forward in frame.glsl).
vec3 ray_direction(vec2 frag) {
    vec2 ndc = frag / frame.viewport.xy * 2.0 - 1.0;
    return frame.ray_forward.xyz + ndc.x * frame.ray_right.xyz + ndc.y * frame.ray_down.xyz;
}

// The point where pixel `frag`'s ray crosses the near plane, in texture space.
vec3 near_point(vec2 frag) {
    return frame.eye_tex.xyz + ray_direction(frag) * frame.ray_forward.w;
}

vec4 march(vec3 a, vec3 b) {
    vec3 d = b - a;
    float len = length(d * frame.extent.xyz);
    float h = frame.extent.w;
    float win_lo = frame.value_map.z;
    float win_span = frame.value_map.w - win_lo;
    // Opacity correction: step_alpha is the opacity of one voxel-length step.
    float const_alpha = 1.0 - pow(1.0 - frame.alpha.x, frame.alpha.y);
    bool multiplied = frame.alpha.w > 0.5;
    int max_steps = int(frame.viewport.z);
    vec3 color = vec3(0.0);
    float opacity = 0.0;
    for (int k = 0; k < max_steps; k++) {
        float t = (float(k) + 0.5) * h;
        if (t >= len) {
            break;
        }
        vec3 p = a + d * (t / len);
        float v = textureLod(sampler3D(volume_tex, linear_smp), p, 0.0).r * frame.value_map.x + frame.value_map.y;
        if (isnan(v) || v < win_lo || v > frame.value_map.w) {
            continue;
        }
        float c = (v - win_lo) / win_span;
        vec3 rgb = colormap(c);
        float alpha = const_alpha;
        if (multiplied) {
            alpha = 1.0 - pow(1.0 - c * frame.alpha.x, frame.alpha.y);
        }
        color += (1.0 - opacity) * alpha * rgb;
        opacity += (1.0 - opacity) * alpha;
        if (opacity >= frame.alpha.z) {
            break;
        }
    }
    return vec4(color + (1.0 - opacity) * frame.background.rgb, 1.0);
}
