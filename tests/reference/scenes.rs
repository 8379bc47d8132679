//! The scenes the reference's self-tests share, and the closed forms' helpers.
//!
//! Most cases use a 16³ volume on a unit cube, looked at head-on along -z through the centre pixel of an odd-sized
//! image: that ray crosses the box over exactly L = 1 = 16 voxels, so with step length `s` it takes
//! n = #{k : (k + o)·s < 16} samples (o = 0.5 without jitter). Emission and density composite the n + 1 segments
//! between the ray's start, its samples and its end (rule 6, pre-integrated), so with opacity α per voxel a
//! constant volume reaches A = 1 - (1 - α)^16 at every step length. Colours are composited in linear light and
//! encoded to sRGB once (rule 8).

use crate::common;

use common::classify::{encode, srgb_to_linear};
use common::reference::{quantise, Reference};
use glam::{DVec3, Vec3};
use image::{Rgba, RgbaImage};
use volcast::scene::camera::Camera;
use volcast::scene::settings::RenderSettings;
use volcast::transfer::function::{TfUnits, TransferFunction};
use volcast::volume::{Volume, VoxelData, VoxelType};

pub const N: u32 = 16;

/// Odd, so that pixel (CENTRE, CENTRE) looks exactly along the view axis.
pub const SIZE: u32 = 9;

pub const CENTRE: u32 = SIZE / 2;

pub const BACKGROUND: Vec3 = Vec3::new(0.2, 0.4, 0.6);

pub const STEP_ALPHA: f32 = 0.2;

/// `1 - α` as the reference sees it (0.2 is not exact in f32).
pub fn keep() -> f64 {
    1.0 - f64::from(STEP_ALPHA)
}

/// A volume of `dims` voxels with `spacing` whose voxels are `value(x, y, z)`, normalised with the data range fixed
/// at `range`.
pub fn volume_with(dims: [u32; 3], spacing: [f32; 3], range: [f64; 2], value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    let mut data = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                data.push(value(x, y, z));
            }
        }
    }
    let mut volume =
        Volume::new("selftest", dims, spacing, VoxelType::F32, VoxelData::F32(data)).expect("a valid volume");
    volume.range = range;
    volume
}

/// A 16³ volume on the unit cube whose voxels are `value(x, y, z)`, normalised with the data range fixed at
/// [0, 2] (so raw 1 reads 0.5 whatever the data's own range is).
pub fn volume_from(value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    volume_with([N; 3], [1.0; 3], [0.0, 2.0], value)
}

pub fn constant_volume() -> Volume {
    volume_from(|_, _, _| 1.0)
}

/// A 16³ unit cube whose normalised value is z/16 at texel z: along z, v(tex) = tex − 1/32, clamped to [0, 15/16].
pub fn z_ramp() -> Volume {
    volume_with([N; 3], [1.0; 3], [0.0, 16.0], |_, _, z| z as f32)
}

/// Looking down -z at the unit cube from z = 3, window [0,1] (so the constant volume has v = 0.5), no early stop,
/// samples at the step midpoints.
pub fn head_on(volume: &Volume, size: u32) -> RenderSettings {
    let mut s = RenderSettings::new(size, size, volume.extent());
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    s.colour.window = [0.0, 1.0];
    s.colour.step_alpha = STEP_ALPHA;
    s.compositing.early_termination = 1.0;
    s.background = BACKGROUND;
    s.sampling.jitter = None;
    s
}

/// A transfer function (normalised units) with colour `srgb` and opacity `alpha` everywhere.
pub fn constant_tf(srgb: [f32; 3], alpha: f32) -> TransferFunction {
    TransferFunction {
        name: "constant".into(),
        units: TfUnits::Normalized,
        colors: vec![[0.0, srgb[0], srgb[1], srgb[2]], [1.0, srgb[0], srgb[1], srgb[2]]],
        colormap: Default::default(),
        opacity: vec![[0.0, alpha], [1.0, alpha]],
    }
}

/// Grey level = v (sRGB), opacity `alpha`.
pub fn grey_ramp_tf(alpha: f32) -> TransferFunction {
    TransferFunction {
        colors: vec![[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]],
        ..constant_tf([0.0; 3], alpha)
    }
}

pub fn linear(c: Vec3) -> DVec3 {
    let c = c.as_dvec3();
    DVec3::new(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z))
}

/// The pixel a miss shows: the background, decoded for compositing and encoded again.
pub fn background_pixel() -> Rgba<u8> {
    quantise(encode(linear(BACKGROUND)))
}

/// The reference's classification colour at `v` (linear light), for the tests of compositing.
pub fn table_rgb(volume: &Volume, s: &RenderSettings, v: f64) -> DVec3 {
    Reference::new(volume).classifier(s).rgb(v)
}

pub fn expected_samples(distance_in_voxels: f64, step_length: f64) -> u32 {
    expected_samples_at(distance_in_voxels, step_length, 0.5)
}

pub fn expected_samples_at(distance_in_voxels: f64, step_length: f64, offset: f64) -> u32 {
    (0..)
        .take_while(|&k| (f64::from(k) + offset) * step_length < distance_in_voxels)
        .count() as u32
}

/// Rule 6's segment lengths (in steps' units of voxels) of a ray `distance` voxels long at step length `step` with
/// start offset `offset`: from the start to the first sample, between samples, from the last sample to the end.
pub fn segment_lengths(distance: f64, step: f64, offset: f64) -> Vec<f64> {
    let samples = expected_samples_at(distance, step, offset);
    let mut points = vec![0.0];
    points.extend((0..samples).map(|k| (f64::from(k) + offset) * step));
    points.push(distance);
    points.windows(2).map(|w| w[1] - w[0]).collect()
}

pub fn assert_near(what: &str, actual: f64, expected: f64, tolerance: f64) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} but expected {expected} (± {tolerance})"
    );
}

pub fn assert_near3(what: &str, actual: DVec3, expected: DVec3, tolerance: f64) {
    assert!(
        (actual - expected).abs().max_element() <= tolerance,
        "{what}: {actual} but expected {expected} (± {tolerance})"
    );
}

pub fn assert_all_background(image: &RgbaImage, what: &str) {
    let bg = background_pixel();
    for (x, y, p) in image.enumerate_pixels() {
        assert_eq!(*p, bg, "{what}: pixel ({x}, {y}) is not the background");
    }
}
