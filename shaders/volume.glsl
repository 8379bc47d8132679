// The volume as the shaders read it: set 1's bindings (render/init.rs lays the set out, render/mod.rs
// `write_volume_set` fills it), rule 3's value at a point, the classification and its integrals, and gradients.
// The march and rule 9's light grid pass (light.comp) both read the volume through this file.
layout(set = 1, binding = 0) uniform texture3D volume_tex;
layout(set = 1, binding = 1) uniform sampler linear_smp;
// The baked table (src/render/mod.rs LUT_ROWS): linear rgb + opacity per voxel step at 4096 values.
layout(std430, set = 1, binding = 2) readonly buffer Lut {
    vec4 entries[4096];
} lut;
layout(set = 1, binding = 3) uniform texture3D occupancy_tex;   // one texel per 8^3 brick: class and reach (walk.glsl)
#if defined(GRADIENT_TEXTURE)
// Precomputed central differences on the voxel grid (RGBA16 SNORM, value per voxel x 2), filtered trilinearly:
// one 4-channel sample instead of six, at 8 bytes per voxel (RenderSettings::gradient_texture).
layout(set = 1, binding = 4) uniform texture3D gradient_tex;
#endif
#if defined(CORNERS8) || defined(CORNERS16)
layout(set = 1, binding = 5) uniform utexture3D corner_tex;   // CORNERS8: R32_UINT bytes; CORNERS16: RG32_UINT halves
#endif
// Its integral functions (src/transfer/preintegrate.rs): per entry the integrals over the value of extinction x colour
// (rgb) and of extinction (a), from 0 to the entry's value. A uniform buffer: on lavapipe its per-lane loads are
// branch-free, where a storage buffer's are a loop over the lanes.
layout(std140, set = 1, binding = 6) uniform Integrals {
    vec4 cumulative[4096];
} integrals;
#if defined(LIGHT_VOLUME)
// Rule 9's light grid (src/render/light_volume.rs): x the light's transmittance, y the ambient occlusion.
layout(set = 1, binding = 7) uniform texture3D light_tex;
#endif

// The brick pool's page table (src/render/pool.rs): per level-0 brick, the slot holding the data shown there
// (x, y, z packed 10:10:10) and that data's level.
layout(set = 1, binding = 8) uniform utexture3D directory_tex;

// A brick's translation from a point p (texture space, [0,1]^3 over the volume) to its slot's texels: the texel
// coordinate u = p * scale + offset (texel centres at integers + 0.5).
struct Brick {
    vec3 scale;
    vec3 offset;
};

#if defined(POOL_BRICKS)
// The one addressing function: the brick under p and where its data lies in the pool; `lo` and `hi` bound the
// level-0 brick it was looked up for (texture space), where the walk's spans end, and `level` is the level of the
// data shown there (the page table's). The level-L brick under level-0
// brick b is b >> L; its voxel x (level-L units, x = p * dims / 2^L) lies in its slot at
// x - (b >> L) * brick + border + slot * slot_side.
Brick brick_box_at(vec3 p, out vec3 lo, out vec3 hi, out int level) {
    vec3 vox = p * frame.dims.xyz;
    // (Not textureSize: a page table one brick deep is two slices, image_3d's copy.)
    ivec3 b = clamp(ivec3(floor(vox / frame.pool_brick.xyz)), ivec3(0), ivec3(frame.pool_grid.xyz) - 1);
    uvec2 e = texelFetch(usampler3D(directory_tex, linear_smp), b, 0).rg;
    vec3 slot = vec3(uvec3(e.x, e.x >> 10u, e.x >> 20u) & uvec3(1023u));
    level = int(e.y);
    float s = exp2(-float(level));
    vec3 origin = frame.pool_brick.w + slot * frame.pool_slot.xyz - vec3(b >> level) * frame.pool_brick.xyz;
    lo = vec3(b) * frame.pool_brick.xyz * frame.texel.xyz;
    hi = lo + frame.pool_brick.xyz * frame.texel.xyz;
    return Brick(frame.dims.xyz * s, origin);
}

Brick brick_at(vec3 p) {
    vec3 lo;
    vec3 hi;
    int level;
    return brick_box_at(p, lo, hi, level);
}
#else
// A volume kept as one brick (render/pool.rs): the same translation everywhere, and no page table to read (the
// march variant without POOL_BRICKS, so that small volumes pay nothing for the pool).
Brick brick_at(vec3 p) {
    return Brick(frame.dims.xyz, vec3(frame.pool_brick.w) - frame.part_origin.xyz);
}
#endif

// The pool as the march reads it (render::VolumeLayout). A 3D texture, filtered by the sampler; or, on CPU devices
// (lavapipe), a "corner texture": per texel the four values of the 2x2 square its cell starts in x and y in one
// texel, so a trilinear sample is two texelFetch (at z and z + 1) and seven lerps instead of eight filtered texel
// reads. lavapipe fetches 32-bit texels with one gather for all lanes. Both return what a UNORM or float texture
// returns (stored / 255, stored / 65535, or the float). A point in brick `b` (or within two voxels of it) reads
// only b's slot: its border holds the voxels around it.
#if defined(CORNERS8) || defined(CORNERS16)
float sample_in(Brick b, vec3 p) {
    vec3 q = p * b.scale + b.offset - 0.5;
    ivec3 i = ivec3(floor(q));
    vec3 f = q - vec3(i);
    ivec3 i1 = ivec3(i.xy, i.z + 1);
#if defined(CORNERS8)
    uint a = texelFetch(usampler3D(corner_tex, linear_smp), i, 0).r;
    uint c = texelFetch(usampler3D(corner_tex, linear_smp), i1, 0).r;
    vec4 lo = vec4(uvec4(a, a >> 8u, a >> 16u, a >> 24u) & uvec4(255u));
    vec4 hi = vec4(uvec4(c, c >> 8u, c >> 16u, c >> 24u) & uvec4(255u));
    const float unorm = 1.0 / 255.0;
#else
    uvec2 a = texelFetch(usampler3D(corner_tex, linear_smp), i, 0).rg;
    uvec2 c = texelFetch(usampler3D(corner_tex, linear_smp), i1, 0).rg;
    vec4 lo = vec4(uvec4(a.x, a.x >> 16u, a.y, a.y >> 16u) & uvec4(65535u));
    vec4 hi = vec4(uvec4(c.x, c.x >> 16u, c.y, c.y >> 16u) & uvec4(65535u));
    const float unorm = 1.0 / 65535.0;
#endif
    vec4 z = mix(lo, hi, f.z);
    vec2 y = mix(z.xy, z.zw, f.y);
    return mix(y.x, y.y, f.x) * unorm;
}
#else
float sample_in(Brick b, vec3 p) {
    return textureLod(sampler3D(volume_tex, linear_smp), (p * b.scale + b.offset) * frame.pool_inv.xyz, 0.0).r;
}
#endif

// The normalised value at p in brick b (see sample_value).
float value_in(Brick b, vec3 p) {
    float v = sample_in(b, p) * frame.value_map.x + frame.value_map.y;
    return isnan(v) ? v : clamp(v, 0.0, 1.0);
}

// The normalised value, in [0, 1] by definition (rule 3): f32 rounding of the scale and bias must not push the
// data's maximum just above 1 (out of a window ending at 1) nor its minimum below 0. NaN stays NaN.
// Looked up where p lies: for points the walk did not place in its span (segment ends, bisection, the light grid).
float sample_value(vec3 p) {
    return value_in(brick_at(p), p);
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

// Central differences one voxel apart: value change per voxel along each texture axis, from the gradient texture
// (binding 4) or six samples, all in the brick holding the centre p (its border reaches one voxel past it).
#if defined(GRADIENT_TEXTURE)
vec3 gradient_in(Brick b, vec3 p) {
    // Per voxel of the brick's level (2^L level-0 voxels): scaled to level 0's (b.scale = dims / 2^L).
    vec4 g = textureLod(sampler3D(gradient_tex, linear_smp), (p * b.scale + b.offset) * frame.pool_inv.xyz, 0.0);
    return 0.5 * g.xyz * (b.scale.x / frame.dims.x);
}
#else
vec3 gradient_in(Brick b, vec3 p) {
    vec3 d = frame.texel.xyz;
    vec3 g = 0.5 * vec3(
        value_in(b, p + vec3(d.x, 0.0, 0.0)) - value_in(b, p - vec3(d.x, 0.0, 0.0)),
        value_in(b, p + vec3(0.0, d.y, 0.0)) - value_in(b, p - vec3(0.0, d.y, 0.0)),
        value_in(b, p + vec3(0.0, 0.0, d.z)) - value_in(b, p - vec3(0.0, 0.0, d.z)));
    if (any(isnan(g))) {
        g = vec3(0.0);
    }
    return g;
}
#endif

vec3 gradient(vec3 p) {
    return gradient_in(brick_at(p), p);
}
