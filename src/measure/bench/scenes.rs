//! The bench's scene table: which volumes, transfer functions, cameras, sizes and shadings are timed, and the
//! `vtk-helix` scene that matches `../shared/tools/vtk_bench.py`.

use super::layered::{BenchLayer, LayerFrom, AAL, ALONE, FOUR_CHANNELS, ONE_CHANNEL, OVER_T1, T1, ZMAP};
use crate::scene::camera::Camera;
use crate::scene::settings::{self, RenderSettings};
use crate::transfer::Colormap;
use crate::volume::{self, Volume, VolumeError};
use glam::Vec3;

/// Where a scene's volume comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source {
    Builtin {
        name: &'static str,
        size: Option<u32>,
    },
    /// A raw file (open-scivis name) in the data folder (`--data`); the scene is skipped when it is missing.
    DataFile {
        file: &'static str,
        spacing: [f32; 3],
    },
    /// A file in the `native/` folder beside the data folder, opened with its placement (layered scenes).
    Native {
        file: &'static str,
    },
    /// Generated fluorescence channel 0 (`layered::channel_volume`).
    Channel,
    /// `../shared/tools/make_volume.py`'s helix: the file given with `--vtk-raw`, else the same field generated
    /// here by [`vtk_helix_volume`] (a port of the script; see there for how close it is).
    VtkHelix,
}

/// Shading variants scenes are timed with: off, Blinn–Phong with VTK's coefficients (ambient 0.2, diffuse 0.7,
/// specular 0.3, power 20: `settings::Shading::default()`, as ../shared/tools/vtk_bench.py uses), and the same
/// with rule 9's shadows and ambient occlusion (the key light; the grid is made before the timed frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shading {
    Off,
    On,
    Shadows,
}

pub const SHADINGS: &[Shading] = &[Shading::Off, Shading::On];

/// The variants of the scenes that also time shadows and occlusion.
pub const LIT_SHADINGS: &[Shading] = &[Shading::Off, Shading::On, Shading::Shadows];

impl Shading {
    pub const ALL: [Shading; 3] = [Shading::Off, Shading::On, Shading::Shadows];

    pub fn apply(self, s: &mut RenderSettings) {
        s.lighting.shading = match self {
            Shading::Off => None,
            Shading::On | Shading::Shadows => Some(settings::Shading::default()),
        };
        (s.lighting.shadows, s.lighting.ambient_occlusion) = (self == Shading::Shadows, self == Shading::Shadows);
    }

    pub fn name(self) -> &'static str {
        match self {
            Shading::Off => "off",
            Shading::On => "on",
            Shading::Shadows => "shadows",
        }
    }
}

/// One row of the scene table: a volume and how it is shown. Each scene is timed at every size in `sizes`, with
/// both ray setups and every shading variant in `shadings`.
#[derive(Clone, Copy)]
pub struct Scene {
    pub name: &'static str,
    pub about: &'static str,
    pub source: Source,
    /// Transfer function and camera on top of [`RenderSettings::new`]'s defaults for the volume.
    pub configure: fn(&mut RenderSettings, &Volume),
    pub sizes: &'static [u32],
    pub shadings: &'static [Shading],
    /// Rule 13's layers over the volume (layered.rs).
    pub layers: &'static [BenchLayer],
}

const FULL_SIZES: &[u32] = &[512, 1024];

/// The full benchmark. Extend here.
pub fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "helix",
            about: "built-in helix 256³ uint8, default transfer function: sparse (most of the box is empty)",
            source: Source::Builtin {
                name: "helix",
                size: None,
            },
            configure: |_, _| {},
            sizes: FULL_SIZES,
            shadings: LIT_SHADINGS,
            layers: &[],
        },
        Scene {
            name: "dense",
            about: "built-in colormap ramp 256³ uint8, window 0–1, step alpha 0.02: every sample visible and \
                    composited, most rays run ≥ 200 samples (the march's worst case)",
            source: Source::Builtin {
                name: "colormap",
                size: None,
            },
            configure: |s, _| {
                s.colour.window = [0.0, 1.0];
                s.colour.step_alpha = 0.02;
            },
            sizes: FULL_SIZES,
            shadings: SHADINGS,
            layers: &[],
        },
        Scene {
            name: "ct-head",
            about: "CT head 256×256×108 int16 at 0.96×0.96×1.5 mm, window 0.33–0.9, plasma, step alpha 0.6 (the \
                    CT picture of docs/cli.md); lit with --shading-fade 0.05 (soft tissue's gradients are noise)",
            source: Source::DataFile {
                file: "cranium_ct_256x256x108_int16.raw",
                spacing: [0.957031, 0.957031, 1.5],
            },
            configure: |s, v| {
                s.colour.window = [0.33, 0.9];
                s.colour.colormap = Colormap::Plasma;
                s.colour.step_alpha = 0.6;
                s.lighting.shading_fade = 0.05;
                let d = Camera::fit_distance(v.extent().length() * 0.5, s.camera.fov_y_deg);
                s.camera = Camera::orbit(25.0, 10.0, d, Vec3::ZERO);
            },
            sizes: FULL_SIZES,
            shadings: LIT_SHADINGS,
            layers: &[],
        },
        Scene {
            name: "mri-brain",
            about: "MRI brain (colin27 T1) 181×217×181 uint8, window 0.2–1, grayscale, step alpha 0.05",
            source: Source::DataFile {
                file: "colin27_t1_181x217x181_uint8.raw",
                spacing: [1.0, 1.0, 1.0],
            },
            configure: |s, _| {
                s.colour.window = [0.2, 1.0];
                s.colour.colormap = Colormap::Grayscale;
                s.colour.step_alpha = 0.05;
            },
            sizes: FULL_SIZES,
            shadings: SHADINGS,
            layers: &[],
        },
        Scene {
            name: "vtk-helix",
            about: "the scene of ../shared/tools/vtk_bench.py: make_volume.py's helix 256³ uint8, viridis, opacity \
                    0 at 0.08 of the range rising linearly to 0.2, 1-voxel steps, VTK's camera",
            source: Source::VtkHelix,
            configure: configure_vtk_helix,
            sizes: FULL_SIZES,
            shadings: SHADINGS,
            layers: &[],
        },
        layered(ALONE, "the colin27 T1 NIfTI alone, as the layered scenes show it", &[]),
        layered(
            OVER_T1[0],
            "the T1 with the motor z-map (3 mm) over it, |z| ≥ 3",
            &[ZMAP],
        ),
        layered(
            OVER_T1[1],
            "the T1 with the AAL atlas (1 mm, 116 labels) over it",
            &[AAL],
        ),
        layered(OVER_T1[2], "the T1 with the z-map and the AAL atlas", &[ZMAP, AAL]),
        channels(
            ONE_CHANNEL,
            "a 256³ channel of 48 balls (generated), as a fluorescence channel",
            &[],
        ),
        channels(
            FOUR_CHANNELS,
            "the channel with three more of their own balls over it, by maximum (--channels all)",
            &[CHANNEL_1, CHANNEL_2, CHANNEL_3],
        ),
    ]
}

const fn channel(k: u32) -> BenchLayer {
    BenchLayer {
        from: LayerFrom::Channel(k),
        labels: false,
        threshold: None,
    }
}
const CHANNEL_1: BenchLayer = channel(1);
const CHANNEL_2: BenchLayer = channel(2);
const CHANNEL_3: BenchLayer = channel(3);

/// A channel scene at 512², unshaded: generated channel 0 in grey with `layers` (channels) over it.
fn channels(name: &'static str, about: &'static str, layers: &'static [BenchLayer]) -> Scene {
    Scene {
        name,
        about,
        source: Source::Channel,
        configure: |s, _| {
            s.colour.window = [0.1, 1.0];
            s.colour.colormap = Colormap::Grayscale;
            s.colour.step_alpha = 0.3;
        },
        sizes: &[512],
        shadings: &[Shading::Off],
        layers,
    }
}

/// A layered scene (rule 13) at 512², unshaded: the T1 as `mri-brain` shows it, with `layers`; its ratio to
/// `mri-t1` in one run is a layer's cost.
fn layered(name: &'static str, about: &'static str, layers: &'static [BenchLayer]) -> Scene {
    Scene {
        name,
        about,
        source: Source::Native { file: T1 },
        configure: |s, _| {
            s.colour.window = [0.2, 1.0];
            s.colour.colormap = Colormap::Grayscale;
            s.colour.step_alpha = 0.05;
        },
        sizes: &[512],
        shadings: &[Shading::Off],
        layers,
    }
}

/// `--quick` (CI smoke mode): a tiny helix, both ray setups, a few seconds in all.
pub fn quick_scenes() -> Vec<Scene> {
    vec![Scene {
        name: "quick-helix",
        about: "built-in helix 64³, 64×64 (smoke test)",
        source: Source::Builtin {
            name: "helix",
            size: Some(64),
        },
        configure: |_, _| {},
        sizes: &[64],
        shadings: SHADINGS,
        layers: &[],
    }]
}

/// vtk_bench.py's camera and transfer function in volcast's terms.
///
/// - Opacity: VTK ramps 0 at 0.08 of the range to 0.2 at the top, per unit distance 1 voxel at 1-voxel steps.
///   With `multiplied_alpha`, window [0.08, 1] and step alpha 0.2, α = c·0.2 with c = (v − 0.08)/0.92: the same ramp.
/// - Colour: viridis. VTK spreads it over the whole scalar range, volcast over the window, so colours of the same
///   value differ slightly (a value at 0.5 of the range shows viridis(0.46) here).
/// - Camera: vtk_bench.py starts on the −y side of the focal point (position = focal − 1000·y) and turns by
///   Azimuth(35), Elevation(25); `Camera::orbit`'s azimuth 0 is on +y, so VTK's 35° is 215° here. VTK's
///   `ResetCamera` fits the sphere around the *points'* bounding box ((dims − 1)·spacing) at its default 30° view
///   angle; `Zoom(1.45)` then narrows the angle to 30°/1.45.
pub fn configure_vtk_helix(s: &mut RenderSettings, v: &Volume) {
    s.colour.colormap = Colormap::Viridis;
    s.colour.window = [0.08, 1.0];
    s.colour.multiplied_alpha = true;
    s.colour.step_alpha = 0.2;
    s.background = Vec3::ZERO;
    let spacing = v.spacing();
    let world_per_unit = v.extent().x / (v.dims[0] as f32 * spacing[0]);
    let points = Vec3::from_array([0, 1, 2].map(|i| (v.dims[i] as f32 - 1.0) * spacing[i]));
    let radius = 0.5 * points.length() * world_per_unit;
    let distance = radius / 15f32.to_radians().sin();
    s.camera = Camera::orbit(VTK_AZIMUTH_HERE, 25.0, distance, Vec3::ZERO);
    s.camera.fov_y_deg = 30.0 / 1.45;
}

/// vtk_bench.py's azimuth 35° in `Camera::orbit`'s convention (see [`configure_vtk_helix`]).
pub const VTK_AZIMUTH_HERE: f32 = 215.0;

/// make_volume.py's field (helix tube + radial gradient ball), computed in f64. numpy computes it in float32
/// (partly float64), so a few voxels on rounding boundaries may differ by one level; pass the script's own file
/// with `--vtk-raw` to compare exactly like for like.
pub fn vtk_helix_volume(n: u32) -> Result<Volume, VolumeError> {
    use std::f64::consts::PI;
    let (big_r, turns, z0, z1, sigma) = (0.55f64, 3.0f64, -0.85f64, 0.85f64, 0.12f64);
    let pitch = (z1 - z0) / turns;
    let c_ = pitch / (2.0 * PI);
    let cos_alpha = big_r / (big_r * big_r + c_ * c_).sqrt();
    let coord = |i: u32| (f64::from(i) + 0.5) / f64::from(n) * 2.0 - 1.0;
    let mut data = Vec::with_capacity((n as usize).pow(3));
    for zi in 0..n {
        let z = coord(zi);
        for yi in 0..n {
            let y = coord(yi);
            for xi in 0..n {
                let x = coord(xi);
                let rho = (x * x + y * y + z * z).sqrt();
                let ball = (1.0 - rho / 0.9).clamp(0.0, 1.0);
                let r = x.hypot(y);
                let phi = y.atan2(x);
                let t = (z - z0) / c_ - phi;
                let k = (t / (2.0 * PI)).round_ties_even();
                let dz = z - (z0 + c_ * (phi + 2.0 * PI * k));
                let d = ((r - big_r).powi(2) + (dz * cos_alpha).powi(2)).sqrt();
                let over = (z0 - z).max(z - z1).max(0.0);
                let tube = (-(d / sigma).powi(2)).exp() * (-(over / 0.05).powi(2)).exp();
                let v = (0.30 * ball + tube).clamp(0.0, 1.0);
                let u = (v * 255.0).round_ties_even() as u8;
                data.push(if u < 2 { 0 } else { u });
            }
        }
    }
    let mut v = Volume::new(
        "vtk-helix",
        [n; 3],
        [1.0; 3],
        volume::VoxelType::U8,
        volume::VoxelData::U8(data),
    )?;
    v.format = "generated (port of make_volume.py)".into();
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtk_camera_frames_the_box_like_vtk() {
        let v = volume::builtin("helix", Some(8)).unwrap();
        let mut s = RenderSettings::new(512, 512, v.extent());
        configure_vtk_helix(&mut s, &v);
        assert!((s.camera.fov_y_deg - 20.69).abs() < 0.01);
        // Eye on the −y side, turned towards +x by VTK's positive azimuth, lifted by the elevation.
        let e = s.camera.eye.normalize();
        assert!(e.x > 0.0 && e.y < 0.0 && e.z > 0.0, "{e}");
        assert!((e.z - 25f32.to_radians().sin()).abs() < 1e-5);
        assert!((e.x / -e.y - 35f32.to_radians().tan()).abs() < 1e-5);
    }
}
