//! What one rank holds of the volume: its held box (its k-d box and the ghost layer), read from the file by box where
//! the voxels lie in place (raw, NRRD, MetaImage, NIfTI, uncompressed `.vti`), else cut from the volume read whole;
//! and the whole volume's header that every rank builds its settings from.

use super::decompose::Box3;
use crate::cli::args::VolumeArgs;
use crate::volume::{FinerLevels, Geometry, Volume, VoxelData};
use anyhow::{Context, Result};

/// A rank's part and what it cost to read.
pub struct Part {
    /// The held box's voxels, as a volume of its own (range and scaling still the part's own until `run::globalise_range`).
    pub volume: Volume,
    pub whole_dims: [u32; 3],
    pub geometry: Geometry,
    /// Bytes this rank read from the file.
    pub bytes_read: u64,
    /// Whether the part was read by box (else the whole volume was read and cut).
    pub by_box: bool,
}

/// The whole volume's size and placement, from its header alone where the file is read by box.
pub enum Source {
    ByBox {
        finer: Box<crate::scale::finer::Finer>,
        name: String,
        scaling: crate::volume::Scaling,
        voxel_type: crate::volume::VoxelType,
    },
    Whole(Box<Volume>),
}

impl Source {
    /// Opens the volume `args` names: by box where its voxels lie in place uncompressed (a single time step), else
    /// read whole (the built-ins, compressed files, DICOM, TIFF, OME-Zarr, series).
    pub fn open(args: &VolumeArgs) -> Result<(Source, [u32; 3], Geometry)> {
        if let (Some(path), None) = (&args.file, &args.time) {
            let opts = args.open_options()?;
            if let Some(place) = crate::formats::in_place::in_place(path, &opts)? {
                if place.by_box() && place.timesteps <= 1 {
                    let (dims, mut geometry) = (place.dims, place.geometry);
                    // --spacing overrides the file's, as `VolumeArgs::load` applies it.
                    if let Some(sp) = &args.spacing {
                        geometry = geometry.with_spacing([sp[0], sp[1], sp[2]].map(f64::from));
                    }
                    let voxel_type = place.voxel_type;
                    let (name, scaling) = (place.name.clone(), place.scaling);
                    // "Held" at level 1 so that level 0 is read by box; only level 0 is ever read.
                    let finer = crate::scale::finer::Finer::of(&place, 1)?
                        .with_context(|| format!("{} cannot be read by box", path.display()))?;
                    return Ok((
                        Source::ByBox {
                            finer: Box::new(finer),
                            name,
                            scaling,
                            voxel_type,
                        },
                        dims,
                        geometry,
                    ));
                }
            }
        }
        let v = args.load()?;
        let (dims, geometry) = (v.dims, v.geometry);
        Ok((Source::Whole(Box::new(v)), dims, geometry))
    }

    /// Checks that the box `held` fits the host budget `budget` (bytes) as the rank will hold it, before it is read:
    /// a part over it names the sizes and asks for more ranks. (A volume read whole was fitted by its load.)
    pub fn check_budget(&self, held: Box3, budget: u64) -> Result<()> {
        if let Source::ByBox { voxel_type, .. } = self {
            let bytes = held.voxels() * crate::pyramid::budget::held_bytes(*voxel_type);
            if bytes > budget {
                anyhow::bail!(crate::cli::UsageError(format!(
                    "this rank's part ({:?}..{:?}, ghost layer included) needs {} MiB, over the host budget of {} MiB \
                     (--host-budget): use more ranks",
                    held.lo,
                    held.hi,
                    bytes >> 20,
                    budget >> 20
                )));
            }
        }
        Ok(())
    }

    /// Reads `held` (a box of the whole volume) as a volume of its own.
    pub fn read(&self, held: Box3, whole_dims: [u32; 3], geometry: Geometry) -> Result<Part> {
        let size = [0, 1, 2].map(|a| held.hi[a] - held.lo[a]);
        let spacing = geometry.spacing().map(|s| s as f32);
        let (volume, bytes_read, by_box) = match self {
            Source::ByBox {
                finer,
                name,
                scaling,
                voxel_type,
            } => {
                let data = finer.read(0, held.lo, size)?;
                let v = Volume::new(name.clone(), size, spacing, *voxel_type, data)?.with_scaling(*scaling)?;
                (v, held.voxels() * voxel_type.size() as u64, true)
            }
            Source::Whole(whole) => {
                let data = crop(&whole.data, whole.dims, held);
                let mut v = Volume::new(whole.name.clone(), size, spacing, whole.source_type, data)?
                    .with_scaling(whole.scaling)?;
                v.format = whole.format.clone();
                let bytes = whole.voxel_count() as u64 * whole.source_type.size() as u64;
                v.modality = whole.modality.clone();
                v.channels = whole.channels.clone();
                (v, bytes, false)
            }
        };
        Ok(Part {
            volume,
            whole_dims,
            geometry,
            bytes_read,
            by_box,
        })
    }
}

/// The voxels of box `b` of `data` (a volume of `dims`), x fastest.
pub fn crop(data: &VoxelData, dims: [u32; 3], b: Box3) -> VoxelData {
    fn cut<T: Copy>(d: &[T], dims: [u32; 3], b: Box3) -> Vec<T> {
        let mut out = Vec::with_capacity(b.voxels() as usize);
        let (w, h) = (dims[0] as usize, dims[1] as usize);
        for z in b.lo[2] as usize..b.hi[2] as usize {
            for y in b.lo[1] as usize..b.hi[1] as usize {
                let row = (z * h + y) * w;
                out.extend_from_slice(&d[row + b.lo[0] as usize..row + b.hi[0] as usize]);
            }
        }
        out
    }
    match data {
        VoxelData::U8(d) => VoxelData::U8(cut(d, dims, b)),
        VoxelData::U16(d) => VoxelData::U16(cut(d, dims, b)),
        VoxelData::F32(d) => VoxelData::F32(cut(d, dims, b)),
    }
}

/// The whole volume as the settings see it: `part`'s facts with the whole's size, placement and (already
/// reduced) range, and no voxels.
pub fn header(part: &Volume, whole_dims: [u32; 3], geometry: Geometry) -> Volume {
    Volume {
        name: part.name.clone(),
        dims: whole_dims,
        geometry,
        source_type: part.source_type,
        data: match part.data {
            VoxelData::U8(_) => VoxelData::U8(Vec::new()),
            VoxelData::U16(_) => VoxelData::U16(Vec::new()),
            VoxelData::F32(_) => VoxelData::F32(Vec::new()),
        },
        range: part.range,
        stored_range: part.stored_range,
        scaling: part.scaling,
        format: part.format.clone(),
        modality: part.modality.clone(),
        notes: Vec::new(),
        arrays: Vec::new(),
        series: Vec::new(),
        time: Default::default(),
        channels: part.channels.clone(),
        finer: None,
        cells: None,
        source_voxels: part.source_voxels,
    }
}

/// Counts of `volume`'s normalised values in `bins` bins over the voxels of `owned` (its own coordinates): the
/// automatic transfer function's histogram (`transfer::auto::value_histogram`), summed over the ranks' boxes.
pub fn histogram(volume: &Volume, owned: Box3, bins: usize) -> Vec<u64> {
    let data = crop(&volume.data, volume.dims, owned);
    let mut h = vec![0u64; bins];
    let bin = |v: f64| ((v.clamp(0.0, 1.0) * bins as f64) as usize).min(bins - 1);
    // 8- and 16-bit elements are counted by element, then each element value is normalised once.
    let mut by_element = |counts: Vec<u64>| {
        for (e, &n) in counts.iter().enumerate().filter(|(_, &n)| n > 0) {
            let v = volume.normalize_element(e as f64);
            if v.is_finite() {
                h[bin(v)] += n;
            }
        }
    };
    fn count(elements: impl Iterator<Item = usize>, size: usize) -> Vec<u64> {
        let mut n = vec![0u64; size];
        elements.for_each(|e| n[e] += 1);
        n
    }
    match &data {
        VoxelData::U8(d) => by_element(count(d.iter().map(|&e| usize::from(e)), 256)),
        VoxelData::U16(d) => by_element(count(d.iter().map(|&e| usize::from(e)), 65536)),
        VoxelData::F32(d) => {
            for &e in d {
                let v = volume.normalize_element(f64::from(e));
                if v.is_finite() {
                    h[bin(v)] += 1;
                }
            }
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distributed::decompose::Decomposition;
    use crate::volume::VoxelType;

    fn volume(dims: [u32; 3]) -> Volume {
        let n = dims.iter().product::<u32>() as usize;
        let data: Vec<i16> = (0..n).map(|i| ((i * 7919) % 3001) as i16 - 1000).collect();
        let biased = data.iter().map(|&v| (i32::from(v) + 32768) as u16).collect();
        Volume::new("t", dims, [1.0; 3], VoxelType::I16, VoxelData::U16(biased)).unwrap()
    }

    /// The ranks' histograms over their own boxes add up to the whole volume's, and crops are the boxes' voxels.
    #[test]
    fn box_histograms_add_up_to_the_whole_volumes() {
        let whole = volume([37, 29, 23]);
        let want = crate::transfer::auto::value_histogram(&whole, 64);
        let d = Decomposition::new(whole.dims, 5).unwrap();
        let mut sum = vec![0u64; 64];
        for b in &d.boxes {
            for (s, h) in sum.iter_mut().zip(histogram(&whole, *b, 64)) {
                *s += h;
            }
            let VoxelData::U16(part) = crop(&whole.data, whole.dims, *b) else {
                panic!()
            };
            let at = |x: u32, y: u32, z: u32| whole.data.as_u16().unwrap()[(x + 37 * (y + 29 * z)) as usize];
            assert_eq!(part[0], at(b.lo[0], b.lo[1], b.lo[2]));
            assert_eq!(*part.last().unwrap(), at(b.hi[0] - 1, b.hi[1] - 1, b.hi[2] - 1));
            assert_eq!(part.len() as u64, b.voxels());
        }
        assert_eq!(sum, want);
    }

    #[test]
    fn the_header_is_the_whole_volume_without_voxels() {
        let part = volume([8, 8, 8]);
        let h = header(&part, [100, 90, 80], part.geometry);
        assert_eq!((h.dims, h.voxel_count(), h.data.len()), ([100, 90, 80], 720_000, 0));
        assert_eq!((h.range, h.source_type), (part.range, VoxelType::I16));
    }
}
