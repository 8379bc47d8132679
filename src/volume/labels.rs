//! Label maps: volumes of integer ids (a segmentation, an atlas), their ids made dense for the GPU, and the table
//! that names and colours them. Pure model; `formats::label_table` reads tables from files.

use super::{Volume, VoxelType};

/// The largest id a label map may hold: 32-bit ids reach the GPU as f32 (volume/mod.rs), whose 24-bit mantissa
/// keeps every integer up to 2^24 exact and no more.
pub const MAX_LABEL_ID: f64 = 16_777_216.0;

/// Why a volume is not a label map.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LabelError {
    #[error("'{name}' holds {kind} values, not integer label ids: a label map must be uint8, uint16, uint32 (or int8/int16/int32 without negative ids); give it with --overlay instead")]
    NotIntegers { name: String, kind: &'static str },
    #[error("'{name}' holds the negative id {id}: label ids must be 0 (background) or positive")]
    Negative { name: String, id: i64 },
    #[error("'{name}' holds the id {id}, above the largest id volcast keeps exact ({MAX_LABEL_ID}, 2^24)")]
    TooLarge { name: String, id: f64 },
}

/// A label map made dense: `ids[k]` is the id of dense index k (`ids[0]` = 0, the background, always), and
/// `index` holds every voxel's dense index, x fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelMap {
    pub ids: Vec<u32>,
    pub index: Vec<u32>,
    /// Voxels per dense index.
    pub counts: Vec<u64>,
}

impl LabelMap {
    /// The ids of `volume`, which must hold non-negative integers no larger than [`MAX_LABEL_ID`].
    pub fn of(volume: &Volume) -> Result<LabelMap, LabelError> {
        let name = volume.name.clone();
        let raw = (0..volume.voxel_count())
            .map(|i| label_id(volume.value_at_index(i), &name, volume.source_type))
            .collect::<Result<Vec<u32>, _>>()?;
        let mut ids = raw.clone();
        ids.push(0);
        ids.sort_unstable();
        ids.dedup();
        let mut counts = vec![0u64; ids.len()];
        let index: Vec<u32> = raw
            .iter()
            .map(|id| {
                let k = ids.binary_search(id).expect("every id is listed");
                counts[k] += 1;
                k as u32
            })
            .collect();
        Ok(LabelMap { ids, index, counts })
    }

    /// The dense index of `id` (None: the map lacks it).
    pub fn dense(&self, id: u32) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }
}

/// One voxel's id: an integer (a float file may hold integers exactly: a NIfTI atlas stored as float32).
fn label_id(v: f64, name: &str, ty: VoxelType) -> Result<u32, LabelError> {
    if !v.is_finite() || v.fract() != 0.0 {
        return Err(LabelError::NotIntegers {
            name: name.to_string(),
            kind: if matches!(ty, VoxelType::F32 | VoxelType::F64) {
                "float"
            } else {
                "non-integer"
            },
        });
    }
    if v < 0.0 {
        return Err(LabelError::Negative {
            name: name.to_string(),
            id: v as i64,
        });
    }
    if v > MAX_LABEL_ID {
        return Err(LabelError::TooLarge {
            name: name.to_string(),
            id: v,
        });
    }
    Ok(v as u32)
}

/// One row of a label table: an id, its name and its sRGB colour with opacity (0–255).
#[derive(Clone, Debug, PartialEq)]
pub struct LabelEntry {
    pub id: u32,
    pub name: String,
    pub rgba: [u8; 4],
}

/// The names and colours of a label map's ids, sorted by id; ids it lacks get [`default_colour`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabelTable {
    pub entries: Vec<LabelEntry>,
}

impl LabelTable {
    pub fn get(&self, id: u32) -> Option<&LabelEntry> {
        self.entries
            .binary_search_by_key(&id, |e| e.id)
            .ok()
            .map(|i| &self.entries[i])
    }

    /// The colour of `id`: the table's, else the default. Id 0, the background, is transparent.
    pub fn rgba(&self, id: u32) -> [u8; 4] {
        if id == 0 {
            return [0; 4];
        }
        self.get(id).map_or_else(
            || {
                let [r, g, b] = default_colour(id);
                [r, g, b, 255]
            },
            |e| e.rgba,
        )
    }

    /// The name of `id`, or `label <id>`.
    pub fn name(&self, id: u32) -> String {
        self.get(id).map_or_else(|| format!("label {id}"), |e| e.name.clone())
    }
}

/// A distinct, stable colour for any id (sRGB): hues a golden angle apart (id·0.618… turns), so neighbouring
/// ids differ strongly, at a saturation and value that alternate over three steps so ids a few turns apart still
/// differ. The same id always gets the same colour, in every file and session.
pub fn default_colour(id: u32) -> [u8; 3] {
    const GOLDEN: f64 = 0.618_033_988_749_895;
    let hue = (f64::from(id) * GOLDEN).fract();
    let (s, v) = [(0.65, 0.95), (0.85, 0.80), (0.50, 0.85)][(id % 3) as usize];
    hsv(hue, s, v)
}

fn hsv(h: f64, s: f64, v: f64) -> [u8; 3] {
    let i = (h * 6.0).floor();
    let f = h * 6.0 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - f * s), v * (1.0 - (1.0 - f) * s));
    let (r, g, b) = match i as i32 % 6 {
        0 => (v, t, p),
        1 => (q, v, p),
        2 => (p, v, t),
        3 => (p, q, v),
        4 => (t, p, v),
        _ => (v, p, q),
    };
    [r, g, b].map(|c| (c * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelData;

    fn map_of(values: Vec<f32>) -> Result<LabelMap, LabelError> {
        let n = values.len() as u32;
        let v = Volume::new("m", [n, 1, 1], [1.0; 3], VoxelType::F32, VoxelData::F32(values)).unwrap();
        LabelMap::of(&v)
    }

    #[test]
    fn sparse_ids_are_made_dense_with_the_background_first() {
        let m = map_of(vec![7.0, 1_000_000.0, 7.0, 3.0]).unwrap();
        assert_eq!(m.ids, [0, 3, 7, 1_000_000]);
        assert_eq!(m.index, [2, 3, 2, 1]);
        assert_eq!(m.counts, [0, 1, 2, 1]);
        assert_eq!(m.dense(7), Some(2));
        assert_eq!(m.dense(8), None);
    }

    #[test]
    fn floats_and_negative_ids_are_refused_by_name() {
        let e = map_of(vec![1.5]).unwrap_err().to_string();
        assert!(e.contains("'m'") && e.contains("not integer"), "{e}");
        let e = map_of(vec![-2.0]).unwrap_err().to_string();
        assert!(e.contains("negative id -2"), "{e}");
        let e = map_of(vec![3e7]).unwrap_err().to_string();
        assert!(e.contains("2^24"), "{e}");
    }

    #[test]
    fn default_colours_are_stable_and_distinct_between_neighbours() {
        assert_eq!(default_colour(5), default_colour(5));
        for id in 1..300u32 {
            let (a, b) = (default_colour(id), default_colour(id + 1));
            let d: i32 = (0..3).map(|i| (i32::from(a[i]) - i32::from(b[i])).abs()).sum();
            assert!(d > 60, "ids {id} and {} look alike: {a:?} {b:?}", id + 1);
        }
        let t = LabelTable::default();
        assert_eq!(t.rgba(0), [0; 4]);
        assert_eq!(t.name(4), "label 4");
    }
}
