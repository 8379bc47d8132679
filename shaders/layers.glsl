// Rule 13's layers (src/scene/layers.rs states the rule; src/render/layers.rs fills these bindings): further
// volumes on their own grids, sampled at each sample of the base's march and mixed into its segment there.
// Overlays (f32, data units) and label maps (dense ids) are stacked along z in one texture per kind.
layout(set = 1, binding = 9) uniform texture3D layer_values;
layout(set = 1, binding = 10) uniform utexture3D layer_labels;
struct LayerParams {
    mat4 to_index;   // the base's texture space -> the layer's voxel index (centres at integers)
    vec4 dims;       // xyz: the layer's size in voxels; w: its first slice in its kind's texture
    vec4 look;       // x: an overlay's blend (0 composite, 1 max, 2 add); y, z: its window (data units); w: its threshold
    vec4 more;       // x: 1 / its smallest voxel side (world); y: its first colour; z: an overlay's log2(1 - opacity);
                     // w: 0 window test, 1 v >= threshold, 2 |v| >= threshold
    vec4 texel;      // xyz: 1 / the size of its kind's texture
};
// How many there are: frame.voxel_world.y overlays, then .z label maps. A uniform buffer: on lavapipe a storage buffer's loads loop over the
// lanes (render/layers.rs MAX_LAYERS).
layout(std140, set = 1, binding = 11) uniform Layers {
    vec4 span_lo;   // xyz: the box (base texture space) outside which no layer shows anything; w: 1, or 0 where
    vec4 span_hi;   // none shows anything anywhere (render/layers.rs GpuLayers::span)
    LayerParams p[16];
} layers;
// Per overlay 256 entries over its window (linear rgb); per label map one per dense id (linear rgb and
// log2(1 - opacity), the layer's opacity included);
// 4096 to a row (render/layers.rs COLOUR_ROW).
layout(set = 1, binding = 12) uniform texture2D layer_colours;

vec4 layer_colour(uint i) {
    return texelFetch(sampler2D(layer_colours, linear_smp), ivec2(i & 4095u, i >> 12u), 0);
}

// An overlay's value at voxel index x: trilinear (one filtered fetch), clamped to the edge within its own slices.
float layer_value(LayerParams L, vec3 x) {
    vec3 u = clamp(x, vec3(0.0), L.dims.xyz - 1.0) + 0.5;
    u.z += L.dims.w;
    return textureLod(sampler3D(layer_values, linear_smp), u * L.texel.xyz, 0.0).r;
}

// Where point p (base texture space) lies in layer L: its voxel index x; false outside its box.
bool layer_index(LayerParams L, vec3 p, out vec3 x) {
    x = (L.to_index * vec4(p, 1.0)).xyz;
    return all(greaterThanEqual(x, vec3(-0.5))) && all(lessThanEqual(x, L.dims.xyz - 0.5));
}

// The opacity a (per voxel of layer L's own grid, given as k = log2(1 - a)) over one march step:
// 1 - (1 - a)^(h / d) = 1 - 2^(k h / d).
float layer_alpha(LayerParams L, float k) {
    return 1.0 - exp2(k * frame.extent.w * L.more.x);
}

// Overlay L at p: colour (linear) and opacity over the step; nothing outside its box or where it is not shown.
vec4 overlay_sample(LayerParams L, vec3 p) {
    vec3 x;
    if (!layer_index(L, p, x)) {
        return vec4(0.0);
    }
    float v = layer_value(L, x);
    float m = L.more.w > 1.5 ? abs(v) : v;
    bool shown = L.more.w > 0.5 ? m >= L.look.w : (v >= L.look.y && v <= L.look.z);
    if (isnan(v) || !shown) {
        return vec4(0.0);
    }
    float c = clamp((v - L.look.y) / (L.look.z - L.look.y), 0.0, 1.0) * 255.0;
    int i0 = min(int(c), 254);
    uint first = uint(L.more.y);
    vec3 rgb = mix(layer_colour(first + uint(i0)).rgb, layer_colour(first + uint(i0) + 1u).rgb, c - float(i0));
    return vec4(rgb, layer_alpha(L, L.more.z));
}

#if defined(SHADED)
// 1 where voxel v of label map L (clamped to its edge) holds `id`, else 0.
float holds(LayerParams L, ivec3 v, uint id) {
    ivec3 u = clamp(v, ivec3(0), ivec3(L.dims.xyz) - 1);
    u.z += int(L.dims.w);
    return texelFetch(usampler3D(layer_labels, linear_smp), u, 0).r == id ? 1.0 : 0.0;
}

// One edge of the cell, from voxel v (holding h0) to v + e (h1): the indicator's central differences at its two
// ends, mixed by t along it.
float edge_difference(LayerParams L, ivec3 v, ivec3 e, float h0, float h1, float t, uint id) {
    return 0.5 * mix(h1 - holds(L, v - e, id), holds(L, v + 2 * e, id) - h0, t);
}

// Rule 13's normal of label `id` at voxel index x of label map L: at each corner of the cell around x the central
// difference of "the voxel holds id" (indices clamped to the edge), interpolated trilinearly, as a gradient per
// base voxel for shade(). It turns smoothly across the cells, where the ids' own faces are a staircase.
vec3 label_gradient(LayerParams L, vec3 x, uint id) {
    vec3 top = L.dims.xyz - 1.0;
    vec3 c = clamp(x, vec3(0.0), top);
    vec3 lo = min(floor(c), max(top - 1.0, vec3(0.0)));
    vec3 f = c - lo;
    ivec3 a = ivec3(lo);
    ivec3 b = min(a + 1, ivec3(top));
    ivec3 v[8] = ivec3[8](a, ivec3(b.x, a.y, a.z), ivec3(a.x, b.y, a.z), ivec3(b.x, b.y, a.z), ivec3(a.x, a.y, b.z),
                          ivec3(b.x, a.y, b.z), ivec3(a.x, b.y, b.z), b);
    float h[8];
    for (int k = 0; k < 8; k++) {
        h[k] = holds(L, v[k], id);
    }
    ivec3 ex = ivec3(1, 0, 0);
    ivec3 ey = ivec3(0, 1, 0);
    ivec3 ez = ivec3(0, 0, 1);
    vec3 g = vec3(
        mix(mix(edge_difference(L, v[0], ex, h[0], h[1], f.x, id), edge_difference(L, v[2], ex, h[2], h[3], f.x, id), f.y),
            mix(edge_difference(L, v[4], ex, h[4], h[5], f.x, id), edge_difference(L, v[6], ex, h[6], h[7], f.x, id), f.y), f.z),
        mix(mix(edge_difference(L, v[0], ey, h[0], h[2], f.y, id), edge_difference(L, v[1], ey, h[1], h[3], f.y, id), f.x),
            mix(edge_difference(L, v[4], ey, h[4], h[6], f.y, id), edge_difference(L, v[5], ey, h[5], h[7], f.y, id), f.x), f.z),
        mix(mix(edge_difference(L, v[0], ez, h[0], h[4], f.z, id), edge_difference(L, v[1], ez, h[1], h[5], f.z, id), f.x),
            mix(edge_difference(L, v[2], ez, h[2], h[6], f.z, id), edge_difference(L, v[3], ez, h[3], h[7], f.z, id), f.x), f.y));
    // Per layer voxel -> per base voxel: the chain through to_index (of base texture space) and 1 / the base's dims.
    return (transpose(mat3(L.to_index)) * g) * frame.texel.xyz;
}
#endif

// Label map L at p: the nearest voxel's id (never interpolated), its colour and opacity over the step; with
// shading, its colour lit (rule 5, towards `light`) along label_gradient.
vec4 labels_sample(LayerParams L, vec3 p, vec3 light) {
    vec3 x;
    if (!layer_index(L, p, x)) {
        return vec4(0.0);
    }
    ivec3 v = clamp(ivec3(floor(x + 0.5)), ivec3(0), ivec3(L.dims.xyz) - 1);
    v.z += int(L.dims.w);
    uint id = texelFetch(usampler3D(layer_labels, linear_smp), v, 0).r;
    vec4 c = layer_colour(uint(L.more.y) + id);
    vec3 rgb = c.rgb;
#if defined(SHADED)
    if (frame.flags.w != 0u) {
        rgb = shade(rgb, label_gradient(L, x, id), light, p, 1.0);
    }
#endif
    return vec4(rgb, layer_alpha(L, c.a));
}

// Where ray r may meet something a layer shows: [t_in, t_out) of its path through the span box, or nothing
// (both past any ray's end). The march mixes layers only there (march.glsl march_emission).
vec2 layer_span(WalkRay r) {
    vec3 t0 = (layers.span_lo.xyz - r.a) * r.inv_dir;
    vec3 t1 = (layers.span_hi.xyz - r.a) * r.inv_dir;
    vec3 near = min(t0, t1);
    vec3 far = max(t0, t1);
    float t_in = max(max(near.x, near.y), near.z);
    float t_out = min(min(far.x, far.y), far.z);
    bool meets = layers.span_lo.w > 0.5 && t_in <= t_out;
    return meets ? vec2(t_in, t_out) : vec2(3.0e38);
}

#if defined(LAYER_BLENDS)
// Rule 13's other blends, gathered along the ray and added to its colour at its end (layers_glow): the light of
// the overlays blended by addition, and per overlay blended by maximum its largest light so far.
vec3 layer_added;
vec3 layer_peak[16];

void start_glow() {
    layer_added = vec3(0.0);
    for (int i = 0; i < 16; i++) {
        layer_peak[i] = vec3(0.0);
    }
}

// Overlay i's step l at a sample behind transmittance `front`: false where it is composited in depth; else its
// light is gathered by its blend.
bool gathered(uint i, vec4 l, float front) {
    float blend = layers.p[i].look.x;
    if (blend < 0.5) {
        return false;
    }
    if (blend > 1.5) {
        layer_added += front * l.a * l.rgb;
    } else {
        // Its opacity per voxel, not per step: a maximum does not grow with the number of samples.
        float a = l.a > 0.0 ? 1.0 - exp2(layers.p[i].more.z) : 0.0;
        layer_peak[i] = max(layer_peak[i], front * a * l.rgb);
    }
    return true;
}

// What the blends gathered along the ray: the added light and every overlay's maximum.
vec3 layers_glow() {
    vec3 glow = layer_added;
    for (int i = 0; i < 16; i++) {
        glow += layer_peak[i];
    }
    return glow;
}
#endif

// Rule 13's mix at a sample behind transmittance `front` (label maps lit towards `light` where shading is on): the base's segment and every layer's step composited in
// depth as one, alpha = 1 - prod(1 - alpha_i), colour = sum(alpha_i c_i) / sum(alpha_i); the overlays blended
// otherwise are gathered (LAYER_BLENDS). The overlays come first in the table, then the label maps
// (frame.voxel_world.y and .z of each). A variant compiles only the loops of the kinds its frame has
// (LAYER_OVERLAYS, LAYER_LABELS), each tested at its end: lavapipe runs a loop's body once more than it is taken,
// masked, where the test comes first, and runs a loop of no turns once.
vec4 mix_layers(vec4 base, vec3 p, float front, vec3 light) {
    float keep = 1.0 - base.a;
    vec3 sum = base.a * base.rgb;
    float weight = base.a;
    uint overlays = uint(frame.voxel_world.y);
#if defined(LAYER_OVERLAYS)
    uint i = 0u;
    do {
        vec4 l = overlay_sample(layers.p[i], p);
#if defined(LAYER_BLENDS)
        if (gathered(i, l, front)) {
            l = vec4(0.0);
        }
#endif
        keep *= 1.0 - l.a;
        sum += l.a * l.rgb;
        weight += l.a;
        i++;
    } while (i < overlays);
#endif
#if defined(LAYER_LABELS)
    uint all_layers = overlays + uint(frame.voxel_world.z);
    uint j = overlays;
    do {
        vec4 l = labels_sample(layers.p[j], p, light);
        keep *= 1.0 - l.a;
        sum += l.a * l.rgb;
        weight += l.a;
        j++;
    } while (j < all_layers);
#endif
    return weight > 0.0 ? vec4(sum / weight, 1.0 - keep) : vec4(0.0);
}
