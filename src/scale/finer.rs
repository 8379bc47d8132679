//! The levels finer than the one a volume holds. A file whose voxels lie in place on disk is held at the finest
//! level of the pyramid that the host budget takes; its finer levels stay in the file, and a streamed pool reads
//! their bricks as the view needs them: one box of level-0 voxels per brick (a positioned read per row), reduced
//! to the brick's level by the pyramid's rule (`pyramid::reduce`, recursively, each box aligned to 2^L so that the
//! cascade inside it is exactly the pyramid's). docs/large-volumes.md, "Full resolution from the file".

use crate::convert::source::Source;
use crate::formats::in_place::InPlace;
use crate::formats::zarr::boxes::ZarrBoxes;
use crate::pyramid::bricks::level0_box;
use crate::pyramid::geometry::level_dims;
use crate::pyramid::reduce::mean_to_level;
use crate::pyramid::sample::Sample;
use crate::volume::{FinerLevels, Geometry, VolumeError, VoxelData, VoxelType};
use rayon::prelude::*;

/// Where the level-0 boxes come from.
enum Boxes {
    /// A file in place.
    File(Source),
    /// An OME-Zarr store's level 0.
    Zarr(Box<ZarrBoxes>),
}

impl Boxes {
    fn name(&self) -> &str {
        match self {
            Boxes::File(s) => s.name(),
            Boxes::Zarr(z) => z.name(),
        }
    }

    /// The type the box is read in (wider types are held as float32, see [`FinerLevels::read`]).
    fn voxel_type(&self) -> VoxelType {
        match self {
            Boxes::File(s) => s.held_type(),
            Boxes::Zarr(z) => z.voxel_type,
        }
    }

    fn read_box<T: Sample>(&self, lo: [u32; 3], size: [u32; 3]) -> Result<Vec<T>, VolumeError> {
        match self {
            Boxes::File(s) => s.read_box::<T>(0, lo, size),
            Boxes::Zarr(z) => z.read_box::<T>(lo, size),
        }
    }
}

/// Where the levels below a held level come from.
pub struct Finer {
    source: Boxes,
    /// Level 0's size and placement.
    dims: [u32; 3],
    geometry: Geometry,
    /// The level the volume holds: levels 0..held come from the file.
    held: u32,
    /// Where the boxes are read from, as a note says it.
    origin: &'static str,
}

impl std::fmt::Debug for Finer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Finer({}, {:?} below level {})",
            self.source.name(),
            self.dims,
            self.held
        )
    }
}

impl Finer {
    /// The finer levels of `place`, held at level `held`: only for one step of voxels that lie uncompressed in the
    /// file (`InPlace::by_box`: a compressed stream cannot be read by box, and compressed blocks would be decoded once
    /// per row) and a held level above 0.
    pub fn of(place: &InPlace, held: u32) -> Result<Option<Finer>, VolumeError> {
        if held == 0 || !place.by_box() {
            return Ok(None);
        }
        Ok(Some(Finer {
            source: Boxes::File(Source::in_place(place.clone())?),
            dims: place.dims,
            geometry: place.geometry,
            held,
            origin: "the file",
        }))
    }

    /// [`Finer::of`] a decoded file's level 0 kept in the pyramid cache (`scale::level0`), as the notes name it.
    pub fn of_kept(place: &InPlace, held: u32) -> Result<Option<Finer>, VolumeError> {
        Ok(Finer::of(place, held)?.map(|f| Finer {
            origin: "its level 0 kept in the pyramid cache",
            ..f
        }))
    }

    /// The finer levels of an OME-Zarr store's level 0, `boxes`, held at level `held` (`zarr::boxes::finer_of`).
    pub fn of_zarr(boxes: ZarrBoxes, held: u32) -> Finer {
        Finer {
            dims: boxes.dims,
            geometry: boxes.geometry,
            source: Boxes::Zarr(Box::new(boxes)),
            held,
            origin: "the store's level 0",
        }
    }

    /// The box of level `level` from the level-0 box under it, halved `level` times.
    fn box_at<T: Sample>(&self, level: u32, lo: [u32; 3], size: [u32; 3]) -> Result<Vec<T>, VolumeError> {
        let (lo0, size0) = level0_box(self.dims, level, lo, size);
        let data = self.source.read_box::<T>(lo0, size0)?;
        let (data, dims) = mean_to_level(data, size0.map(|d| d as usize), self.dims, level);
        debug_assert_eq!(dims, size.map(|s| s as usize));
        Ok(data)
    }
}

impl FinerLevels for Finer {
    fn dims(&self) -> [u32; 3] {
        self.dims
    }

    fn geometry(&self) -> Geometry {
        self.geometry
    }

    fn held(&self) -> u32 {
        self.held
    }

    fn origin(&self) -> &'static str {
        self.origin
    }

    /// The box must lie within the level; the representation is the held level's (biased 8/16-bit integers,
    /// float32 for wider types).
    fn read(&self, level: u32, lo: [u32; 3], size: [u32; 3]) -> Result<VoxelData, VolumeError> {
        let within = level_dims(self.dims, level);
        if level >= self.held || (0..3).any(|a| size[a] == 0 || lo[a] + size[a] > within[a]) {
            return Err(VolumeError::Header {
                file: self.source.name().to_string(),
                problem: format!("no box {lo:?}+{size:?} in level {level} below level {}", self.held),
            });
        }
        Ok(match self.source.voxel_type() {
            VoxelType::U8 => VoxelData::U8(self.box_at::<u8>(level, lo, size)?),
            VoxelType::I8 => VoxelData::U8(
                (self.box_at::<i8>(level, lo, size)?.into_par_iter())
                    .map(|v| (i16::from(v) + 128) as u8)
                    .collect(),
            ),
            VoxelType::U16 => VoxelData::U16(self.box_at::<u16>(level, lo, size)?),
            VoxelType::I16 => VoxelData::U16(
                (self.box_at::<i16>(level, lo, size)?.into_par_iter())
                    .map(|v| (i32::from(v) + 32768) as u16)
                    .collect(),
            ),
            _ => VoxelData::F32(self.box_at::<f32>(level, lo, size)?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::in_place::in_place;
    use crate::scale::read::read_level;

    /// Every box of every finer level equals that level of the pyramid read whole, at odd sizes and offsets.
    #[test]
    fn boxes_of_finer_levels_equal_the_pyramid() {
        let dims = [13u32, 9, 11];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let src: Vec<i16> = (0..n).map(|i| ((i * 7919) % 601) as i16 - 300).collect();
        let (path, opts) = crate::scale::test_file::int16_raw("finer", dims, &src, None);
        let place = in_place(&path, &opts).unwrap().unwrap();
        let finer = Finer::of(&place, 3).unwrap().expect("raw has finer levels");
        let whole = Source::in_place(place).unwrap();
        for level in 0..3 {
            let full = if level == 0 {
                crate::formats::open(&path, &opts).unwrap()
            } else {
                read_level(&whole, level, 1 << 30, Vec::new(), &mut |_| {}).unwrap()
            };
            let ld = full.dims;
            let half = ld.map(|d| d / 2);
            let rest = [0, 1, 2].map(|a| ld[a] - half[a]);
            for (lo, size) in [
                ([0, 0, 0], ld),
                (half, rest),
                ([ld[0] - 1, 0, ld[2] - 1], [1, ld[1], 1]),
            ] {
                let VoxelData::U16(got) = finer.read(level, lo, size).unwrap() else {
                    panic!("int16 is held as biased uint16")
                };
                let VoxelData::U16(all) = &full.data else { panic!() };
                for z in 0..size[2] {
                    for y in 0..size[1] {
                        for x in 0..size[0] {
                            let at = |p: [u32; 3], d: [u32; 3]| (p[0] + d[0] * (p[1] + d[1] * p[2])) as usize;
                            let want = all[at([lo[0] + x, lo[1] + y, lo[2] + z], ld)];
                            assert_eq!(
                                got[at([x, y, z], size)],
                                want,
                                "level {level} box {lo:?} at {x},{y},{z}"
                            );
                        }
                    }
                }
            }
        }
        assert!(
            finer.read(3, [0; 3], [1; 3]).is_err(),
            "the held level is not read from the file"
        );
        assert!(
            finer.read(0, [12, 0, 0], [2, 1, 1]).is_err(),
            "a box past the level's edge"
        );
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }
}
