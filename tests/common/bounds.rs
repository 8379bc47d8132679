//! How close each family of GPU images must come to the reference, over the object pixels (compare.rs). Each bound
//! sits at most 2× above the worst case measured over its family on lavapipe (Mesa 22.3, LLVM 15; the test
//! binaries print each family's worst with --nocapture), and says the smallest bug it catches. Means leave out the
//! `outliers` worst pixels, as the max bound allows them. docs/testing.md's Tolerances lists the same numbers.

use super::compare::Bounds;

/// The GPU against the reference, every layout but 8-bit textures: every test family in tests/gpu/vs_reference.rs,
/// gpu/methods_agree.rs, gpu/features.rs (skipping, gradient texture) and cli/options.rs.
/// Measured over ~1000 comparisons (axis-aligned, oblique, mirrored and sheared placements): worst mean 0.142 (the
/// float64 diffusion MRI), p99 1; at most 3 pixels of one image above 2/255 (silhouettes, early-termination ties). Catches: a steady error of 1/255 on a
/// quarter of the object (mean), an error of 3/255 on 2% of it (p99), and any wrong region of more than 6 pixels
/// by more than 2/255 — a missing row or column of the image, a half-texel shift, a skipped brick.
pub const REFERENCE: Bounds = Bounds {
    mean: 0.25,
    p99: 2.0,
    max: 2,
    outliers: 6,
};

/// Spaced rays (rule 12): [`REFERENCE`]'s image, stretched by the device's linear blit. Vulkan leaves the precision
/// of linear filtering to the implementation, and lavapipe blends 8-bit values with 8-bit fixed-point weights, so
/// about half the stretched pixels land one step from the reference's rounding. Measured (the 64³ helix, plain
/// and mirrored, at 77×53 with k = 2 and 4, every ray setup): worst mean 0.50, p99 1, max 1. Catches a marched
/// image framed at its own aspect, a filter off by half a marched pixel, or a nearest-pixel stretch.
pub const SPACED: Bounds = Bounds {
    mean: 0.6,
    p99: 1.0,
    max: 1,
    outliers: 6,
};

/// R8_UNORM textures (`--texture native` on 8-bit data): lavapipe filters 8-bit UNORM textures with 8-bit
/// fixed-point weights, so a trilinear sample can be off by up to ~1/256 of the value range; where the data is
/// steep that moves samples across the window's edge and the error compounds along the ray. The same data as
/// R16_UNORM, float textures or corner textures meet [`REFERENCE`].
/// Measured (uint8 and int8 Marschner–Lobb, the 48³ helix through `--texture native`): worst mean 0.884, p99 23
/// (the helix's few hundred object pixels make its p99 its fourth-worst pixel), max 89; at most 10 pixels above
/// 16/255. Catches: a steady error of 2/255 over the object, or any region of more than 16 pixels off by more
/// than 16/255.
pub const REFERENCE_R8: Bounds = Bounds {
    mean: 1.75,
    p99: 30.0,
    max: 16,
    outliers: 16,
};

/// Brick strides (rule 2) against every step of the same frame, both from the reference: what the strides rule
/// gives up, which the quality levels promise stays small. Measured (helix, Marschner–Lobb, CT head at 0.4-voxel
/// steps and strides up to 4; four transfer functions): worst mean 0.69 and p99 3 (Marschner–Lobb, sampled near
/// its Nyquist limit, under a faint and a density table), max 6. Catches the rule without its spread term
/// (means 1.1–1.7, p99 8–12, max 45: strides leaping over the helix's edges) and a stride taken in strong bricks.
pub const STRIDES: Bounds = Bounds {
    mean: 1.0,
    p99: 4.0,
    max: 8,
    outliers: 6,
};

/// The two ray setups against each other (entry/exit faces, analytic), at every `compare` viewpoint.
/// Measured (helix, CT head): worst mean 0.003, p99 0, at most 2 pixels above 1/255 (silhouettes, where the
/// rasteriser and the analytic slab test decide a grazing ray differently). Catches: any systematic difference
/// in where rays start or end (an entry target read at the wrong pixel, a near plane applied by one setup only).
pub const METHODS: Bounds = Bounds {
    mean: 0.006,
    p99: 1.0,
    max: 1,
    outliers: 4,
};

/// Entry/exit targets of half floats (`--positions rgba16f`): positions keep 11 significant bits, so a ray's ends
/// move by up to 1/2048 of the box and its samples with them: a documented trade of accuracy for memory, which
/// `volcast compare` reports as the setups differing (tests/cli/tools.rs).
/// Measured (the 48³ helix at 64×48, tests/cli/options.rs): mean 0.636, p99 5, max 11; 1 pixel above 8/255.
/// Catches: rgba16f targets read at the wrong pixel or with the wrong format (mean, p99).
pub const POSITIONS_RGBA16F: Bounds = Bounds {
    mean: 1.25,
    p99: 10.0,
    max: 8,
    outliers: 4,
};
