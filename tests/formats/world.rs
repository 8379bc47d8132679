//! Volumes in their true place: every reader's voxel-to-RAS affine against the library that wrote (or reads) the
//! file, as `volcast info --json` prints it; the phantom's markers where the patient has them; and rendered views
//! that show the patient's left on the screen's right from the front, through the binary.
//!
//! The files in tests/data/world were written by nibabel, SimpleITK, pynrrd, pydicom and VTK (see its README and
//! make.py): a body with three markers in patient space — value 1000 on the patient's left at RAS (−30, 0, 0) mm,
//! 700 anterior at (0, 35, 0), 400 superior at (0, 0, 32) — stored in many orders, mirrored, oblique and tilted.

use crate::common;

use std::path::{Path, PathBuf};

/// A file's expected placement, from the library that wrote or reads it.
struct Expected {
    path: &'static str,
    /// RAS+, row-major, the first three rows.
    affine: [[f64; 4]; 3],
    /// Where +i, +j, +k point (None: the format has no orientation).
    axes: Option<&'static str>,
    handedness: &'static str,
}

// Each file's expected affine with the library call that produced it (tests/data/world/expected.json has them
// with more detail).
include!("world/expected.rs");

fn s(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 path")
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The file at `rel` (relative to the crate), or None after recording a skip for ../shared.
fn file(rel: &str) -> Option<PathBuf> {
    match rel.strip_prefix("../shared/data/") {
        Some(shared) => common::shared_data(shared),
        None => Some(root().join(rel)),
    }
}

fn info_json(path: &Path) -> serde_json::Value {
    let o = common::volcast(&["info", "--json", s(path)]);
    assert!(o.status.success(), "{}: {}", path.display(), common::stderr(&o));
    serde_json::from_slice(&o.stdout).expect("info --json prints JSON")
}

#[test]
fn affines_match_the_libraries_that_wrote_the_files() {
    let mut failures = Vec::new();
    for Expected {
        path: rel,
        affine,
        axes,
        handedness,
    } in EXPECTED
    {
        let Some(path) = file(rel) else { continue };
        let j = info_json(&path);
        let got: Vec<Vec<f64>> = j["affine_ras"]
            .as_array()
            .expect("affine_ras")
            .iter()
            .map(|row| row.as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect())
            .collect();
        let worst = (0..3)
            .flat_map(|r| (0..4).map(move |c| (r, c)))
            .map(|(r, c)| (got[r][c] - affine[r][c]).abs())
            .fold(0.0, f64::max);
        if worst > 1e-3 {
            failures.push(format!("{rel}: affine {got:?} is {worst} mm from {affine:?}"));
        }
        assert_eq!(got[3], vec![0.0, 0.0, 0.0, 1.0], "{rel}");
        if j["axes"].as_str() != *axes {
            failures.push(format!("{rel}: axes {} but expected {axes:?}", j["axes"]));
        }
        if j["handedness"] != *handedness {
            failures.push(format!(
                "{rel}: handedness {} but expected {handedness}",
                j["handedness"]
            ));
        }
        for key in ["format", "dims", "type", "spacing", "value_range", "timesteps"] {
            assert!(!j[key].is_null(), "{rel}: info --json lacks {key}");
        }
        assert_eq!(j["timesteps"], 1, "{rel}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Loaded and placed by its affine, each marker's voxels lie where the phantom put it (within a voxel): the
/// centroid of the voxels above the body's value within 15 mm of where the marker should be, weighted by how far
/// above. This holds for the unevenly spaced DICOM series only because volcast resamples it (ITK's single affine
/// misplaces the slices past the gap by up to 2.4 mm).
#[test]
fn markers_are_where_the_patient_has_them() {
    let markers = [
        (1000.0, [-30.0, 0.0, 0.0]),
        (700.0, [0.0, 35.0, 0.0]),
        (400.0, [0.0, 0.0, 32.0]),
    ];
    for rel in EXPECTED
        .iter()
        .map(|e| e.path)
        .filter(|p| p.starts_with("tests/data/world"))
    {
        let v = volcast::formats::open(&root().join(rel), &Default::default()).expect("loads");
        let [nx, ny, nz] = v.dims;
        // A marker cube sampled on a coarse grid has its centroid up to about a third of a voxel off (measured
        // 1.6 mm at 4 mm voxels); without resampling the uneven series is 3.2 mm off.
        let slack = f64::from(v.spacing().iter().copied().fold(0.0f32, f32::max)) * 0.3 + 0.5;
        for (value, centre) in markers {
            let centre = glam::DVec3::from_array(centre);
            let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0);
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        let ras = v
                            .geometry
                            .affine
                            .transform_point3(glam::DVec3::new(x.into(), y.into(), z.into()));
                        let w = v.value(x, y, z) - 100.0;
                        if w > 0.0 && (ras - centre).length() < 15.0 {
                            sum += ras * w;
                            weight += w;
                        }
                    }
                }
            }
            assert!(
                weight > 0.0,
                "{rel}: nothing of the {value} marker within 15 mm of {centre}"
            );
            let at = sum / weight;
            let off = (at - centre).length();
            assert!(
                off < slack,
                "{rel}: the {value} marker is at RAS {at}, {off:.2} mm from {centre} (allowed {slack:.2})"
            );
        }
    }
}

/// Where the marker of normalised value `value` shows: the centre of the largest 4-connected patch of pixels
/// whose grey lies between `value − 0.25` and `value + 0.05` and that are not within 2 pixels of a brighter
/// marker's pixels (a brighter marker's edges pass through every lower value). The markers are 1.0 (left),
/// 0.7 (anterior) and 0.4 (superior); MIP shows a marker's values as they are, a little lower on its edges.
fn marker_at(image: &image::RgbaImage, value: f64) -> Option<(f64, f64)> {
    let (w, h) = (image.width() as i64, image.height() as i64);
    let grey = |x: i64, y: i64| f64::from(image.get_pixel(x as u32, y as u32)[0]) / 255.0;
    let brighter = |x: i64, y: i64| {
        (-2..=2).any(|dy: i64| {
            (-2..=2).any(|dx: i64| {
                let (u, v) = (x + dx, y + dy);
                u >= 0 && v >= 0 && u < w && v < h && grey(u, v) > value + 0.05
            })
        })
    };
    let mut inside = vec![false; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let g = grey(x, y);
            inside[(x + w * y) as usize] = g > value - 0.25 && g <= value + 0.05 && !brighter(x, y);
        }
    }
    let mut best: Vec<(i64, i64)> = Vec::new();
    for start in 0..inside.len() {
        if !inside[start] {
            continue;
        }
        inside[start] = false;
        let mut patch = vec![(start as i64 % w, start as i64 / w)];
        let mut i = 0;
        while i < patch.len() {
            let (x, y) = patch[i];
            for (u, v) in [(x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)] {
                if u >= 0 && v >= 0 && u < w && v < h && inside[(u + w * v) as usize] {
                    inside[(u + w * v) as usize] = false;
                    patch.push((u, v));
                }
            }
            i += 1;
        }
        if patch.len() > best.len() {
            best = patch;
        }
    }
    if best.len() < 4 {
        return None;
    }
    let n = best.len() as f64;
    let sum = best
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x as f64, b + y as f64));
    Some((sum.0 / n, sum.1 / n))
}

/// Rendered through the binary with `--view`, the phantom shows its left marker on the screen's right from the
/// front (and on the left from behind and from above), its superior marker at the top from the front and the
/// side, and its anterior marker at the top from above and on the screen's left from the patient's left: for a
/// NIfTI stored RAS, LAS (qfac −1), coronal and oblique, a MetaImage in ITK's RIP, an NRRD in LPS and the axial
/// and tilted DICOM series. MIP in grey over [0, 1000], so a pixel's grey is the largest value on its ray.
#[test]
fn views_show_the_patient_the_right_way_round() {
    const SIZE: u32 = 128;
    let centre = f64::from(SIZE) / 2.0;
    let files = [
        "nifti_ras.nii.gz",
        "nifti_las_qform.nii.gz",
        "nifti_coronal.nii.gz",
        "nifti_oblique.nii.gz",
        "mha_rip.mha",
        "nrrd_lps.nrrd",
        "dicom_series",
        "dicom_oblique",
    ];
    // (view, marker value, 'x' or 'y', the side it must be on: −1 left/top, +1 right/bottom).
    let expectations: [(&str, f64, char, f64); 7] = [
        ("anterior", 1.0, 'x', 1.0),
        ("anterior", 0.4, 'y', -1.0),
        ("posterior", 1.0, 'x', -1.0),
        ("superior", 0.7, 'y', -1.0),
        ("superior", 1.0, 'x', -1.0),
        ("left", 0.7, 'x', -1.0),
        ("left", 0.4, 'y', -1.0),
    ];
    let dir = common::scratch("world-views");
    let mut failures = Vec::new();
    for f in files {
        for view in ["anterior", "posterior", "superior", "left"] {
            let out = dir.join(format!("{f}-{view}.png"));
            let volume = root().join("tests/data/world").join(f);
            let size = format!("{SIZE}x{SIZE}");
            common::volcast_ok(&[
                "render",
                s(&volume),
                "--view",
                view,
                "--mode",
                "mip",
                "--colormap",
                "grayscale",
                "--window",
                "0%,100%",
                "--no-jitter",
                "--size",
                &size,
                "--validate",
                "-o",
                s(&out),
            ]);
            let image = image::open(&out).expect("PNG").to_rgba8();
            for &(v, value, axis, side) in expectations.iter().filter(|e| e.0 == view) {
                let Some((x, y)) = marker_at(&image, value) else {
                    failures.push(format!(
                        "{f} from {view}: the {value} marker is not visible ({})",
                        out.display()
                    ));
                    continue;
                };
                let offset = if axis == 'x' { x - centre } else { y - centre };
                if offset * side < 10.0 {
                    failures.push(format!(
                        "{f} from {v}: the {value} marker is at ({x}, {y}); expected it {} ({})",
                        match (axis, side > 0.0) {
                            ('x', true) => "right of centre",
                            ('x', false) => "left of centre",
                            (_, true) => "below centre",
                            (_, false) => "above centre",
                        },
                        out.display()
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `--voxel-axes` draws the grid as stored: the LAS file's left marker (stored towards +i) then shows on the
/// screen's left from the front, where patient space puts it on the right; and `info` says the file mirrors.
#[test]
fn voxel_axes_draw_the_grid_as_stored() {
    let file = root().join("tests/data/world/nifti_las_qform.nii.gz");
    let dir = common::scratch("world-voxel-axes");
    let mut sides = Vec::new();
    for extra in [&[][..], &["--voxel-axes"][..]] {
        let out = dir.join(format!("las{}.png", extra.len()));
        let args = [
            "render",
            s(&file),
            "--view",
            "anterior",
            "--mode",
            "mip",
            "--colormap",
            "grayscale",
            "--window",
            "0%,100%",
            "--no-jitter",
            "--size",
            "128x128",
            "--validate",
            "-o",
            s(&out),
        ];
        common::volcast_ok(&[&args[..], extra].concat());
        let image = image::open(&out).unwrap().to_rgba8();
        let (x, _) = marker_at(&image, 1.0).expect("the left marker is visible");
        sides.push(x - 64.0);
    }
    assert!(
        sides[0] > 10.0 && sides[1] < -10.0,
        "left marker columns from centre: {sides:?}"
    );
    let o = common::volcast(&["info", s(&file)]);
    let text = common::stdout(&o);
    assert!(
        text.contains("LAS") && text.contains("mirrored (left-handed)"),
        "{text}"
    );
}
