// The march shared by both ray setups: samples the segment a -> b (texture space) and composites it by the
// rules in RenderSettings (src/scene/settings.rs); the CPU reference in tests/common follows the same rules.
layout(set = 1, binding = 0) uniform texture3D volume_tex;
layout(set = 1, binding = 1) uniform sampler linear_smp;
// The baked table (src/render/mod.rs LUT_ROWS): linear rgb + opacity per voxel step at 4096 values.
layout(std430, set = 1, binding = 2) readonly buffer Lut {
    vec4 entries[4096];
} lut;
// Its integral functions (src/transfer/preintegrate.rs): per entry the integrals over the value of extinction x colour
// (rgb) and of extinction (a), from 0 to the entry's value. A uniform buffer: on lavapipe its per-lane loads are
// branch-free, where a storage buffer's are a loop over the lanes.
layout(std140, set = 1, binding = 6) uniform Integrals {
    vec4 cumulative[4096];
} integrals;
layout(set = 1, binding = 3) uniform texture3D occupancy_tex;   // one texel per 8^3 brick: class and reach
#include "clip.glsl"

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

// Where the volume comes from (render::VolumeLayout). A 3D texture, filtered by the sampler; or, on CPU devices
// (lavapipe), a "corner texture": per voxel the four values of the 2x2 square its cell starts in x and y
// (neighbours clamped to the edge) in one texel, so a trilinear sample is two texelFetch (at z and z + 1) and
// seven lerps instead of eight filtered texel reads. lavapipe fetches 32-bit texels with one gather for all
// lanes. Both return what a UNORM or float texture returns (stored / 255, stored / 65535, or the float).
#if defined(CORNERS8) || defined(CORNERS16)
layout(set = 1, binding = 5) uniform utexture3D corner_tex;   // CORNERS8: R32_UINT bytes; CORNERS16: RG32_UINT halves

float sample_raw(vec3 p) {
    // Texel centres at (i + 0.5) / n, clamped to the edge, as CLAMP_TO_EDGE linear filtering does.
    vec3 q = clamp(p * frame.dims.xyz - 0.5, vec3(0.0), frame.dims.xyz - 1.0);
    ivec3 i = ivec3(q);
    vec3 f = q - vec3(i);
    ivec3 i1 = ivec3(i.xy, min(i.z + 1, int(frame.dims.z) - 1));
#if defined(CORNERS8)
    uint a = texelFetch(usampler3D(corner_tex, linear_smp), i, 0).r;
    uint b = texelFetch(usampler3D(corner_tex, linear_smp), i1, 0).r;
    vec4 lo = vec4(uvec4(a, a >> 8u, a >> 16u, a >> 24u) & uvec4(255u));
    vec4 hi = vec4(uvec4(b, b >> 8u, b >> 16u, b >> 24u) & uvec4(255u));
    const float unorm = 1.0 / 255.0;
#else
    uvec2 a = texelFetch(usampler3D(corner_tex, linear_smp), i, 0).rg;
    uvec2 b = texelFetch(usampler3D(corner_tex, linear_smp), i1, 0).rg;
    vec4 lo = vec4(uvec4(a.x, a.x >> 16u, a.y, a.y >> 16u) & uvec4(65535u));
    vec4 hi = vec4(uvec4(b.x, b.x >> 16u, b.y, b.y >> 16u) & uvec4(65535u));
    const float unorm = 1.0 / 65535.0;
#endif
    vec4 z = mix(lo, hi, f.z);
    vec2 y = mix(z.xy, z.zw, f.y);
    return mix(y.x, y.y, f.x) * unorm;
}
#else
float sample_raw(vec3 p) {
    return textureLod(sampler3D(volume_tex, linear_smp), p, 0.0).r;
}
#endif

// The normalised value, in [0, 1] by definition (rule 3): f32 rounding of the scale and bias must not push the
// data's maximum just above 1 (out of a window ending at 1) nor its minimum below 0. NaN stays NaN.
float sample_value(vec3 p) {
    float v = sample_raw(p) * frame.value_map.x + frame.value_map.y;
    return isnan(v) ? v : clamp(v, 0.0, 1.0);
}

bool visible(float v) {
    return !isnan(v) && v >= frame.value_map.z && v <= frame.value_map.w;
}

// The classification (row 0) at v, interpolated linearly between its two nearest entries. (A storage buffer:
// on lavapipe two loads cost less than two texel fetches, and a filtered fetch less than either.)
vec4 classify(float v) {
    float u = clamp(v, 0.0, 1.0) * 4095.0;
    int i0 = min(int(u), 4094);
    return mix(lut.entries[i0], lut.entries[i0 + 1], u - float(i0));
}

// The integral functions at v clamped into the window (interpolated linearly between entries) and, in `slope`,
// their slope over the entry holding it. Clamping applies the window exactly: the integral over [vp, v] of what
// lies inside it is the difference of the integrals at the clamped ends. NaN reads as 0 (its segments are dropped
// by segment_mean).
vec4 integral_at(float v, out vec4 slope) {
    float u = (isnan(v) ? 0.0 : clamp(v, frame.value_map.z, frame.value_map.w)) * 4095.0;
    int i0 = min(int(u), 4094);
    vec4 lo = integrals.cumulative[i0];
    vec4 hi = integrals.cumulative[i0 + 1];
    slope = (hi - lo) * 4095.0;
    return mix(lo, hi, u - float(i0));
}

// Pre-integration (src/transfer/preintegrate.rs, rule 6): the mean (extinction x colour, extinction) of the segment from
// value vp (integrals ip) to v (integrals iv, slope at v), as the quotient of differences; within one entry
// (preintegrate::SLOPE_BELOW) the slope instead, which f32 cancellation cannot spoil, if the segment's midpoint
// is inside the window. A NaN end drops the segment.
vec4 segment_mean(float vp, vec4 ip, float v, vec4 iv, vec4 slope) {
    float dv = v - vp;
    float mid = 0.5 * (v + vp);
    vec4 near = (mid >= frame.value_map.z && mid <= frame.value_map.w) ? slope : vec4(0.0);
    vec4 mean = abs(dv) >= 1.0 / 4095.0 ? (iv - ip) / dv : near;
    return (isnan(v) || isnan(vp)) ? vec4(0.0) : mean;
}

// Central differences one voxel apart: value change per voxel along each texture axis.
#if defined(GRADIENT_TEXTURE)
// Precomputed central differences on the voxel grid (RGBA16 SNORM, value per voxel x 2), filtered trilinearly:
// one 4-channel sample instead of six, at 8 bytes per voxel (RenderSettings::gradient_texture).
layout(set = 1, binding = 4) uniform texture3D gradient_tex;

vec3 gradient(vec3 p) {
    return 0.5 * textureLod(sampler3D(gradient_tex, linear_smp), p, 0.0).xyz;
}
#else
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
#endif

#if defined(LIGHT_VOLUME)
// Rule 9's light grid (src/render/light_volume.rs): x the light's transmittance, y the ambient occlusion.
layout(set = 1, binding = 7) uniform texture3D light_tex;
#endif

// Blinn-Phong (rule 5), two-sided, at texture position p: `view` is the unit direction towards the eye, in world
// space; the light is frame.light_dir, or a headlight along `view`. With the light grid (rule 9) the light is
// shadowed by T and the ambient term occluded by O.
vec3 shade(vec3 rgb, vec3 g, vec3 view, vec3 p) {
    vec3 gw = mat3(frame.gradient_to_world) * g;
    float len = length(gw);
    if (len < 1e-8) {
        return rgb;
    }
    vec3 n = gw / len;
    n = dot(n, view) < 0.0 ? -n : n;
    vec3 l = frame.light_dir.w > 0.5 ? frame.light_dir.xyz : view;
    float ndl = max(dot(n, l), 0.0);
    vec3 half_sum = l + view;
    float hl = length(half_sum);
    float ndh = hl > 1e-6 ? max(dot(n, half_sum / hl), 0.0) : 0.0;
    vec4 s = frame.shading;
    float spec = ndl > 0.0 ? pow(ndh, s.w) : 0.0;
    vec3 c = frame.light_color.rgb;
    float ambient = s.x;
#if defined(LIGHT_VOLUME)
    uint grid = uint(frame.light_grid.w);
    if ((grid & 1u) != 0u) {
        c *= textureLod(sampler3D(light_tex, linear_smp), p + frame.light_grid.xyz, 0.0).x;
    }
    if ((grid & 2u) != 0u) {
        ambient *= textureLod(sampler3D(light_tex, linear_smp), p, 0.0).y;
    }
#endif
    return rgb * (ambient + s.y * ndl * c) + s.z * spec * c;
}

// Empty-space skipping and brick strides (rule 2). The ray is walked span by span: `brick_span` looks up the 8^3
// brick holding the sample at `t` and returns the index of the first sample past the cube of bricks around it
// that share its class (x) and that class (y). The march leaps over empty bricks without leaving its sample grid,
// and in the others takes the samples of the class's stride without further lookups. With lookups off (no
// skipping, no strides), the whole ray is one span at stride 1.
// What brick_span needs of the ray, computed once per pixel (lavapipe's LLVM passes hoist nothing out of loops).
struct BrickWalk {
    vec3 a;
    vec3 dir;
    // 1 / dir, with zero components taking the far side (a huge, ignored exit instead of 0/0).
    vec3 inv_dir;
    // Per axis, whether the ray leaves a cube of bricks through its upper face.
    bvec3 up;
    vec3 inv_brick;
    float inv_h;
    ivec3 bricks;
};

BrickWalk brick_walk(vec3 a, vec3 dir, float h, ivec3 bricks) {
    vec3 safe = mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
    return BrickWalk(a, dir, 1.0 / safe, greaterThanEqual(dir, vec3(0.0)), 1.0 / frame.brick.xyz, 1.0 / h, bricks);
}

ivec2 brick_span(BrickWalk w, float t, float h, float o) {
    if (frame.mode_params.z < 0.5) {
        return ivec2(2147483647, 3);
    }
    vec3 p = w.a + w.dir * t;
    ivec3 b = clamp(ivec3(floor(p * w.inv_brick)), ivec3(0), w.bricks - 1);
    // skip::encode_reach: bits 0-1 the class (0 empty; 1, 2, 3 strides 4, 2, 1), bits 2-7 the reach r: every
    // brick within r bricks has the same class, so the ray is walked to where it leaves that cube of bricks as
    // one span.
    int code = int(texelFetch(sampler3D(occupancy_tex, linear_smp), b, 0).r * 255.0 + 0.5);
    int level = code & 3;
    int reach = code >> 2;
    vec3 lo = vec3(b - ivec3(reach)) * frame.brick.xyz;
    vec3 hi = vec3(b + ivec3(reach + 1)) * frame.brick.xyz;
    vec3 exits = (mix(lo, hi, w.up) - w.a) * w.inv_dir;
    // A little short of the exit: rounding must never leap over a sample of the next brick.
    float t_exit = min(exits.x, min(exits.y, exits.z)) - 1e-4 * h;
    return ivec2(int(ceil(t_exit * w.inv_h - o)), level);
}

// The walk of the projection and isosurface families, one sample index per iteration (see the emission walk
// below): `k` is the next sample index and [.., stop) the span being walked, looked up when k reaches it. Returns
// 0 where the ray ends, 1 after a leap (no sample this iteration), 2 with sample k's position in `t` (k then
// advanced past it).
int walk_next(BrickWalk walk, inout int k, inout int span_end, inout int stop, float h, float o, float len,
              int max_steps, out float t) {
    t = 0.0;
    if (k >= stop) {
        k = span_end;
        float t0 = (float(k) + o) * h;
        if (k >= max_steps || t0 >= len) {
            return 0;
        }
        ivec2 span = brick_span(walk, t0, h, o);
        span_end = max(span.x, k + 1);
        // Leapt over, or walked sample by sample.
        stop = span.y == 0 ? k : span_end;
        if (span.y == 0) {
            return 1;
        }
    }
    t = (float(k) + o) * h;
    if (t >= len) {
        return 0;
    }
    k += 1;
    return 2;
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

// The pixel's output: its colour, or with `RenderSettings::count_samples` the number of sample positions the
// march visited (gradient and bisection samples not counted), as a 24-bit integer in the R, G, B bytes.
vec4 output_pixel(vec4 colour, uint taken) {
    if (frame.viewport.w > 0.5) {
        return vec4(vec3(uvec3(taken, taken >> 8u, taken >> 16u) & uvec3(255u)), 255.0) / 255.0;
    }
    return colour;
}

// A pre-integrated segment (rule 6) over `seg_steps` voxel lengths, from its mean (extinction x colour,
// extinction): colour (not premultiplied) and opacity. With shading, lit by the gradient at its midpoint `p`.
vec4 segment_sample(vec4 mean, float seg_steps, vec3 p, vec3 light, bool density_model) {
    float sigma = max(mean.a, 0.0);
#if defined(SHADED)
    // A transparent segment adds nothing; leaving here also skips its six gradient samples.
    if (sigma <= 0.0) {
        return vec4(0.0);
    }
    vec3 rgb = clamp(mean.rgb / sigma, 0.0, 1.0);
    vec3 g = gradient(p);
    float grad_ref = frame.voxel_world.w;
    if (grad_ref > 0.0) {
        sigma *= min(1.0, length(g) / grad_ref);
    }
    if (frame.flags.w != 0u) {
        rgb = shade(rgb, g, light, p);
    }
#else
    vec3 rgb = sigma > 0.0 ? clamp(mean.rgb / sigma, 0.0, 1.0) : vec3(0.0);
#endif
    float alpha = density_model ? min(1.0, sigma * seg_steps) : 1.0 - exp(-sigma * seg_steps);
    return vec4(rgb, alpha);
}

// The segment from the previous point (t_prev, its value v_prev and integrals i_prev) to the point at `t` on
// the ray a + dir * t: samples the value there and returns the segment's colour and opacity (segment_sample);
// the point at `t` becomes the previous one.
vec4 segment_to(vec3 a, vec3 dir, float t, float h, vec3 light, bool density_model,
                inout float t_prev, inout float v_prev, inout vec4 i_prev) {
    float v = sample_value(a + dir * t);
    vec4 slope;
    vec4 iv = integral_at(v, slope);
    vec4 c = segment_sample(segment_mean(v_prev, i_prev, v, iv, slope), frame.alpha.y * (t - t_prev) / h,
                            a + dir * (0.5 * (t + t_prev)), light, density_model);
    t_prev = t;
    v_prev = v;
    i_prev = iv;
    return c;
}

// The march is compiled in variants (build.rs defines one of FAMILY_PROJECTION / FAMILY_ISOSURFACE, or neither
// for emission/density, and SHADED), because lavapipe executes an `if` holding texture samples at full cost
// even when no pixel takes it: unused shading code made the plain march 4x slower.
vec4 march(vec3 a, vec3 b, vec2 frag) {
    // Rule 10: where the clipping plane starts the ray, iso-surfaces are cut open, not capped (see below).
    bool cut_start;
    if (!clip_segment(a, b, cut_start)) {
        return output_pixel(background_pixel(), 0u);
    }
    vec3 d = b - a;
    // World length and direction: the placement may scale, rotate, shear or mirror the box.
    vec3 d_world = mat3(frame.tex_to_world) * d;
    float len = length(d_world);
    float h = frame.extent.w;
    float o = frame.flags.y != 0u ? jitter_offset(uvec2(frag), frame.flags.z) : 0.5;
    uint mode = frame.flags.x;
    vec3 light = -normalize(d_world);
    int max_steps = int(frame.viewport.z);
    vec3 dir = d / len;
    BrickWalk walk = brick_walk(a, dir, h, textureSize(sampler3D(occupancy_tex, linear_smp), 0));
    uint taken = 0u;

#if defined(FAMILY_PROJECTION)
    float m = mode == MODE_MIP ? -1e30 : 1e30;
    float sum = 0.0;
    float count = 0.0;
    int k = 0;
    int span_end = 0;
    int stop = 0;
    for (;;) {
        float t;
        int step = walk_next(walk, k, span_end, stop, h, o, len, max_steps, t);
        if (step == 0) {
            break;
        }
        if (step == 1) {
            continue;
        }
        taken += 1u;
        float v = sample_value(a + dir * t);
        if (!visible(v)) {
            continue;
        }
        m = mode == MODE_MIP ? max(m, v) : min(m, v);
        sum += v;
        count += 1.0;
    }
    if (count == 0.0) {
        return output_pixel(background_pixel(), taken);
    }
    return output_pixel(finish(classify(mode == MODE_AVERAGE ? sum / count : m).rgb, 1.0), taken);
#elif defined(FAMILY_ISOSURFACE)
    // Rule 7: the surfaces (by value) where the samples cross them, composited front to back. A NaN sample, and a
    // sample leapt over (its brick holds nothing at or above the lowest surface), count as below every surface.
    int count = int(frame.mode_params.w);
    vec3 color = vec3(0.0);
    float opacity = 0.0;
    float v_prev = -1e30;
    float t_prev = 0.0;
    bool has_prev = false;
    int k = 0;
    int span_end = 0;
    int stop = 0;
    for (;;) {
        float t;
        int step = walk_next(walk, k, span_end, stop, h, o, len, max_steps, t);
        if (step == 0) {
            break;
        }
        if (step == 1) {
            // The samples leapt over are below every surface; the bisection may start at the last of them.
            v_prev = -1e30;
            t_prev = (float(k) - 1.0 + o) * h;
            has_prev = k > 0;
            continue;
        }
        taken += 1u;
        float v = sample_value(a + dir * t);
        v = isnan(v) ? -1e30 : v;
        // The first sample meets every surface at or below its value, highest first (the innermost material where
        // the ray starts: a cut face shows what is there) -- except on the clipping plane, which cuts surfaces open:
        // there the first sample meets none and only starts the next crossing's interval.
        bool rising = has_prev && v >= v_prev;
        int meets = (cut_start && !has_prev) ? 0 : count;
        for (int j = 0; j < meets; j++) {
            int i = rising ? j : count - 1 - j;
            float iso = frame.iso_values[i];
            bool below_before = v_prev < iso;
            if (below_before == (v < iso)) {
                continue;
            }
            float t_hit = t;
            if (has_prev) {
                float lo = t_prev;
                float hi = t;
                for (int b = 0; b < 8; b++) {
                    float mid = 0.5 * (lo + hi);
                    float vm = sample_value(a + dir * mid);
                    bool below = isnan(vm) || vm < iso;
                    if (below == below_before) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                t_hit = 0.5 * (lo + hi);
            }
            vec4 material = frame.iso_colors[i];
            vec3 rgb = material.r < 0.0 ? classify(clamp(iso, frame.value_map.z, frame.value_map.w)).rgb : material.rgb;
            vec3 p_hit = a + dir * t_hit;
            vec3 lit = shade(rgb, gradient(p_hit), light, p_hit);
            color += (1.0 - opacity) * material.a * lit;
            opacity += (1.0 - opacity) * material.a;
            if (opacity >= frame.alpha.z) {
                break;
            }
        }
        if (opacity >= frame.alpha.z) {
            break;
        }
        v_prev = v;
        t_prev = t;
        has_prev = true;
    }
    return output_pixel(finish(color, opacity), taken);
#else
    // Emission-absorption and the density-factor model, pre-integrated (rule 6): the ray from its start to its
    // end is composited segment by segment between consecutive points: the start, the samples, the end.
    vec3 color = vec3(0.0);
    float opacity = 0.0;
    bool density_model = mode == MODE_DENSITY;
    bool reached_end = false;
    bool done = false;
    // The segment's start (rule 6): the ray's start, then each point taken.
    float t_prev = 0.0;
    float v_prev = sample_value(a);
    vec4 unused;
    vec4 i_prev = integral_at(v_prev, unused);
    // Whether the last span walked held something (its points were taken), or was leapt over.
    bool walked = true;
    // One sample per iteration (lavapipe runs a loop until its slowest lane ends, and nested loops at the pace of
    // the slowest lane of each): the span [k, stop) being walked at `stride`, looked up when k reaches `stop`.
    int k = 0;
    int span_end = 0;
    int stop = 0;
    int stride = 1;
    bool resample = false;
    int resample_at = 0;
    for (;;) {
        if (k >= stop && !resample) {
            k = span_end;
            if (k >= max_steps) {
                break;
            }
            float t0 = (float(k) + o) * h;
            if (t0 >= len) {
                reached_end = true;
                break;
            }
            ivec2 span = brick_span(walk, t0, h, o);
            span_end = max(span.x, k + 1);
            // Leaving bricks that hold something, the segment from the last point there to the first sample beyond
            // still spans the values between theirs: that one sample is taken before the leap.
            bool exiting = span.y == 0 && walked;
            if (span.y == 0 && !exiting) {
                stop = k;
                continue;
            }
            // After a leap, the segment starts at the last sample leapt over (nothing there is visible).
            resample = !walked && k > 0;
            resample_at = k - 1;
            walked = !exiting;
            // The span's stride s (rule 2): the samples whose index is a multiple of s.
            stride = exiting ? 1 : 1 << (3 - span.y);
            stop = exiting ? k + 1 : span_end;
            k = (k + stride - 1) & ~(stride - 1);
            if (k >= stop && !resample) {
                continue;
            }
        }
        int j = resample ? resample_at : k;
        float t = (float(j) + o) * h;
        if (!resample && t >= len) {
            reached_end = true;
            break;
        }
        float v = sample_value(a + dir * t);
        vec4 slope;
        vec4 iv = integral_at(v, slope);
        if (resample) {
            resample = false;
        } else {
            taken += 1u;
            vec4 c = segment_sample(segment_mean(v_prev, i_prev, v, iv, slope), frame.alpha.y * (t - t_prev) / h,
                                    a + dir * (0.5 * (t + t_prev)), light, density_model);
            color += (1.0 - opacity) * c.a * c.rgb;
            opacity += (1.0 - opacity) * c.a;
            k = j + stride;
        }
        t_prev = t;
        v_prev = v;
        i_prev = iv;
        if (opacity >= frame.alpha.z) {
            done = true;
            break;
        }
    }
    // The last segment, from the last point to the ray's end, where the march got there through bricks that hold
    // something (not by early termination; past a leap everything left is invisible).
    if (reached_end && walked && opacity < frame.alpha.z) {
        vec4 c = segment_to(a, dir, len, h, light, density_model, t_prev, v_prev, i_prev);
        color += (1.0 - opacity) * c.a * c.rgb;
        opacity += (1.0 - opacity) * c.a;
    }
    return output_pixel(finish(color, opacity), taken);
#endif
}
