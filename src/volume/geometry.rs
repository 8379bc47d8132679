//! Where a volume's voxels are: its voxel-to-world affine, and what the world's axes mean. Pure maths.
//!
//! The world of an *anatomical* volume is patient space in millimetres, RAS+ as nibabel and 3D Slicer use it:
//! +x towards the patient's right, +y anterior, +z superior. Readers convert their file's space into it (DICOM,
//! ITK's MetaImage and LPS NRRD flip x and y). A volume without orientation (raw, VTK legacy, non-anatomical NRRD
//! spaces, built-ins) lives in the file's own x, y, z, with no anatomical names.

use glam::{DMat3, DMat4, DVec3, DVec4};

/// A volume's placement in space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Voxel index (i, j, k, 1), i fastest on disk, to world millimetres (RAS+ when `anatomical`). Voxel centres
    /// sit at integer indices.
    pub affine: DMat4,
    /// The file says which way the patient lies (NIfTI qform/sform, an anatomical NRRD space, MetaImage, DICOM).
    pub anatomical: bool,
}

/// The LPS (DICOM, ITK) ↔ RAS conversion: negate x and y.
pub const LPS_TO_RAS: DMat4 = DMat4::from_diagonal(DVec4::new(-1.0, -1.0, 1.0, 1.0));

impl Geometry {
    /// Voxels of `spacing` along the world's axes, voxel (0, 0, 0) at the origin, no orientation.
    pub fn from_spacing(spacing: [f64; 3]) -> Geometry {
        Geometry {
            affine: DMat4::from_diagonal(DVec4::new(spacing[0], spacing[1], spacing[2], 1.0)),
            anatomical: false,
        }
    }

    /// An anatomical placement from a voxel-to-RAS affine.
    pub fn anatomical(affine: DMat4) -> Geometry {
        Geometry {
            affine,
            anatomical: true,
        }
    }

    /// The 3×3 linear part: column i is the world step of one voxel along i.
    pub fn linear(&self) -> DMat3 {
        DMat3::from_mat4(self.affine)
    }

    /// World position of voxel (0, 0, 0).
    pub fn origin(&self) -> DVec3 {
        self.affine.w_axis.truncate()
    }

    /// The voxel size along each index axis: the lengths of the linear part's columns.
    pub fn spacing(&self) -> [f64; 3] {
        let l = self.linear();
        [l.x_axis.length(), l.y_axis.length(), l.z_axis.length()]
    }

    /// The shortest voxel side (rule 2's voxel, in millimetres).
    pub fn smallest_side(&self) -> f64 {
        self.spacing().into_iter().fold(f64::INFINITY, f64::min)
    }

    /// The same directions and origin with voxels of `spacing` (a user's override of the file's voxel size).
    pub fn with_spacing(&self, spacing: [f64; 3]) -> Geometry {
        let old = self.spacing();
        let mut affine = self.affine;
        for (i, (&new, &was)) in spacing.iter().zip(&old).enumerate() {
            let scale = if was > 0.0 { new / was } else { new };
            *affine.col_mut(i) *= DVec4::new(scale, scale, scale, 1.0);
            if was <= 0.0 {
                // A degenerate column has no direction to keep: take the index axis itself.
                let mut unit = DVec4::ZERO;
                unit[i] = new;
                *affine.col_mut(i) = unit;
            }
        }
        Geometry { affine, ..*self }
    }

    /// Right-handed (positive determinant) or left-handed: a left-handed affine mirrors the volume.
    pub fn handedness(&self) -> Handedness {
        if self.linear().determinant() < 0.0 {
            Handedness::Left
        } else {
            Handedness::Right
        }
    }

    /// Where +i, +j and +k point, as nibabel's `aff2axcodes` names it ('L'/'R', 'P'/'A', 'I'/'S'), e.g. "LAS";
    /// `None` for a volume without orientation.
    pub fn axcodes(&self) -> Option<[char; 3]> {
        const LABELS: [(char, char); 3] = [('L', 'R'), ('P', 'A'), ('I', 'S')];
        self.anatomical.then(|| {
            io_orientation(self.linear()).map(
                |(axis, positive)| {
                    if positive {
                        LABELS[axis].1
                    } else {
                        LABELS[axis].0
                    }
                },
            )
        })
    }

    /// Largest angle (degrees) between an index axis and the world axis it is nearest to: 0 for a volume stored
    /// along the world's axes (in any order or sign), positive for an oblique one.
    pub fn obliquity_deg(&self) -> f64 {
        let l = self.linear();
        (0..3)
            .map(|i| {
                let c = l.col(i);
                let len = c.length();
                if len == 0.0 {
                    return 0.0;
                }
                (c.abs().max_element() / len).clamp(-1.0, 1.0).acos().to_degrees()
            })
            .fold(0.0, f64::max)
    }

    /// Largest deviation (degrees) of the index axes from being perpendicular to each other: a shear (a DICOM
    /// series with gantry tilt) makes it positive.
    pub fn shear_deg(&self) -> f64 {
        let l = self.linear();
        let cols = [l.x_axis, l.y_axis, l.z_axis];
        let mut worst: f64 = 0.0;
        for a in 0..3 {
            for b in a + 1..3 {
                let (u, v) = (cols[a], cols[b]);
                let d = u.length() * v.length();
                if d > 0.0 {
                    worst = worst.max((90.0 - (u.dot(v) / d).clamp(-1.0, 1.0).acos().to_degrees()).abs());
                }
            }
        }
        worst
    }

    /// The geometry of the volume made by keeping every `factor[i]`-th voxel's block: new voxel j covers old
    /// voxels f·j … f·j + f − 1, centred at old index f·j + (f − 1)/2.
    pub fn downsampled(&self, factor: [u32; 3]) -> Geometry {
        let f = factor.map(f64::from);
        let scale = DMat4::from_cols(
            DVec4::new(f[0], 0.0, 0.0, 0.0),
            DVec4::new(0.0, f[1], 0.0, 0.0),
            DVec4::new(0.0, 0.0, f[2], 0.0),
            DVec4::new((f[0] - 1.0) / 2.0, (f[1] - 1.0) / 2.0, (f[2] - 1.0) / 2.0, 1.0),
        );
        Geometry {
            affine: self.affine * scale,
            ..*self
        }
    }

    /// The render world's scale (rule 0): one over the box's longest side in millimetres (voxels × voxel size),
    /// the same with or without `voxel_axes`.
    pub fn world_per_mm(&self, dims: [u32; 3]) -> f64 {
        let d = DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2]));
        1.0 / (d * DVec3::from_array(self.spacing())).max_element()
    }

    /// Texture space [0, 1]³ of a `dims` grid to volcast's render world: voxel centres at (i + 0.5)/dims, placed
    /// by the affine (or, with `voxel_axes`, along the world's axes by the voxel sizes alone), then centred on the
    /// origin and scaled so the box's longest side is 1. For a volume along the axes that is `(tex − ½)·extent`.
    pub fn tex_to_world(&self, dims: [u32; 3], voxel_axes: bool) -> DMat4 {
        let d = DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2]));
        let index_from_tex = DMat4::from_translation(DVec3::splat(-0.5)) * DMat4::from_scale(d);
        let spacing = DVec3::from_array(self.spacing());
        let mm_from_index = if voxel_axes {
            DMat4::from_scale(spacing)
        } else {
            self.affine
        };
        let centre = mm_from_index.transform_point3((d - 1.0) * 0.5);
        DMat4::from_scale(DVec3::splat(self.world_per_mm(dims)))
            * DMat4::from_translation(-centre)
            * mm_from_index
            * index_from_tex
    }

    /// The affine as four rows of four numbers (row-major, for JSON and printing).
    pub fn rows(&self) -> [[f64; 4]; 4] {
        let r = self.affine.transpose();
        [r.x_axis, r.y_axis, r.z_axis, r.w_axis].map(|v| v.to_array())
    }
}

/// Whether an affine keeps or mirrors handedness.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handedness {
    Right,
    Left,
}

impl Handedness {
    pub fn name(self) -> &'static str {
        match self {
            Handedness::Right => "right",
            Handedness::Left => "left",
        }
    }
}

/// nibabel's `io_orientation`: for each index axis (in order), the world axis it is closest to and whether it
/// points along it, after replacing the (possibly sheared or scaled) linear part by its nearest orthogonal
/// matrix; each world axis is taken once.
pub fn io_orientation(linear: DMat3) -> [(usize, bool); 3] {
    // Columns scaled to unit length (zero columns left alone), as nibabel does before its SVD.
    let mut rs = linear;
    for i in 0..3 {
        let len = rs.col(i).length();
        if len > 0.0 {
            *rs.col_mut(i) /= len;
        }
    }
    let mut r = nearest_orthogonal(rs).transpose(); // rows of `r` are the index axes
    let mut out = [(0, true); 3];
    for (axis, slot) in out.iter_mut().enumerate() {
        let col = r.row(axis);
        // The first largest, as numpy's argmax takes it.
        let mut world = 0;
        for w in 1..3 {
            if col[w].abs() > col[world].abs() {
                world = w;
            }
        }
        *slot = (world, col[world] >= 0.0);
        // Remove that world axis from the remaining index axes (nibabel zeroes its row of R).
        for other in 0..3 {
            let mut row = r.row(other);
            row[world] = 0.0;
            r = set_row(r, other, row);
        }
    }
    out
}

fn set_row(m: DMat3, row: usize, v: DVec3) -> DMat3 {
    let mut t = m.transpose();
    *t.col_mut(row) = v;
    t.transpose()
}

/// The orthogonal matrix nearest to `m` (its polar factor, `U·Vᵀ` of its SVD), by Newton's iteration
/// `X ← (X + X⁻ᵀ)/2`, which converges quadratically for any invertible `m`. A singular `m` falls back to the
/// identity's columns where they vanish.
fn nearest_orthogonal(m: DMat3) -> DMat3 {
    if m.determinant().abs() < 1e-12 {
        return m;
    }
    let mut x = m;
    for _ in 0..100 {
        let next = (x + x.inverse().transpose()) * 0.5;
        let change = (next - x).to_cols_array().iter().map(|v| v.abs()).fold(0.0, f64::max);
        x = next;
        if change < 1e-15 {
            break;
        }
    }
    x
}

/// The NIfTI-1 qform: rotation from the quaternion (b, c, d) with a = √(1 − b² − c² − d²), voxel sizes pixdim,
/// the third axis negated when qfac < 0, then the offsets. From nifti1.h ("METHOD 2"), as nibabel's
/// `quaternions.quat2mat` and `Nifti1Header.get_qform` compute it.
pub fn nifti_qform(quaternion: [f64; 3], qfac: f64, pixdim: [f64; 3], offset: [f64; 3]) -> DMat4 {
    let [b, c, d] = quaternion;
    // nibabel treats a slightly negative 1 − b² − c² − d² (rounding in the stored floats) as 0.
    let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
    let r = DMat3::from_cols(
        DVec3::new(
            a * a + b * b - c * c - d * d,
            2.0 * (b * c + a * d),
            2.0 * (b * d - a * c),
        ),
        DVec3::new(
            2.0 * (b * c - a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d + a * b),
        ),
        DVec3::new(
            2.0 * (b * d + a * c),
            2.0 * (c * d - a * b),
            a * a + d * d - c * c - b * b,
        ),
    );
    let qfac = if qfac < 0.0 { -1.0 } else { 1.0 };
    let zooms = DVec3::new(pixdim[0], pixdim[1], pixdim[2] * qfac);
    let linear = r * DMat3::from_diagonal(zooms);
    DMat4::from_cols(
        linear.x_axis.extend(0.0),
        linear.y_axis.extend(0.0),
        linear.z_axis.extend(0.0),
        DVec4::new(offset[0], offset[1], offset[2], 1.0),
    )
}

/// An affine from its three rows of four (the NIfTI sform's `srow_x`, `srow_y`, `srow_z`).
pub fn from_rows(rows: [[f64; 4]; 3]) -> DMat4 {
    DMat4::from_cols_array_2d(&[rows[0], rows[1], rows[2], [0.0, 0.0, 0.0, 1.0]]).transpose()
}

/// An affine from per-axis direction columns (each already scaled by its voxel size) and an origin.
pub fn from_columns(columns: [DVec3; 3], origin: DVec3) -> DMat4 {
    DMat4::from_cols(
        columns[0].extend(0.0),
        columns[1].extend(0.0),
        columns[2].extend(0.0),
        origin.extend(1.0),
    )
}

/// Names for the index axes i, j, k in a panel: "i (R->L)" for an anatomical volume whose +i points left, "x"
/// (or "y", "z") otherwise. ASCII: the viewer's font has no arrows.
pub fn index_axis_names(geometry: &Geometry) -> [String; 3] {
    let opposite = |c: char| match c {
        'L' => 'R',
        'R' => 'L',
        'A' => 'P',
        'P' => 'A',
        'S' => 'I',
        _ => 'S',
    };
    match geometry.axcodes() {
        Some(codes) => [0, 1, 2].map(|a| format!("{} ({}->{})", ["i", "j", "k"][a], opposite(codes[a]), codes[a])),
        None => ["x", "y", "z"].map(String::from),
    }
}

/// The letter of a world direction in an anatomical world: where the world vector `v` points most.
pub fn direction_label(v: DVec3) -> char {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        if v.x >= 0.0 {
            'R'
        } else {
            'L'
        }
    } else if a.y >= a.z {
        if v.y >= 0.0 {
            'A'
        } else {
            'P'
        }
    } else if v.z >= 0.0 {
        'S'
    } else {
        'I'
    }
}

/// `x` with the fewest decimals that keep it within a millionth of itself: a header's 0.859375 mm that the
/// placement's f32 arithmetic made 0.85937506 prints as 0.859375, and 7.0005236 as 7.00052.
pub fn shortest(x: f64) -> String {
    (0..=12)
        .map(|p| format!("{x:.p$}"))
        .find(|t| t.parse::<f64>().is_ok_and(|r| (r - x).abs() <= 1e-6 * x.abs()))
        .unwrap_or_else(|| x.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(affine: DMat4) -> String {
        Geometry::anatomical(affine).axcodes().unwrap().iter().collect()
    }

    #[test]
    fn axcodes_follow_nibabel() {
        // nibabel.aff2axcodes(np.diag([2, 2, 2, 1])) == ('R', 'A', 'S'); with x negated ('L', 'A', 'S').
        assert_eq!(codes(DMat4::from_diagonal(DVec4::new(2.0, 2.0, 2.0, 1.0))), "RAS");
        assert_eq!(codes(DMat4::from_diagonal(DVec4::new(-3.0, 3.0, 3.0, 1.0))), "LAS");
        // A coronal permutation: i → R, j → S, k → A.
        let coronal = from_columns(
            [
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(0.0, 4.0, 0.0),
            ],
            DVec3::ZERO,
        );
        assert_eq!(codes(coronal), "RSA");
        // Oblique by 30°: still nearest to R, A, S.
        let (s, c) = 30f64.to_radians().sin_cos();
        let oblique = from_columns(
            [DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::new(0.0, 0.0, 1.0)],
            DVec3::ZERO,
        );
        assert_eq!(codes(oblique), "RAS");
        assert!((Geometry::anatomical(oblique).obliquity_deg() - 30.0).abs() < 1e-9);
        // At 45° both index axes are equally near R: the first takes it, nibabel's greedy order.
        let (s, c) = 45f64.to_radians().sin_cos();
        let diagonal = from_columns(
            [DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::new(0.0, 0.0, 1.0)],
            DVec3::ZERO,
        );
        let got = codes(diagonal);
        assert!(got == "RAS" || got == "ALS", "{got}");
    }

    #[test]
    fn handedness_and_spacing() {
        let g = Geometry::anatomical(DMat4::from_diagonal(DVec4::new(-3.0, 2.0, 4.0, 1.0)));
        assert_eq!(g.handedness(), Handedness::Left);
        assert_eq!(g.spacing(), [3.0, 2.0, 4.0]);
        let h = g.with_spacing([1.0, 1.0, 2.0]);
        assert_eq!(h.spacing(), [1.0, 1.0, 2.0]);
        assert_eq!(h.axcodes(), g.axcodes(), "an override keeps the directions");
        assert_eq!(h.handedness(), Handedness::Left);
    }

    #[test]
    fn qform_matches_nifti1_h() {
        // Identity quaternion, qfac −1: the third axis is negated (nibabel: diag([2, 3, -4, 1]) + offsets).
        let q = nifti_qform([0.0, 0.0, 0.0], -1.0, [2.0, 3.0, 4.0], [10.0, 20.0, 30.0]);
        let expected = from_rows([[2.0, 0.0, 0.0, 10.0], [0.0, 3.0, 0.0, 20.0], [0.0, 0.0, -4.0, 30.0]]);
        assert!((q - expected).abs().to_cols_array().iter().all(|&e| e < 1e-12), "{q}");
        // b = 1 (a = 0): a 180° turn about x, so j and k flip (nibabel quat2mat([0, 1, 0, 0]) = diag(1, −1, −1)).
        let q = nifti_qform([1.0, 0.0, 0.0], 1.0, [1.0, 1.0, 1.0], [0.0; 3]);
        assert!(
            (q - DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0)))
                .abs()
                .max_element_all()
                < 1e-12
        );
    }

    #[test]
    fn downsampling_keeps_the_world_box() {
        let g = Geometry::anatomical(from_rows([
            [-2.0, 0.0, 0.0, 50.0],
            [0.0, 3.0, 0.0, -10.0],
            [0.0, 0.0, 1.0, 5.0],
        ]));
        let d = g.downsampled([2, 2, 1]);
        // New voxel 0 is the centre of old voxels 0 and 1: old index 0.5.
        let p = d.affine.transform_point3(DVec3::ZERO);
        assert!((p - g.affine.transform_point3(DVec3::new(0.5, 0.5, 0.0))).length() < 1e-12);
        assert_eq!(d.spacing(), [4.0, 6.0, 1.0]);
    }

    #[test]
    fn tex_to_world_centres_and_scales_the_box() {
        // Along the axes: the old (tex − ½)·extent, whatever the origin.
        let g = Geometry::from_spacing([1.0, 2.0, 0.5]);
        let m = g.tex_to_world([10, 20, 8], false);
        let extent = DVec3::new(10.0, 40.0, 4.0) / 40.0;
        for tex in [DVec3::ZERO, DVec3::ONE, DVec3::new(0.25, 0.5, 0.75)] {
            assert!((m.transform_point3(tex) - (tex - 0.5) * extent).length() < 1e-12);
        }
        // LAS storage: +i runs to the left (−x), so texture x = 0 lies at world +x.
        let las = Geometry::anatomical(DMat4::from_diagonal(DVec4::new(-3.0, 3.0, 3.0, 1.0)));
        let m = las.tex_to_world([10, 10, 10], false);
        assert!((m.transform_point3(DVec3::ZERO) - DVec3::new(0.5, -0.5, -0.5)).length() < 1e-12);
        assert!(m.determinant() < 0.0, "mirrored");
        // In voxel axes the same volume is not mirrored.
        assert!(las.tex_to_world([10, 10, 10], true).determinant() > 0.0);
    }

    #[test]
    fn shear_and_labels() {
        let tilted = from_columns([DVec3::X, DVec3::Y, DVec3::new(0.0, 0.2, 1.0)], DVec3::ZERO);
        let g = Geometry::anatomical(tilted);
        assert!((g.shear_deg() - 0.2f64.atan().to_degrees()).abs() < 1e-9);
        assert_eq!(direction_label(DVec3::new(-0.9, 0.1, 0.3)), 'L');
        assert_eq!(direction_label(DVec3::new(0.1, 0.2, -0.8)), 'I');
        let las = Geometry::anatomical(DMat4::from_diagonal(DVec4::new(-3.0, 3.0, 3.0, 1.0)));
        assert_eq!(index_axis_names(&las)[0], "i (R->L)");
        assert_eq!(index_axis_names(&Geometry::from_spacing([1.0; 3]))[2], "z");
    }

    trait MaxAll {
        fn max_element_all(&self) -> f64;
    }

    impl MaxAll for DMat4 {
        fn max_element_all(&self) -> f64 {
            self.to_cols_array().iter().fold(0.0, |m, v| m.max(*v))
        }
    }

    #[test]
    fn spacing_prints_its_shortest_form_within_a_millionth() {
        let cases = [
            (f64::from(0.859_375_06f32), "0.859375"),
            (7.000_523_6, "7.00052"),
            (1.0, "1"),
            (0.5, "0.5"),
            (2.0 / 3.0, "0.666667"),
            (1234.5, "1234.5"),
            (0.0, "0"),
        ];
        for (x, want) in cases {
            assert_eq!(super::shortest(x), want, "{x}");
        }
    }
}
