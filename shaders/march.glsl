// The march shared by both ray setups: samples the segment a -> b (texture space) and composites it by the
// rules in RenderSettings (src/settings.rs); the CPU reference in tests/common follows the same rules.
layout(set = 1, binding = 0) uniform texture3D volume_tex;
layout(set = 1, binding = 1) uniform sampler linear_smp;
layout(set = 1, binding = 2) uniform texture2D lut_tex;   // 4096 x 1, RGBA32F: linear rgb + opacity per voxel step

const uint MODE_EMISSION = 0u;
const uint MODE_MIP = 1u;
const uint MODE_MINIP = 2u;
const uint MODE_AVERAGE = 3u;
const uint MODE_ISOSURFACE = 4u;
const uint MODE_DENSITY = 5u;

vec2 pixel_ndc(vec2 frag) {
    return frag / frame.viewport.xy * 2.0 - 1.0;
}

// Pixel `frag`'s ray in texture space (see frame.glsl).
vec3 ray_origin(vec2 frag) {
    vec2 ndc = pixel_ndc(frag);
    return frame.eye_tex.xyz + ndc.x * frame.origin_dx.xyz + ndc.y * frame.origin_dy.xyz;
}

vec3 ray_direction(vec2 frag) {
    vec2 ndc = pixel_ndc(frag);
    return frame.ray_forward.xyz + ndc.x * frame.ray_right.xyz + ndc.y * frame.ray_down.xyz;
}

// The point where pixel `frag`'s ray crosses the near plane, in texture space.
vec3 near_point(vec2 frag) {
    return ray_origin(frag) + ray_direction(frag) * frame.ray_forward.w;
}

float sample_value(vec3 p) {
    return textureLod(sampler3D(volume_tex, linear_smp), p, 0.0).r * frame.value_map.x + frame.value_map.y;
}

bool visible(float v) {
    return !isnan(v) && v >= frame.value_map.z && v <= frame.value_map.w;
}

// The baked table at v, interpolated by hand from two fetches (lavapipe filters with reduced precision).
vec4 classify(float v) {
    float u = clamp(v, 0.0, 1.0) * 4095.0;
    int i0 = min(int(u), 4094);
    vec4 a = texelFetch(sampler2D(lut_tex, linear_smp), ivec2(i0, 0), 0);
    vec4 b = texelFetch(sampler2D(lut_tex, linear_smp), ivec2(i0 + 1, 0), 0);
    return mix(a, b, u - float(i0));
}

// Central differences one voxel apart: value change per voxel along each texture axis.
vec3 gradient(vec3 p) {
    vec3 d = frame.texel.xyz;
    vec3 g = 0.5 * vec3(
        sample_value(p + vec3(d.x, 0.0, 0.0)) - sample_value(p - vec3(d.x, 0.0, 0.0)),
        sample_value(p + vec3(0.0, d.y, 0.0)) - sample_value(p - vec3(0.0, d.y, 0.0)),
        sample_value(p + vec3(0.0, 0.0, d.z)) - sample_value(p - vec3(0.0, 0.0, d.z)));
    if (any(isnan(g))) {
        g = vec3(0.0);
    }
    return g;
}

// Blinn-Phong with a headlight (two-sided): `light` is the unit direction towards the eye, in world space.
vec3 shade(vec3 rgb, vec3 g, vec3 light) {
    vec3 gw = g / frame.voxel_world.xyz;
    float len = length(gw);
    if (len < 1e-8) {
        return rgb;
    }
    float ndl = abs(dot(gw / len, light));
    vec4 s = frame.shading;
    return rgb * (s.x + s.y * ndl) + vec3(s.z * pow(ndl, s.w));
}

// The per-pixel start offset of jittered rays: must equal settings::jitter_offset.
float jitter_offset(uvec2 px, uint seed) {
    uint v = (px.x * 1973u + px.y * 9277u + seed * 26699u) | 1u;
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    uint h = (word >> 22u) ^ word;
    return float(h >> 8u) * (1.0 / 16777216.0);
}

vec3 linear_to_srgb(vec3 c) {
    vec3 lo = c * 12.92;
    vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(hi, lo, lessThanEqual(c, vec3(0.0031308)));
}

// Output rule: composite over the background in linear light, encode once.
vec4 finish(vec3 color, float opacity) {
    vec3 rgb = clamp(color + (1.0 - opacity) * frame.background.rgb, 0.0, 1.0);
    return vec4(linear_to_srgb(rgb), 1.0);
}

vec4 background_pixel() {
    return finish(vec3(0.0), 0.0);
}

vec4 march(vec3 a, vec3 b, vec2 frag) {
    vec3 d = b - a;
    float len = length(d * frame.extent.xyz);
    float h = frame.extent.w;
    float o = frame.flags.y != 0u ? jitter_offset(uvec2(frag), frame.flags.z) : 0.5;
    uint mode = frame.flags.x;
    bool shading_on = frame.flags.w != 0u;
    float grad_ref = frame.voxel_world.w;
    vec3 light = -normalize(d * frame.extent.xyz);
    int max_steps = int(frame.viewport.z);
    float step_length = frame.alpha.y;

    if (mode == MODE_MIP || mode == MODE_MINIP || mode == MODE_AVERAGE) {
        float m = mode == MODE_MIP ? -1e30 : 1e30;
        float sum = 0.0;
        float count = 0.0;
        for (int k = 0; k < max_steps; k++) {
            float t = (float(k) + o) * h;
            if (t >= len) {
                break;
            }
            float v = sample_value(a + d * (t / len));
            if (!visible(v)) {
                continue;
            }
            m = mode == MODE_MIP ? max(m, v) : min(m, v);
            sum += v;
            count += 1.0;
        }
        if (count == 0.0) {
            return background_pixel();
        }
        return finish(classify(mode == MODE_AVERAGE ? sum / count : m).rgb, 1.0);
    }

    if (mode == MODE_ISOSURFACE) {
        float iso = frame.mode_params.x;
        float prev_t = 0.0;
        for (int k = 0; k < max_steps; k++) {
            float t = (float(k) + o) * h;
            if (t >= len) {
                break;
            }
            float v = sample_value(a + d * (t / len));
            if (!isnan(v) && v >= iso) {
                float t_hit = t;
                if (k > 0) {
                    float lo = prev_t;
                    float hi = t;
                    for (int i = 0; i < 8; i++) {
                        float mid = 0.5 * (lo + hi);
                        float vm = sample_value(a + d * (mid / len));
                        if (!isnan(vm) && vm >= iso) {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    t_hit = 0.5 * (lo + hi);
                }
                vec3 p = a + d * (t_hit / len);
                return finish(shade(classify(iso).rgb, gradient(p), light), 1.0);
            }
            prev_t = t;
        }
        return background_pixel();
    }

    // Emission-absorption and the density-factor model.
    vec3 color = vec3(0.0);
    float opacity = 0.0;
    for (int k = 0; k < max_steps; k++) {
        float t = (float(k) + o) * h;
        if (t >= len) {
            break;
        }
        vec3 p = a + d * (t / len);
        float v = sample_value(p);
        if (!visible(v)) {
            continue;
        }
        vec4 c = classify(v);
        float alpha = c.a;
        // A transparent sample adds nothing; skipping it also skips its six gradient samples.
        if (alpha <= 0.0) {
            continue;
        }
        vec3 rgb = c.rgb;
        if (shading_on || grad_ref > 0.0) {
            vec3 g = gradient(p);
            if (grad_ref > 0.0) {
                alpha *= min(1.0, length(g) / grad_ref);
            }
            if (shading_on) {
                rgb = shade(rgb, g, light);
            }
        }
        float a_step = mode == MODE_DENSITY
            ? min(1.0, alpha * frame.mode_params.y * step_length)
            : 1.0 - pow(1.0 - alpha, step_length);
        color += (1.0 - opacity) * a_step * rgb;
        opacity += (1.0 - opacity) * a_step;
        if (opacity >= frame.alpha.z) {
            break;
        }
    }
    return finish(color, opacity);
}
