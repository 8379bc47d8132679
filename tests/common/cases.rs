//! The settings and volumes the GPU tests render: viewpoints, one case per setting and per rendering rule, and
//! synthetic volumes of every voxel type on non-cubic voxels.

use glam::{DMat3, DMat4, DVec3, Vec3};
use std::f64::consts::PI;
use volcast::scene::camera::Camera;
use volcast::scene::settings::{CompositeMode, RenderSettings, Shading};
use volcast::transfer::function::TransferFunction;
use volcast::transfer::Colormap;
use volcast::volume::{Geometry, Scaling, Volume, VoxelData, VoxelType};

#[derive(Clone)]
pub struct Case {
    pub name: String,
    pub settings: RenderSettings,
}

pub fn base(volume: &Volume, size: u32) -> RenderSettings {
    RenderSettings::new(size, size, volume.extent())
}

pub fn with(volume: &Volume, size: u32, name: &str, f: impl FnOnce(&mut RenderSettings)) -> Case {
    let mut s = base(volume, size);
    f(&mut s);
    Case {
        name: name.to_string(),
        settings: s,
    }
}

/// Viewpoints every volume goes through.
pub fn standard_cases(v: &Volume, size: u32) -> Vec<Case> {
    let e = v.extent();
    vec![
        with(v, size, "oblique", |_| {}),
        with(v, size, "axis-x", |s| {
            s.camera = Camera::orbit(90.0, 0.0, 2.5, Vec3::ZERO)
        }),
        with(v, size, "axis-z-top", |s| {
            s.camera = Camera::orbit(0.0, 90.0, 2.5, Vec3::ZERO)
        }),
        with(v, size, "inside", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.05, -0.1, 0.02) * e, Vec3::new(0.3, 0.4, 0.1) * e);
        }),
        with(v, size, "on-face", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.0, 0.5 * e.y, 0.0), Vec3::ZERO)
        }),
        with(v, size, "multiplied-viridis", |s| {
            s.colour.multiplied_alpha = true;
            s.colour.step_alpha = 0.5;
            s.colour.colormap = Colormap::Viridis;
        }),
    ]
}

/// Cases that exercise one setting each.
pub fn settings_cases(v: &Volume, size: u32) -> Vec<Case> {
    vec![
        with(v, size, "window", |s| s.colour.window = [0.3, 0.7]),
        with(v, size, "window-plasma", |s| {
            // Colour follows the window position, not the value: a window off-centre in the range tells them apart.
            s.colour.window = [0.15, 0.45];
            s.colour.colormap = Colormap::Plasma;
        }),
        with(v, size, "slab", |s| {
            s.cut.set_slab(0, 0.5, 0.4);
            s.cut.set_slab(2, 0.3, 0.5);
        }),
        with(v, size, "slab-inside", |s| {
            s.cut.set_slab(1, 0.6, 0.3);
            s.camera = Camera::looking_at(Vec3::new(0.1, 0.0, 0.05), Vec3::new(-0.2, 0.5, 0.0));
        }),
        with(v, size, "half-step", |s| {
            s.sampling.step_length = 0.5;
            s.colour.colormap = Colormap::Plasma;
        }),
        with(v, size, "double-step-gnuplot", |s| {
            s.sampling.step_length = 2.0;
            s.colour.colormap = Colormap::Gnuplot;
        }),
        with(v, size, "no-early-stop-rainbow", |s| {
            s.compositing.early_termination = 1.0;
            s.colour.step_alpha = 0.05;
            s.colour.colormap = Colormap::Rainbow;
        }),
        with(v, size, "early-stop-half", |s| {
            s.compositing.early_termination = 0.5;
            s.colour.step_alpha = 0.3;
        }),
        with(v, size, "background-grayscale", |s| {
            // Channels chosen off the .5 rounding ties (0.3 × 255 = 76.5 would round either way).
            s.background = Vec3::new(0.2, 0.35, 0.45);
            s.colour.colormap = Colormap::Grayscale;
        }),
        with(v, size, "wide-angle-close", |s| {
            s.camera = Camera::orbit(-60.0, -30.0, 1.2, Vec3::ZERO);
            s.camera.fov_y_deg = 70.0;
        }),
        with(v, size, "near-plane-cuts", |s| {
            // The near plane, far from the eye, cuts the box: rays start on it, not at the box.
            s.camera = Camera::orbit(20.0, 10.0, 1.6, Vec3::ZERO);
            s.camera.near = 1.4;
        }),
        with(v, size, "non-square", |s| {
            s.width = size + 37;
            s.height = size - 21;
        }),
        with(v, size, "no-jitter", |s| s.sampling.jitter = None),
        with(v, size, "jitter-seed-7", |s| s.sampling.jitter = Some(7)),
        with(v, size, "orthographic", |s| s.camera.ortho = true),
        with(v, size, "orthographic-wide", |s| {
            s.camera.ortho = true;
            s.width = size + 41;
            s.height = size - 17;
        }),
        with(v, size, "orthographic-inside", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.3, 0.4, 0.1));
            s.camera.ortho = true;
        }),
    ]
}

/// One case per compositing mode, shading and classification option.
pub fn quality_cases(v: &Volume, size: u32) -> Vec<Case> {
    vec![
        with(v, size, "mip", |s| s.compositing.mode = CompositeMode::Mip),
        with(v, size, "minip", |s| {
            s.compositing.mode = CompositeMode::MinIp;
            s.colour.window = [0.2, 1.0];
        }),
        with(v, size, "average", |s| s.compositing.mode = CompositeMode::Average),
        with(v, size, "iso", |s| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.compositing.iso_value = 0.4;
        }),
        with(v, size, "iso-ortho-phong", |s| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.compositing.iso_value = 0.6;
            s.camera.ortho = true;
            s.lighting.shading = Some(Shading {
                ambient: 0.1,
                diffuse: 0.6,
                specular: 0.6,
                shininess: 40.0,
            });
        }),
        with(v, size, "density", |s| {
            s.compositing.mode = CompositeMode::Density;
            s.compositing.density = 2.5;
        }),
        with(v, size, "density-half-step", |s| {
            s.compositing.mode = CompositeMode::Density;
            s.compositing.density = 1.5;
            s.sampling.step_length = 0.5;
        }),
        with(v, size, "shaded", |s| s.lighting.shading = Some(Shading::default())),
        with(v, size, "shaded-gradient-opacity", |s| {
            s.lighting.shading = Some(Shading::default());
            s.lighting.gradient_opacity = Some(0.05);
            s.colour.step_alpha = 0.4;
        }),
        with(v, size, "shaded-fade", |s| {
            s.lighting.shading = Some(Shading::default());
            s.lighting.shading_fade = 0.05;
            s.colour.window = [0.1, 0.9];
        }),
        with(v, size, "shaded-double-step", |s| {
            s.lighting.shading = Some(Shading::default());
            s.sampling.step_length = 2.0;
        }),
        with(v, size, "tf-mr-default", |s| {
            s.colour.transfer_function = Some(TransferFunction::preset("mr-default").unwrap());
            s.colour.window = [0.0, 1.0];
        }),
        with(v, size, "tf-qt-example-multiplied-off", |s| {
            s.colour.transfer_function = Some(TransferFunction::preset("qt-example").unwrap());
            s.colour.window = [0.0, 1.0];
        }),
    ]
}

/// The rendering rules that depend on voxel geometry and the data's values: shading, iso-surfaces and gradient
/// opacity (for non-cubic voxels and every data type).
pub fn gradient_cases(v: &Volume, size: u32) -> Vec<Case> {
    quality_cases(v, size)
        .into_iter()
        .filter(|c| c.name.starts_with("shaded") || c.name.starts_with("iso"))
        .collect()
}

/// Marschner & Lobb's test function (1994; f_M = 6, α = 0.25) over [−1, 1]³, sampled on 33 × 29 × 25 voxels
/// of 1 × 1.2 × 0.8 (neither the grid nor the voxels cubic), stored as `ty` over a range typical of that type
/// (signed types straddle zero, as CT data do).
/// The CT head from `../shared/data` at its true spacing (None after a skip where the file is missing).
pub fn ct_head() -> Option<Volume> {
    let path = super::shared_data("raw/cranium_ct_256x256x108_int16.raw")?;
    let opts = volcast::formats::RawOptions {
        spacing: Some([0.957031, 0.957031, 1.5]),
        ..Default::default()
    };
    Some(volcast::formats::load_raw(&path, &opts).expect("CT head"))
}

pub fn marschner_lobb_as(ty: VoxelType) -> Volume {
    marschner_lobb_sized(ty, [33, 29, 25])
}

/// [`marschner_lobb_as`] on a grid of `dims`.
pub fn marschner_lobb_sized(ty: VoxelType, dims: [u32; 3]) -> Volume {
    let coord = |i: u32, n: u32| -1.0 + 2.0 * f64::from(i) / f64::from(n - 1);
    let mut values = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let (x, y, z) = (coord(i, dims[0]), coord(j, dims[1]), coord(k, dims[2]));
                let rho_r = (2.0 * PI * 6.0 * (0.5 * PI * x.hypot(y)).cos()).cos();
                values.push((1.0 - (0.5 * PI * z).sin() + 0.25 * (1.0 + rho_r)) / 2.5);
            }
        }
    }
    let scaled = |lo: f64, hi: f64| values.iter().map(move |v| (lo + v * (hi - lo)).round());
    let data = match ty {
        VoxelType::U8 => VoxelData::U8(scaled(0.0, 255.0).map(|v| v as u8).collect()),
        // int8 is stored biased (+128) in a U8, int16 (+32768) in a U16.
        VoxelType::I8 => VoxelData::U8(scaled(-100.0, 120.0).map(|v| (v as i32 + 128) as u8).collect()),
        VoxelType::U16 => VoxelData::U16(scaled(0.0, 4095.0).map(|v| v as u16).collect()),
        VoxelType::I16 => VoxelData::U16(scaled(-1000.0, 2000.0).map(|v| (v as i32 + 32768) as u16).collect()),
        // 32-bit integers and float64 reach the GPU as f32; values past 2^24 round there.
        VoxelType::U32 => VoxelData::F32(scaled(0.0, 3.0e6).map(|v| v as f32).collect()),
        VoxelType::I32 => VoxelData::F32(scaled(-2.0e6, 1.0e6).map(|v| v as f32).collect()),
        VoxelType::F64 => VoxelData::F32(values.iter().map(|v| (v * 1.0e3 - 250.0) as f32).collect()),
        VoxelType::F32 => VoxelData::F32(values.iter().map(|&v| v as f32).collect()),
    };
    Volume::new(format!("ml-{}", ty.name()), dims, [1.0, 1.2, 0.8], ty, data).expect("valid volume")
}

/// `v` placed obliquely: turned 25° about z and 12° about x, voxels 1.0 × 1.3 × 0.8, shifted off the origin (a
/// right-handed, anatomical placement like an oblique acquisition's sform).
pub fn oblique(v: &Volume) -> Volume {
    let turn = DMat3::from_rotation_x(12f64.to_radians()) * DMat3::from_rotation_z(25f64.to_radians());
    place(v, "oblique", turn * DMat3::from_diagonal(DVec3::new(1.0, 1.3, 0.8)))
}

/// `v` stored mirrored, as a NIfTI with qfac −1 or an LAS sform: i runs to the patient's left.
pub fn mirrored(v: &Volume) -> Volume {
    place(v, "mirrored", DMat3::from_diagonal(DVec3::new(-1.2, 1.0, 0.9)))
}

/// `v` sheared as a gantry-tilted CT series: each slice offset along y by 0.3 of a slice step.
pub fn sheared(v: &Volume) -> Volume {
    place(
        v,
        "sheared",
        DMat3::from_cols(DVec3::X, DVec3::Y, DVec3::new(0.0, 0.3, 1.0)),
    )
}

fn place(v: &Volume, what: &str, linear: DMat3) -> Volume {
    let affine = DMat4::from_mat3_translation(linear, DVec3::new(-40.0, 12.0, 7.5));
    let mut placed = v
        .clone()
        .with_geometry(Geometry::anatomical(affine))
        .expect("a valid affine");
    placed.name = format!("{}-{what}", v.name);
    placed
}

/// A label mask: 1 inside a ball and a slab, 0 elsewhere, stored as `ty` (1 → the type's 1, 255 or 65535
/// scaled), so that whole regions sit exactly at the data's maximum, the top of the default window.
pub fn mask_as(ty: VoxelType) -> Volume {
    const N: u32 = 40;
    let inside = |x: u32, y: u32, z: u32| {
        let c = |i: u32| f64::from(i) - 19.5;
        (c(x).powi(2) + c(y).powi(2) + c(z).powi(2)).sqrt() < 12.0 || (4..8).contains(&z)
    };
    let flags: Vec<bool> = (0..N * N * N)
        .map(|i| inside(i % N, (i / N) % N, i / (N * N)))
        .collect();
    let data = match ty {
        VoxelType::U8 => VoxelData::U8(flags.iter().map(|&f| u8::from(f) * 255).collect()),
        // As a CT series stores it: 1024 + value, rescale intercept −1024.
        VoxelType::U16 => VoxelData::U16(flags.iter().map(|&f| 1024 + u16::from(f) * 1000).collect()),
        _ => VoxelData::F32(flags.iter().map(|&f| f32::from(u8::from(f))).collect()),
    };
    let ty = match ty {
        VoxelType::U8 | VoxelType::U16 => ty,
        _ => VoxelType::F32,
    };
    let v = Volume::new(format!("mask-{}", ty.name()), [N; 3], [1.0, 1.0, 1.3], ty, data).expect("valid volume");
    if ty == VoxelType::U16 {
        let ct = Scaling {
            slope: 1.0,
            intercept: -1024.0,
        };
        return v.with_scaling(ct).expect("valid rescale");
    }
    v
}
