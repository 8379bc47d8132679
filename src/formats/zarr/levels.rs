//! Which level of a multiscale image to load: the finest whose every dimension is within the caller's maximum and
//! whose voxels are within [`MAX_VOXELS`]. A level that fits is read as stored (never downsampled); only when even
//! the coarsest is too large does the open path's downsampling take over.

use super::metadata::{AxisRole, Multiscale};
use crate::volume::{MAX_DIM, MAX_VOXELS};

/// A level's size in volcast's terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LevelSize {
    /// x (the last space axis), y, z (1 for a 2-D image).
    pub dims: [u64; 3],
    pub timesteps: u64,
    pub channels: u64,
}

impl LevelSize {
    /// The sizes of an array of `shape` under `ms`'s axes; `None` if the ranks disagree.
    pub fn of(ms: &Multiscale, shape: &[u64]) -> Option<LevelSize> {
        if shape.len() != ms.axes.len() {
            return None;
        }
        let space = ms.space_axes();
        let n = space.len();
        let dims = [
            shape[space[n - 1]],
            shape[space[n - 2]],
            if n == 3 { shape[space[0]] } else { 1 },
        ];
        let along = |role| ms.axis_index(role).map_or(1, |i| shape[i]);
        Some(LevelSize {
            dims,
            timesteps: along(AxisRole::Time),
            channels: along(AxisRole::Channel),
        })
    }

    pub fn voxels(&self) -> u64 {
        self.dims.iter().fold(1u64, |a, &d| a.saturating_mul(d))
    }

    pub fn text(&self) -> String {
        format!("{}x{}x{}", self.dims[0], self.dims[1], self.dims[2])
    }

    /// Why this level is too large for `max_dim`, or `None` if it fits.
    pub fn too_large(&self, max_dim: u32) -> Option<String> {
        let limit = max_dim.min(MAX_DIM);
        if let Some(&d) = self.dims.iter().find(|&&d| d > u64::from(limit)) {
            let which = if max_dim < MAX_DIM {
                "the maximum dimension"
            } else {
                "volcast's limit"
            };
            return Some(format!("{d} exceeds {which} {limit}"));
        }
        let v = self.voxels();
        (v > MAX_VOXELS).then(|| format!("{v} voxels exceed the limit of {MAX_VOXELS}"))
    }

    /// Within volcast's hard limits (what downsampling can still bring under a smaller maximum).
    pub fn loadable(&self) -> bool {
        self.dims.iter().all(|&d| (1..=u64::from(MAX_DIM)).contains(&d)) && self.voxels() <= MAX_VOXELS
    }
}

/// The level to load among `sizes` (finest first, read up to the first that fits, of `count` levels) and a note
/// naming it and why finer ones were passed over. `Err` when even the coarsest cannot be loaded at all.
pub(crate) fn choose(
    sizes: &[LevelSize],
    misfits: &[Option<String>],
    count: usize,
    max_dim: u32,
) -> Result<(usize, Option<String>), String> {
    let fits = (0..sizes.len()).position(|i| sizes[i].too_large(max_dim).is_none() && misfits[i].is_none());
    let index = match fits {
        Some(i) => i,
        None => {
            let coarsest = sizes.len() - 1;
            if !sizes[coarsest].loadable() {
                let why = sizes[coarsest]
                    .too_large(MAX_DIM)
                    .unwrap_or_else(|| "it has a zero dimension".into());
                return Err(format!(
                    "even its coarsest level ({coarsest}, {}) is too large to load: {why}",
                    sizes[coarsest].text()
                ));
            }
            coarsest
        }
    };
    let mut note = format!("level {index} of {count} ({})", sizes[index].text());
    if index > 0 {
        let why = sizes[0]
            .too_large(max_dim)
            .or_else(|| misfits[0].clone())
            .unwrap_or_default();
        note.push_str(&format!("; level 0 ({}) is too large: {why}", sizes[0].text()));
    }
    if fits.is_none() {
        note.push_str("; no level fits, so the coarsest is downsampled");
    }
    Ok((index, (count > 1 || index > 0).then_some(note)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size(x: u64, y: u64, z: u64) -> LevelSize {
        LevelSize {
            dims: [x, y, z],
            timesteps: 1,
            channels: 1,
        }
    }

    #[test]
    fn the_finest_level_that_fits_is_chosen() {
        let sizes = [size(1024, 1024, 512), size(512, 512, 256), size(256, 256, 128)];
        let (i, note) = choose(&sizes, &[None, None, None][..sizes.len()], sizes.len(), 512).unwrap();
        assert_eq!(i, 1);
        let note = note.unwrap();
        assert!(note.starts_with("level 1 of 3 (512x512x256); level 0 (1024x1024x512) is too large: 1024 exceeds the maximum dimension 512"), "{note}");
        assert_eq!(
            choose(&sizes, &vec![None; sizes.len()], sizes.len(), 2048).unwrap().0,
            0
        );
        let (i, note) = choose(&sizes, &[None, None, None][..sizes.len()], sizes.len(), 100).unwrap();
        assert_eq!(i, 2);
        assert!(note.unwrap().contains("downsampled"));
    }

    #[test]
    fn petabyte_levels_are_refused() {
        let sizes = [size(1 << 30, 1 << 30, 1 << 30)];
        let e = choose(&sizes, &vec![None; sizes.len()], sizes.len(), 2048).unwrap_err();
        assert!(e.contains("too large to load"), "{e}");
        let voxels = [size(16384, 16384, 16384)];
        assert!(choose(&voxels, &[None], 1, 16384).is_err());
    }
}
