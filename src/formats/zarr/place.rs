//! A level's voxel-to-world affine: OME-Zarr's per-axis scale and translation (x the last space axis), or volcast's
//! own level-0 affine carried to the level (see docs/formats.md, "OME-Zarr").

use super::metadata::{LevelInfo, Multiscale, VolcastHint};
use glam::{DMat4, DVec4};

/// The (x, y, z) scale and translation of `level` in millimetres; a 2-D image gets a z step equal to its smaller
/// in-plane step and z 0.
pub(crate) fn xyz(ms: &Multiscale, level: &LevelInfo) -> ([f64; 3], [f64; 3]) {
    let space = ms.space_axes();
    let n = space.len();
    let pick = |v: &[f64], k: usize| v[space[n - 1 - k]];
    let mut scale = [pick(&level.scale, 0), pick(&level.scale, 1), 0.0];
    let mut shift = [pick(&level.translation, 0), pick(&level.translation, 1), 0.0];
    if n == 3 {
        scale[2] = pick(&level.scale, 2);
        shift[2] = pick(&level.translation, 2);
    } else {
        scale[2] = scale[0].abs().min(scale[1].abs());
    }
    (scale, shift)
}

/// The affine of level `k` and whether it is anatomical (RAS), with a note when volcast's hint was not used.
pub(crate) fn affine(ms: &Multiscale, k: usize, notes: &mut Vec<String>) -> (DMat4, bool) {
    let (scale, shift) = xyz(ms, &ms.levels[k]);
    let plain = DMat4::from_cols(
        DVec4::new(scale[0], 0.0, 0.0, 0.0),
        DVec4::new(0.0, scale[1], 0.0, 0.0),
        DVec4::new(0.0, 0.0, scale[2], 0.0),
        DVec4::new(shift[0], shift[1], shift[2], 1.0),
    );
    let Some(hint) = &ms.hint else {
        return (plain, false);
    };
    let (scale0, shift0) = xyz(ms, &ms.levels[0]);
    match from_hint(hint, scale0, shift0, scale, shift) {
        Some(a) => (a, hint.ras),
        None => {
            notes.push("volcast placement metadata ignored: its voxel sizes disagree with the level-0 scale".into());
            (plain, false)
        }
    }
}

/// Level-0 affine `hint` moved to a level of (`scale`, `shift`): columns scaled by scale / scale0, origin at the
/// level's translation mapped through the level-0 affine. `None` when the hint's column lengths are not the level-0
/// voxel sizes.
fn from_hint(
    hint: &VolcastHint,
    scale0: [f64; 3],
    shift0: [f64; 3],
    scale: [f64; 3],
    shift: [f64; 3],
) -> Option<DMat4> {
    let a0 = DMat4::from_cols_array_2d(&hint.affine).transpose();
    let consistent = (0..3).all(|i| {
        let len = a0.col(i).truncate().length();
        (len - scale0[i].abs()).abs() <= 1e-4 * scale0[i].abs().max(1e-12)
    });
    if !consistent || a0.row(3) != DVec4::new(0.0, 0.0, 0.0, 1.0) {
        return None;
    }
    let mut out = a0;
    let mut at = DVec4::W;
    for i in 0..3 {
        *out.col_mut(i) = a0.col(i) * (scale[i] / scale0[i]);
        at[i] = (shift[i] - shift0[i]) / scale0[i];
    }
    *out.col_mut(3) = a0 * at;
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hint_moves_to_a_coarser_level_by_voxel_centres() {
        // Level 0 flips x (RAS from LPS-like storage); level 1 doubles every step, shifted by half a level-0 voxel.
        let hint = VolcastHint {
            affine: [
                [-2.0, 0.0, 0.0, 100.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 3.0, 5.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
            ras: true,
            scaling: None,
        };
        let a = from_hint(&hint, [2.0, 1.0, 3.0], [0.0; 3], [4.0, 2.0, 6.0], [1.0, 0.5, 1.5]).unwrap();
        // Level-1 voxel 0 is level-0 voxel 0.5: x = 100 - 2 * 0.5.
        assert_eq!(a.w_axis, DVec4::new(99.0, 0.5, 6.5, 1.0));
        assert_eq!(a.x_axis, DVec4::new(-4.0, 0.0, 0.0, 0.0));
        assert!(from_hint(&hint, [1.0, 1.0, 3.0], [0.0; 3], [1.0; 3], [0.0; 3]).is_none());
    }
}
