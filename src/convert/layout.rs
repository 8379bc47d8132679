//! The store's OME-Zarr metadata: axes, each level's scale and translation, and volcast's exact placement.
//!
//! The convention (shared with volcast's OME-Zarr reader): array axes are ("z", "y", "x"), type "space", unit
//! "millimeter", after a leading ("t", "time") axis for a series; volcast's index x is the last array axis. Level 0's
//! scale is the affine's column lengths and its translation the world position of voxel (0, 0, 0), both in z, y, x
//! order. A level k voxel covers `f` fine voxels per axis (`f` = 2^k, less along an axis that reached length 1):
//! scale_k = f * scale_0 and translation_k = translation_0 + (f - 1) / 2 * scale_0, the centre of its block.
//! The full affine is always stored too, under the multiscale's `metadata.volcast` key, with the anatomical frame.

use crate::pyramid::geometry::spans;
use crate::volume::Geometry;
use serde_json::{json, Map, Value};

/// Which OME-Zarr (and so Zarr) version the store follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OmeVersion {
    /// OME-Zarr 0.4 on Zarr v2.
    V04,
    /// OME-Zarr 0.5 on Zarr v3.
    V05,
}

/// Where level 0 lies, as OME-Zarr's scale and translation (z, y, x) and as volcast's full affine.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    pub scale: [f64; 3],
    pub translation: [f64; 3],
    /// The affine is a positive diagonal scale plus a translation, so scale and translation say all of it.
    pub axis_aligned: bool,
    pub rows: [[f64; 4]; 4],
    pub anatomical: bool,
}

impl Placement {
    pub fn of(geometry: &Geometry) -> Placement {
        let [sx, sy, sz] = geometry.spacing();
        let o = geometry.origin();
        let l = geometry.linear().to_cols_array_2d();
        let axis_aligned = (0..3).all(|c| (0..3).all(|r| if r == c { l[c][r] > 0.0 } else { l[c][r] == 0.0 }));
        Placement {
            scale: [sz, sy, sx],
            translation: [o.z, o.y, o.x],
            axis_aligned,
            rows: geometry.rows(),
            anatomical: geometry.anatomical,
        }
    }

    /// Scale and translation (z, y, x) of a level whose voxels span `span` (x, y, z) level-0 voxels.
    pub fn at_level(&self, span: [u64; 3]) -> ([f64; 3], [f64; 3]) {
        let f = [span[2], span[1], span[0]].map(|n| n as f64);
        let scale = [0, 1, 2].map(|i| self.scale[i] * f[i]);
        let translation = [0, 1, 2].map(|i| self.translation[i] + (f[i] - 1.0) / 2.0 * self.scale[i]);
        (scale, translation)
    }
}

/// The multiscale object: name, axes, one dataset per level ("0", "1", ...), and volcast's placement.
pub fn multiscale(name: &str, version: OmeVersion, series: bool, p: &Placement, levels: &[[u64; 3]]) -> Value {
    let mut axes = Vec::new();
    if series {
        axes.push(json!({"name": "t", "type": "time"}));
    }
    for a in ["z", "y", "x"] {
        axes.push(json!({"name": a, "type": "space", "unit": "millimeter"}));
    }
    let datasets: Vec<Value> = spans(levels)
        .iter()
        .enumerate()
        .map(|(k, &span)| {
            let (mut scale, mut translation) = (Vec::new(), Vec::new());
            if series {
                scale.push(1.0);
                translation.push(0.0);
            }
            let (s, t) = p.at_level(span);
            scale.extend(s);
            translation.extend(t);
            json!({
                "path": k.to_string(),
                "coordinateTransformations": [
                    {"type": "scale", "scale": scale},
                    {"type": "translation", "translation": translation},
                ],
            })
        })
        .collect();
    let mut m = json!({
        "name": name,
        "axes": axes,
        "datasets": datasets,
        // Under the spec's free-form "metadata" dictionary: ome_zarr_metadata's 0.4 types refuse an unknown key
        // on the multiscale itself.
        "metadata": {"volcast": {"affine": p.rows, "frame": if p.anatomical { json!("RAS") } else { Value::Null }}},
    });
    if version == OmeVersion::V04 {
        m["version"] = json!("0.4");
    }
    m
}

/// The root group's attributes holding `multiscale`: under "ome" with its version in 0.5, bare in 0.4.
pub fn root_attributes(version: OmeVersion, multiscale: Value) -> Map<String, Value> {
    let value = match version {
        OmeVersion::V05 => json!({"ome": {"version": "0.5", "multiscales": [multiscale]}}),
        OmeVersion::V04 => json!({"multiscales": [multiscale]}),
    };
    match value {
        Value::Object(map) => map,
        _ => unreachable!("built as an object"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat4, DVec4};

    #[test]
    fn levels_are_placed_at_their_blocks_centres() {
        let mut g = Geometry::from_spacing([0.5, 2.0, 3.0]);
        g.affine.w_axis = DVec4::new(10.0, 20.0, 30.0, 1.0);
        let p = Placement::of(&g);
        assert!(p.axis_aligned);
        assert_eq!((p.scale, p.translation), ([3.0, 2.0, 0.5], [30.0, 20.0, 10.0]));
        assert_eq!(p.at_level([4, 4, 1]), ([3.0, 8.0, 2.0], [30.0, 23.0, 10.75]));
        assert_eq!(
            spans(&[[200, 100, 1], [100, 50, 1], [50, 25, 1]]),
            vec![[1, 1, 1], [2, 2, 1], [4, 4, 1]]
        );
        let flipped = Geometry::anatomical(DMat4::from_diagonal(DVec4::new(-3.0, 3.0, 3.0, 1.0)));
        let p = Placement::of(&flipped);
        assert!(!p.axis_aligned);
        assert_eq!(p.scale, [3.0, 3.0, 3.0]);
        let m = multiscale("v", OmeVersion::V05, false, &p, &[[2, 2, 2]]);
        assert_eq!(m["metadata"]["volcast"]["frame"], "RAS");
        assert_eq!(m["metadata"]["volcast"]["affine"][0][0], -3.0);
    }
}
