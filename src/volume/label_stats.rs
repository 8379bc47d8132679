//! Per-label statistics (3D Slicer's Segment Statistics): for every id of a label map, its voxel count, its volume
//! in mm³, and the mean, minimum and maximum of every other volume under it. The other volumes are sampled where
//! each label voxel's centre lies in millimetres, trilinearly on their own grids (no resampling), so a 3 mm map
//! is measured under a 1 mm atlas as it is shown.

use super::labels::{LabelMap, LabelTable};
use super::Volume;
use glam::DVec3;
use rayon::prelude::*;

/// One volume's values under one label.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Under {
    pub name: String,
    /// Label voxels whose centre lies inside this volume's box (the others are not counted).
    pub voxels: u64,
    pub mean: Option<f64>,
    pub min: Option<f64>,
    pub max: Option<f64>,
}

/// One label's row.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LabelRow {
    pub id: u32,
    pub name: String,
    pub voxels: u64,
    pub volume_mm3: f64,
    pub under: Vec<Under>,
}

/// Running sums of one volume under one label.
#[derive(Clone, Copy)]
struct Sums {
    n: u64,
    sum: f64,
    min: f64,
    max: f64,
}

impl Default for Sums {
    fn default() -> Sums {
        Sums {
            n: 0,
            sum: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl Sums {
    fn add(&mut self, v: f64) {
        *self = Sums {
            n: self.n + 1,
            sum: self.sum + v,
            min: self.min.min(v),
            max: self.max.max(v),
        };
    }

    fn merge(self, o: Sums) -> Sums {
        Sums {
            n: self.n + o.n,
            sum: self.sum + o.sum,
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
}

/// The rows of every id `map` holds (the background, id 0, left out), in id order; `others` are the volumes
/// measured under them, by name.
pub fn label_stats(labels: &Volume, map: &LabelMap, table: &LabelTable, others: &[(&str, &Volume)]) -> Vec<LabelRow> {
    let [w, h, d] = labels.dims.map(|n| n as usize);
    let ids = map.ids.len();
    // Per slice, per dense id, per other volume; merged over slices.
    let zero = || vec![Sums::default(); ids * others.len()];
    let to_other: Vec<glam::DMat4> = others
        .iter()
        .map(|(_, v)| v.geometry.affine.inverse() * labels.geometry.affine)
        .collect();
    let sums = (0..d)
        .into_par_iter()
        .fold(zero, |mut acc, z| {
            for y in 0..h {
                for x in 0..w {
                    let k = map.index[x + w * (y + h * z)] as usize;
                    if k == 0 {
                        continue;
                    }
                    let p = DVec3::new(x as f64, y as f64, z as f64);
                    for (o, ((_, v), m)) in others.iter().zip(&to_other).enumerate() {
                        if let Some(value) = sample(v, m.transform_point3(p)) {
                            acc[k * others.len() + o].add(value);
                        }
                    }
                }
            }
            acc
        })
        .reduce(zero, |a, b| a.into_iter().zip(b).map(|(x, y)| x.merge(y)).collect());
    let voxel_mm3 = labels.geometry.linear().determinant().abs();
    (1..ids)
        .map(|k| LabelRow {
            id: map.ids[k],
            name: table.name(map.ids[k]),
            voxels: map.counts[k],
            volume_mm3: map.counts[k] as f64 * voxel_mm3,
            under: others
                .iter()
                .enumerate()
                .map(|(o, (name, _))| {
                    let s = sums[k * others.len() + o];
                    let some = |x: f64| (s.n > 0).then_some(x);
                    Under {
                        name: name.to_string(),
                        voxels: s.n,
                        mean: some(s.sum / s.n.max(1) as f64),
                        min: some(s.min),
                        max: some(s.max),
                    }
                })
                .collect(),
        })
        .collect()
}

/// `v` at voxel index `i` (centres at integers): trilinear, clamped to the edge inside its box; None outside the
/// box or where the value is NaN.
fn sample(v: &Volume, i: DVec3) -> Option<f64> {
    let n = DVec3::from_array(v.dims.map(f64::from));
    if i.cmplt(DVec3::splat(-0.5)).any() || i.cmpgt(n - 0.5).any() {
        return None;
    }
    let c = i.clamp(DVec3::ZERO, n - 1.0);
    let lo = c.floor().min((n - 2.0).max(DVec3::ZERO));
    let f = c - lo;
    let hi = (lo + 1.0).min(n - 1.0);
    let mut sum = 0.0;
    for (z, wz) in [(lo.z, 1.0 - f.z), (hi.z, f.z)] {
        for (y, wy) in [(lo.y, 1.0 - f.y), (hi.y, f.y)] {
            for (x, wx) in [(lo.x, 1.0 - f.x), (hi.x, f.x)] {
                let weight = wx * wy * wz;
                if weight != 0.0 {
                    sum += weight * v.value(x as u32, y as u32, z as u32);
                }
            }
        }
    }
    (!sum.is_nan()).then_some(sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Geometry, VoxelData, VoxelType};
    use glam::DMat4;

    #[test]
    fn counts_volumes_and_values_under_each_label_on_another_grid() {
        // Labels 0 | 3 | 3 | 9 along x, 2 mm voxels; under them a 1 mm ramp whose value is its x in mm.
        let labels = Volume::new("l", [4, 1, 1], [2.0; 3], VoxelType::U8, VoxelData::U8(vec![0, 3, 3, 9])).unwrap();
        let ramp: Vec<f32> = (0..8).map(|x| x as f32).collect();
        let mut values = Volume::new("v", [8, 1, 1], [1.0; 3], VoxelType::F32, VoxelData::F32(ramp)).unwrap();
        values = values
            .with_geometry(Geometry {
                affine: DMat4::from_scale(DVec3::new(1.0, 2.0, 2.0)),
                anatomical: false,
            })
            .unwrap();
        let map = LabelMap::of(&labels).unwrap();
        let rows = label_stats(&labels, &map, &LabelTable::default(), &[("v", &values)]);
        assert_eq!(rows.len(), 2);
        assert_eq!((rows[0].id, rows[0].voxels, rows[0].volume_mm3), (3, 2, 16.0));
        // Label 3's centres are at x = 2 and 4 mm: the ramp reads 2 and 4 there.
        assert_eq!(
            (rows[0].under[0].mean, rows[0].under[0].min, rows[0].under[0].max),
            (Some(3.0), Some(2.0), Some(4.0))
        );
        assert_eq!(rows[1].under[0].mean, Some(6.0));
        assert_eq!(rows[1].name, "label 9");
    }
}
