// The march shared by every ray setup: samples the segment a -> b (texture space) and composites it by the rules in
// RenderSettings (src/scene/settings.rs); the CPU reference in tests/common follows the same rules. Every family
// walks the ray with walk.glsl and differs only in what it does with the samples.
//
// It is compiled in variants (src/render/march_key.rs names them; build.rs defines one of FAMILY_EMISSION,
// FAMILY_PROJECTION or FAMILY_ISOSURFACE, and SHADED, GRADIENT_TEXTURE, LIGHT_VOLUME, CORNERS8/CORNERS16),
// because lavapipe executes an `if` holding texture samples at full cost even when no pixel takes it: unused
// shading code made the plain march 4x slower.
#include "volume.glsl"
#include "clip.glsl"
#include "shade.glsl"
// Emission and density composite segments between points (rule 6): only their walk takes strides and yields the
// exiting sample and the resample.
#if defined(FAMILY_EMISSION)
#define WALK_SEGMENTS true
#else
#define WALK_SEGMENTS false
#endif
#include "walk.glsl"
#if defined(LAYERS)
#include "layers.glsl"
#endif

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
    // Rule 11's partial output: nothing (a share adds nothing where its ray misses the volume).
    if (frame.part_origin.w > 0.5) {
        return vec4(0.0);
    }
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

// Rule 11 (src/distributed): whether this process composites what ends at p -- a sample, or the segment or
// crossing ending there. The ranks' boxes split space (half-open, outer sides open), so every sample and segment of
// a ray is composited by exactly one rank, on the one sample grid of the whole ray. A whole volume owns everything.
bool owned(vec3 p) {
    return all(greaterThanEqual(p, frame.part_lo.xyz)) && all(lessThan(p, frame.part_hi.xyz));
}

// Rule 11's partial output: a rank's share before the compositor merges the shares -- premultiplied linear colour and
// opacity, not yet over the background (emission, density, surfaces).
vec4 share_or_finish(vec3 color, float opacity, uint taken) {
    if (frame.part_origin.w > 0.5) {
        return vec4(color, opacity);
    }
    return output_pixel(finish(color, opacity), taken);
}

// Rule 7's front-to-back step, for segments and surfaces alike: `rgb` at opacity `alpha` behind what the ray has
// gathered so far.
void composite(inout vec3 color, inout float opacity, vec3 rgb, float alpha) {
    color += (1.0 - opacity) * alpha * rgb;
    opacity += (1.0 - opacity) * alpha;
}

#if defined(FAMILY_PROJECTION)
// Rule 7 for MIP, MinIP and average: the visible samples' maximum, minimum or mean, coloured by the classification.
vec4 march_projection(WalkRay ray) {
    uint mode = frame.flags.x;
    float m = mode == MODE_MIP ? -1e30 : 1e30;
    float sum = 0.0;
    float count = 0.0;
    uint taken = 0u;
    Walk w = walk_start();
    for (;;) {
        float t;
        int step = walk_step(ray, w, t);
        if (step == WALK_END) {
            break;
        }
        if (step != WALK_SAMPLE) {
            continue;
        }
        taken += 1u;
        vec3 p = ray.a + ray.dir * t;
        float v = value_in(w.brick, p);
        if (!visible(v) || !owned(p)) {
            continue;
        }
        m = mode == MODE_MIP ? max(m, v) : min(m, v);
        sum += v;
        count += 1.0;
    }
    // Rule 11's partial output: the share's extreme (or sum) and its count, reduced across ranks before classifying.
    if (frame.part_origin.w > 0.5) {
        return vec4(mode == MODE_AVERAGE ? sum : m, count, 0.0, 0.0);
    }
    if (count == 0.0) {
        return output_pixel(background_pixel(), taken);
    }
    return output_pixel(finish(classify(mode == MODE_AVERAGE ? sum / count : m).rgb, 1.0), taken);
}
#elif defined(FAMILY_ISOSURFACE)
// Rule 7: the surfaces (by value) where the samples cross them, composited front to back. A NaN sample, and a
// sample leapt over (its brick holds nothing at or above the lowest surface), count as below every surface.
vec4 march_isosurface(WalkRay ray, vec3 light, bool cut_start) {
    int count = int(frame.mode_params.w);
    vec3 color = vec3(0.0);
    float opacity = 0.0;
    float v_prev = -1e30;
    float t_prev = 0.0;
    bool has_prev = false;
    uint taken = 0u;
    Walk w = walk_start();
    for (;;) {
        float t;
        int step = walk_step(ray, w, t);
        if (step == WALK_END) {
            break;
        }
        if (step == WALK_LEAP) {
            // The samples leapt over are below every surface; the bisection may start at the last of them.
            v_prev = -1e30;
            t_prev = (float(w.k) - 1.0 + ray.o) * ray.h;
            has_prev = w.k > 0;
            continue;
        }
        if (step != WALK_SAMPLE) {
            continue;
        }
        taken += 1u;
        float v = value_in(w.brick, ray.a + ray.dir * t);
        v = isnan(v) ? -1e30 : v;
        // The first sample meets every surface at or below its value, highest first (the innermost material where
        // the ray starts: a cut face shows what is there) -- except on the clipping plane, which cuts surfaces open:
        // there the first sample meets none and only starts the next crossing's interval.
        bool rising = has_prev && v >= v_prev;
        // Rule 11: a crossing belongs to the rank owning the sample that ends its interval.
        int meets = ((cut_start && !has_prev) || !owned(ray.a + ray.dir * t)) ? 0 : count;
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
                    float vm = sample_value(ray.a + ray.dir * mid);
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
            vec3 p_hit = ray.a + ray.dir * t_hit;
            composite(color, opacity, shade(rgb, gradient(p_hit), light, p_hit, 1.0), material.a);
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
    return share_or_finish(color, opacity, taken);
}
#else // FAMILY_EMISSION
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
        rgb = shade(rgb, g, light, p, gradient_fade(g));
    }
#else
    vec3 rgb = sigma > 0.0 ? clamp(mean.rgb / sigma, 0.0, 1.0) : vec3(0.0);
#endif
    float alpha = density_model ? min(1.0, sigma * seg_steps) : 1.0 - exp(-sigma * seg_steps);
    return vec4(rgb, alpha);
}

// The segment from the previous point (t_prev, its value v_prev and integrals i_prev) to the point at `t` on the
// ray: samples the value there (in brick b, which holds it) and returns the segment's colour and opacity
// (segment_sample; its midpoint's gradient is looked up where the midpoint lies); the point at `t` becomes the
// previous one.
vec4 segment_to(WalkRay ray, Brick b, float t, vec3 light, bool density_model, inout float t_prev, inout float v_prev,
                inout vec4 i_prev) {
    float v = value_in(b, ray.a + ray.dir * t);
    vec4 slope;
    vec4 iv = integral_at(v, slope);
    vec4 c = segment_sample(segment_mean(v_prev, i_prev, v, iv, slope), frame.alpha.y * (t - t_prev) / ray.h,
                            ray.a + ray.dir * (0.5 * (t + t_prev)), light, density_model);
    t_prev = t;
    v_prev = v;
    i_prev = iv;
    return c;
}

// What the emission march carries from point to point: the composite so far, the segment's start (rule 6: the
// ray's start, then each point taken) and the samples composited.
struct Absorb {
    vec3 color;
    float opacity;
    float t_prev;
    float v_prev;
    vec4 i_prev;
    uint taken;
};

// The march's points before `t_stop`, each segment composited; with `with_layers` (a constant at each call, so a
// loop holds the layers' code or not at all), rule 13's layers mixed in at each sample. True where the ray is
// done (its end or early termination); false at the first point at or past t_stop, which the walk yields again.
bool absorb_until(WalkRay ray, inout Walk walk, inout Absorb m, vec3 light, float t_stop, bool with_layers) {
    bool density_model = frame.flags.x == MODE_DENSITY;
    bool done = false;
    // Plain locals for the loop: naga 30's SPIR-V writer panics on a struct's fields passed as inout arguments.
    vec3 color = m.color;
    float opacity = m.opacity;
    float t_prev = m.t_prev;
    float v_prev = m.v_prev;
    vec4 i_prev = m.i_prev;
    uint taken = m.taken;
    Walk w = walk;
    for (;;) {
        Walk before = w;
        float t;
        int step = walk_step(ray, w, t);
        if (step == WALK_END) {
            done = true;
            break;
        }
        if (step != WALK_SAMPLE && step != WALK_RESAMPLE) {
            continue;
        }
        if (t >= t_stop) {
            w = before;
            break;
        }
        // A resample only starts the next segment: the segment to it is not composited.
        vec4 c = segment_to(ray, w.brick, t, light, density_model, t_prev, v_prev, i_prev);
        // Rule 11: a segment belongs to the rank owning its end.
        if (step == WALK_SAMPLE && owned(ray.a + ray.dir * t)) {
#if defined(LAYERS)
            if (with_layers) {
                // Rule 13: the layers at this sample mix into its segment.
                c = mix_layers(c, ray.a + ray.dir * t, 1.0 - opacity, light);
            }
#endif
            taken += 1u;
            composite(color, opacity, c.rgb, c.a);
        }
        if (opacity >= frame.alpha.z) {
            done = true;
            break;
        }
    }
    m = Absorb(color, opacity, t_prev, v_prev, i_prev, taken);
    walk = w;
    return done;
}

// Emission-absorption and the density-factor model, pre-integrated (rule 6): the ray from its start to its end is
// composited segment by segment between consecutive points: the start, the samples, the end. With layers, only
// the part of the ray that meets their span runs their code (lavapipe runs a loop's code for every lane).
vec4 march_emission(WalkRay ray, vec3 light) {
    float v0 = sample_value(ray.a);
    vec4 unused;
    vec4 i0 = integral_at(v0, unused);
    Absorb m = Absorb(vec3(0.0), 0.0, 0.0, v0, i0, 0u);
    Walk w = walk_start();
    float ALL = 3.0e38;
#if defined(LAYER_BLENDS)
    start_glow();
#endif
#if defined(LAYERS)
    vec2 span = layer_span(ray);
    if (!absorb_until(ray, w, m, light, span.x, false)) {
        if (!absorb_until(ray, w, m, light, span.y, true)) {
            absorb_until(ray, w, m, light, ALL, false);
        }
    }
#else
    absorb_until(ray, w, m, light, ALL, false);
#endif
    // The last segment, from the last point to the ray's end, where the march got there through bricks that hold
    // something (not by early termination; past a leap everything left is invisible).
    vec3 end = ray.a + ray.dir * ray.len;
    if (w.reached_end && w.walked && m.opacity < frame.alpha.z && owned(end)) {
        bool density_model = frame.flags.x == MODE_DENSITY;
        float t_prev = m.t_prev;
        float v_prev = m.v_prev;
        vec4 i_prev = m.i_prev;
        vec4 c = segment_to(ray, brick_at(end), ray.len, light, density_model, t_prev, v_prev, i_prev);
        vec3 color = m.color;
        float opacity = m.opacity;
        composite(color, opacity, c.rgb, c.a);
        m.color = color;
        m.opacity = opacity;
    }
#if defined(LAYER_BLENDS)
    // Rule 13: the light the other blends gathered, added at the ray's end.
    m.color += layers_glow();
#endif
    return share_or_finish(m.color, m.opacity, m.taken);
}
#endif

// Pixel `frag`'s output for its ray's segment a -> b (texture space), whichever setup found it.
vec4 march(vec3 a, vec3 b, vec2 frag) {
    // Rule 10: where the clipping plane starts the ray, iso-surfaces are cut open, not capped (see above).
    bool cut_start;
    if (!clip_segment(a, b, cut_start)) {
        return output_pixel(background_pixel(), 0u);
    }
    vec3 d = b - a;
    // World length and direction: the placement may scale, rotate, shear or mirror the box.
    vec3 d_world = mat3(frame.tex_to_world) * d;
    float len = length(d_world);
    float o = frame.flags.y != 0u ? jitter_offset(uvec2(frag), frame.flags.z) : 0.5;
    WalkRay ray = walk_ray(a, d / len, len, frame.extent.w, o);
    vec3 light = -normalize(d_world);
#if defined(FAMILY_PROJECTION)
    return march_projection(ray);
#elif defined(FAMILY_ISOSURFACE)
    return march_isosurface(ray, light, cut_start);
#else
    return march_emission(ray, light);
#endif
}
