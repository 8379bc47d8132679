// The walk: the one place that advances a ray through the march's sample grid, for every compositing family.
// Sample k of a ray lies at t = (k + o) * h (step h, start offset o). Empty-space skipping and brick strides
// (rule 2): the ray is walked span by span; `span_at` looks up the 8^3 brick holding a sample and gives the
// index of the first sample past the cube of bricks around it that share its class, and that class. The walk
// leaps over empty spans without leaving its sample grid, and in the others takes the samples of the class's
// stride without further lookups. With lookups off (no skipping, no strides), the spans are the pool's
// bricks at stride 1 (a volume kept as one brick: the whole ray). Every span carries its pool brick's translation
// (volume.glsl brick_at), so its samples are read without further lookups.
//
// Emission and density composite segments between consecutive points (rule 6), so their walk also yields, leaving
// bricks that hold something, the first sample beyond them, and after a leap the last sample leapt over as the next
// segment's start (WALK_RESAMPLE); and only they take strides (skip.rs gives the other families none). WALK_SEGMENTS,
// a constant march.glsl defines per family, turns all that on: the projection and isosurface families compile the
// walk without it (lavapipe pays for every line of the lookup on every step) and take every sample alone.
//
// The walk is the only code that knows the sample grid and the bricks: the families loop over walk_step and say
// only what they do with what it yields.

// What the walk needs of the ray, computed once per pixel (lavapipe's LLVM passes hoist nothing out of loops).
struct WalkRay {
    vec3 a;
    vec3 dir;
    // 1 / dir, with zero components taking the far side (a huge, ignored exit instead of 0/0).
    vec3 inv_dir;
    // Per axis, whether the ray leaves a cube of bricks through its upper face.
    bvec3 up;
    vec3 inv_brick;
    ivec3 bricks;
    // The step, its inverse and the start offset.
    float h;
    float inv_h;
    float o;
    // The ray's length and the most samples it may take (frame.viewport.z).
    float len;
    int max_steps;
};

// The ray a + dir * t, t in [0, len), walked at step h from offset o.
WalkRay walk_ray(vec3 a, vec3 dir, float len, float h, float o) {
    vec3 safe = mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
    return WalkRay(a, dir, 1.0 / safe, greaterThanEqual(dir, vec3(0.0)), 1.0 / frame.brick.xyz,
                   textureSize(sampler3D(occupancy_tex, linear_smp), 0), h, 1.0 / h, o, len, int(frame.viewport.z));
}

// A span of the walk: from the sample looked up to the samples before `end`, in bricks of one class (0 empty;
// 1, 2, 3 strides 4, 2, 1) and, with POOL_BRICKS, in one brick of the pool, whose translation it carries. span_at
// is the walk's only lookup, once per span, of the skip grid and the pool's page table.
struct Span {
    int end;
    int level;
    // Rule 2's level stride: 2^(L - S) for a pool brick of level L under a step of level S's voxel (1 without
    // POOL_BRICKS). A coarser brick's samples are taken at its own voxel's pace.
    int coarser;
#if defined(POOL_BRICKS)
    Brick brick;
#endif
};

// The cube of skip bricks around the one holding p that share its class (bounds in texture space): returns the
// class. skip::encode_reach: bits 0-1 the class (0 empty; 1, 2, 3 strides 4, 2, 1), bits 2-7 the reach r: every
// brick within r bricks has the same class, so the ray is walked to where it leaves that cube as one span.
int skip_cube(WalkRay r, vec3 p, out vec3 lo, out vec3 hi) {
    ivec3 b = clamp(ivec3(floor(p * r.inv_brick)), ivec3(0), r.bricks - 1);
    int code = int(texelFetch(sampler3D(occupancy_tex, linear_smp), b, 0).r * 255.0 + 0.5);
    int reach = code >> 2;
    lo = vec3(b - ivec3(reach)) * frame.brick.xyz;
    hi = vec3(b + ivec3(reach + 1)) * frame.brick.xyz;
    return code & 3;
}

// The index of the first sample past where the ray leaves the box [lo, hi].
int span_end(WalkRay r, vec3 lo, vec3 hi) {
    vec3 exits = (mix(lo, hi, r.up) - r.a) * r.inv_dir;
    // A little short of the exit: rounding must never leap over a sample of the next brick.
    float t_exit = min(exits.x, min(exits.y, exits.z)) - 1e-4 * r.h;
    return int(ceil(t_exit * r.inv_h - r.o));
}

// The span starting at the sample at `t` (= (k + o) * h), from the bricks holding that sample: it ends where the
// ray leaves the cube of skip bricks of its class, or the pool's brick.
Span span_at(WalkRay r, float t) {
    vec3 p = r.a + r.dir * t;
    vec3 lo;
    vec3 hi;
#if defined(POOL_BRICKS)
    int shown;
    Brick pb = brick_box_at(p, lo, hi, shown);
    int level = 3;
    if (frame.mode_params.z >= 0.5) {
        vec3 cube_lo;
        vec3 cube_hi;
        level = skip_cube(r, p, cube_lo, cube_hi);
        lo = max(lo, cube_lo);
        hi = min(hi, cube_hi);
    }
    // 2^(L - S): how many of the step's voxels one voxel of the level shown spans (pool_grid.w is the step's
    // level S).
    int coarser = max((1 << shown) >> int(frame.pool_grid.w), 1);
    return Span(span_end(r, lo, hi), level, coarser, pb);
#else
    if (frame.mode_params.z < 0.5) {
        return Span(2147483647, 3, 1);
    }
    int level = skip_cube(r, p, lo, hi);
    return Span(span_end(r, lo, hi), level, 1);
#endif
}

// Where the walk stands. One sample per step (lavapipe runs a loop until its slowest lane ends, and nested loops
// at the pace of the slowest lane of each): `k` is the next sample index and [k, stop) the span being walked at
// `stride`; at `stop` the walk goes on from `span_end` with the next lookup.
struct Walk {
    int k;
    int span_end;
    int stop;
    int stride;
    // Whether the ray ended at its end (rather than at max_steps).
    bool reached_end;
    // WALK_SEGMENTS: whether the last span walked held something (its samples were taken) or was leapt over, and
    // whether the next step yields sample `resample_at` as a segment's start.
    bool walked;
    bool resample;
    int resample_at;
    // The brick of the sample yielded (a volume kept as one brick: always the same); with POOL_BRICKS, those of
    // the span and of the resample.
    Brick brick;
#if defined(POOL_BRICKS)
    Brick span_brick;
    Brick resample_brick;
#endif
};

Walk walk_start() {
    Brick whole = brick_at(vec3(0.0));
#if defined(POOL_BRICKS)
    return Walk(0, 0, 0, 1, false, true, false, 0, whole, whole, whole);
#else
    return Walk(0, 0, 0, 1, false, true, false, 0, whole);
#endif
}

// What a step of the walk yields.
const int WALK_END = 0;       // the ray is done (at its end if reached_end, else at max_steps)
const int WALK_LEAP = 1;      // an empty span leapt over, whose first sample is now k; no sample
const int WALK_NONE = 2;      // a span without a sample of its stride; no sample
const int WALK_SAMPLE = 3;    // the sample at t
const int WALK_RESAMPLE = 4;  // WALK_SEGMENTS: the last sample leapt over, at t: only the next segment's start

// One step of the walk: looks up the next span where the last one ends, and yields at most one sample, at `t`.
int walk_step(WalkRay r, inout Walk w, out float t) {
    t = 0.0;
    if (w.k >= w.stop && !w.resample) {
        w.k = w.span_end;
        float t0 = (float(w.k) + r.o) * r.h;
        if (w.k >= r.max_steps || t0 >= r.len) {
            w.reached_end = w.k < r.max_steps;
            return WALK_END;
        }
        Span span = span_at(r, t0);
        w.span_end = max(span.end, w.k + 1);
        // Leaving bricks that hold something, the segment from the last point there to the first sample beyond
        // still spans the values between theirs: that one sample is taken before the leap.
        bool exiting = WALK_SEGMENTS && span.level == 0 && w.walked;
        if (span.level == 0 && !exiting) {
            w.stop = w.k;
            return WALK_LEAP;
        }
        // After a leap, the segment starts at the last sample leapt over (nothing there is visible).
        w.resample = WALK_SEGMENTS && !w.walked && w.k > 0;
        w.resample_at = w.k - 1;
#if defined(POOL_BRICKS)
        w.span_brick = span.brick;
        if (w.resample) {
            // The last sample leapt over may lie in another of the pool's bricks.
            w.resample_brick = brick_at(r.a + r.dir * ((float(w.resample_at) + r.o) * r.h));
        }
#endif
        w.walked = !exiting;
        // The span's stride s (rule 2): the samples whose index is a multiple of s, its class's stride times its
        // brick's level stride.
        w.stride = (exiting || !WALK_SEGMENTS) ? 1 : (1 << (3 - span.level)) * span.coarser;
        w.stop = exiting ? w.k + 1 : w.span_end;
        w.k = (w.k + w.stride - 1) & ~(w.stride - 1);
        if (WALK_SEGMENTS && w.k >= w.stop && !w.resample) {
            return WALK_NONE;
        }
    }
    int j = w.resample ? w.resample_at : w.k;
    t = (float(j) + r.o) * r.h;
    if (w.resample) {
        w.resample = false;
#if defined(POOL_BRICKS)
        w.brick = w.resample_brick;
#endif
        return WALK_RESAMPLE;
    }
#if defined(POOL_BRICKS)
    w.brick = w.span_brick;
#endif
    if (t >= r.len) {
        w.reached_end = true;
        return WALK_END;
    }
    w.k = j + w.stride;
    return WALK_SAMPLE;
}
