//! Volumes on the CPU: voxel types, the `Volume` the renderer uploads, its placement in the world, time steps and
//! value ranges, and generated test volumes ([`builtin`]). Pure code, no Vulkan, and no files: the readers of the
//! `formats` room make volumes from files, and nothing here names them.
//!
//! Layout everywhere: x fastest, then y, then z; voxel (x, y, z) is at `x + W·(y + H·z)`.
//!
//! Source types and what reaches the GPU: uint8 -> U8; int8 -> U8 biased by +128; uint16 -> U16; int16 -> U16
//! biased by +32768; uint32, int32, float32 and float64 -> F32. 32-bit integers become f32 because no 16-bit
//! texture holds them and imaging data rarely exceeds 2^24 (beyond that, values round to f32's 24-bit mantissa).
//! A linear rescale from the file (NIfTI `scl_slope`/`scl_inter`, DICOM rescale slope/intercept) is *not*
//! applied to the stored voxels: it is kept in [`Volume::scaling`] and folded into [`Volume::value`],
//! [`Volume::range`] and [`Volume::gpu_scale_bias`], so a 12-bit CT with an intercept of -1024 still takes two
//! bytes per voxel on the GPU and no precision is lost.

mod builtin;
pub mod cells;
mod contents;
mod error;
pub mod geometry;
pub mod huge_pages;
pub mod label_stats;
pub mod labels;
pub(crate) mod limits;
pub(crate) mod time;
pub(crate) mod voxel;

pub use builtin::{builtin, BUILTIN_NAMES};
pub use contents::{ArrayInfo, ChannelInfo, SeriesInfo, CHANNEL_COLOURS};
pub(crate) use error::clip;
pub use error::{MissingLayout, VolumeError};
pub use time::TimeSteps;
pub(crate) use voxel::stored_offset;
use voxel::{compute_range, compute_range_of, stored_value};
pub use voxel::{element_range, Scaling, VoxelData, VoxelType};

pub use geometry::Geometry;
pub use limits::{MAX_DIM, MAX_VOXELS};

/// A volume ready for upload.
#[derive(Clone, Debug)]
pub struct Volume {
    pub name: String,
    /// x fastest, then y, then z.
    pub dims: [u32; 3],
    /// Where the voxels are: the voxel-to-world affine (RAS+ millimetres for anatomical files) and whether the
    /// file said which way the patient lies. Set through [`Volume::with_geometry`] and [`Volume::with_spacing`].
    pub geometry: Geometry,
    pub source_type: VoxelType,
    pub data: VoxelData,
    /// min/max of the values after [`Volume::scaling`] (as the GPU sees them, i.e. after float64->f32),
    /// NaN/Inf ignored. `[0, 0]` if no voxel is finite.
    pub range: [f64; 2],
    /// min/max of the source values before scaling.
    pub stored_range: [f64; 2],
    /// Applied to every source value by [`Volume::value`]; identity unless the file asked for a rescale.
    pub scaling: Scaling,
    /// Where the volume came from: "raw", "VTK legacy", "NRRD", "NIfTI-1", "NIfTI-2", "Analyze 7.5", "MetaImage",
    /// "DICOM", "TIFF", "built-in".
    pub format: String,
    /// The acquisition's modality as the file names it ("CT", "MR", ... from DICOM's Modality), if it does.
    pub modality: Option<String>,
    /// Things the user should know that are not errors: orientation ignored, 4-D reduced, downsampled, ...
    pub notes: Vec<String>,
    /// Every point-data array the file holds (VTK files can hold several); empty for single-array formats.
    pub arrays: Vec<ArrayInfo>,
    /// The series of a DICOM folder holding several, the loaded one marked; empty otherwise.
    pub series: Vec<SeriesInfo>,
    /// A time series' other steps ([`Volume::timesteps`], [`Volume::show_step`]); `data` is the step shown.
    pub time: TimeSteps,
    /// The channels of an OME-Zarr image (names, omero windows and colours), the loaded one marked; empty
    /// otherwise. The loaded channel's window and colour seed the default transfer function.
    pub channels: Vec<ChannelInfo>,
    /// Where this is a coarser level of a file read in place, the finer levels' bricks in that file (streamed
    /// pools read them as the view needs them); `None` otherwise.
    pub finer: Option<std::sync::Arc<dyn FinerLevels>>,
    /// Level 0's value range per cell, where this is a coarser level of a file read whole in one pass (made by that
    /// pass, or kept beside the level in the pyramid cache): which bricks finer than this level can show anything
    /// is known before they are read. `None` otherwise (a volume that is its own level 0 has them in its voxels).
    pub cells: Option<std::sync::Arc<cells::CellRanges>>,
    /// How many of its source's voxels one of its voxels spans, along the shortest side: 1 for a file's own voxels;
    /// k for a stand-in (a preview of every k-th voxel, a coarser level read in the file's place). A transfer
    /// function's opacity is per voxel of the source, so a stand-in keeps the source's optical depth (rule 6) and
    /// the picture only sharpens as finer data arrive ([`Volume::stand_in_for`]).
    pub source_voxels: f64,
}

/// The levels below the one a volume holds, where they stay in its file (`scale::finer::Finer`): the pool reads
/// their bricks as the view needs them.
pub trait FinerLevels: std::fmt::Debug + Send + Sync {
    /// Level 0's size in voxels and its placement.
    fn dims(&self) -> [u32; 3];
    fn geometry(&self) -> Geometry;
    /// The level the volume holds (levels 0..held are read from the file).
    fn held(&self) -> u32;
    /// Where the finer bricks are read from, as a note says it ("the file", "the store's level 0", …).
    fn origin(&self) -> &'static str {
        "the file"
    }
    /// Voxels `lo..lo + size` of level `level` (below the held one), x fastest, in the representation the volume
    /// holds its level in.
    fn read(&self, level: u32, lo: [u32; 3], size: [u32; 3]) -> Result<VoxelData, VolumeError>;
}

impl Volume {
    /// Validates data length == product of dims, dims within [`MAX_DIM`] and [`MAX_VOXELS`], spacing positive and
    /// finite, `data` in the representation `source_type` maps to; computes `range`.
    pub fn new(
        name: impl Into<String>,
        dims: [u32; 3],
        spacing: [f32; 3],
        source_type: VoxelType,
        data: VoxelData,
    ) -> Result<Volume, VolumeError> {
        let count = check_dims(dims)?;
        check_spacing(dims, spacing)?;
        if !data.matches(source_type) {
            return Err(VolumeError::TypeMismatch {
                source_type,
                data: data.kind(),
            });
        }
        if data.len() as u64 != count {
            return Err(VolumeError::DataLength {
                dims,
                expected: count,
                actual: data.len(),
            });
        }
        let range = compute_range(source_type, &data);
        Ok(Volume {
            name: name.into(),
            dims,
            geometry: Geometry::from_spacing(spacing.map(f64::from)),
            source_type,
            data,
            range,
            stored_range: range,
            scaling: Scaling::IDENTITY,
            format: "memory".into(),
            modality: None,
            notes: Vec::new(),
            arrays: Vec::new(),
            series: Vec::new(),
            time: TimeSteps::default(),
            channels: Vec::new(),
            finer: None,
            cells: None,
            source_voxels: 1.0,
        })
    }

    /// The voxel size along each index axis (the lengths of the affine's columns).
    pub fn spacing(&self) -> [f32; 3] {
        self.geometry.spacing().map(|s| s as f32)
    }

    /// Replaces the voxel size, keeping the directions and origin; refused (naming it) unless positive and finite.
    pub fn with_spacing(mut self, spacing: [f32; 3]) -> Result<Volume, VolumeError> {
        check_spacing(self.dims, spacing)?;
        self.geometry = self.geometry.with_spacing(spacing.map(f64::from));
        Ok(self)
    }

    /// Places the volume by `geometry`; refused if its voxel sizes are not positive and finite or its affine is
    /// singular or not finite.
    pub fn with_geometry(mut self, geometry: Geometry) -> Result<Volume, VolumeError> {
        let spacing = geometry.spacing().map(|s| s as f32);
        check_spacing(self.dims, spacing)?;
        let finite = geometry.affine.to_cols_array().iter().all(|v| v.is_finite());
        if !finite || geometry.linear().determinant().abs() < 1e-12 {
            return Err(VolumeError::BadAffine {
                rows: Box::new(geometry.rows()),
            });
        }
        self.geometry = geometry;
        Ok(self)
    }

    /// Marks this a stand-in for the volume `source` places (its file's level 0, or a volume itself standing in for
    /// one `source_voxels` times finer): [`Volume::source_voxels`] from the two shortest voxel sides.
    pub fn stand_in_for(mut self, source: &Geometry, source_voxels: f64) -> Volume {
        self.source_voxels = source_voxels * self.geometry.smallest_side() / source.smallest_side();
        self
    }

    /// Sets the rescale and the scaled range. A slope of 0 or a non-finite slope or intercept is refused.
    pub fn with_scaling(mut self, scaling: Scaling) -> Result<Volume, VolumeError> {
        if !(scaling.slope.is_finite() && scaling.slope != 0.0 && scaling.intercept.is_finite()) {
            return Err(VolumeError::BadScaling {
                slope: scaling.slope,
                intercept: scaling.intercept,
            });
        }
        self.scaling = scaling;
        let [a, b] = self.stored_range.map(|v| scaling.apply(v));
        self.range = [a.min(b), a.max(b)];
        Ok(self)
    }

    /// Sets the stored value range (a level of a pyramid takes level 0's) and the scaled range from it.
    pub fn with_stored_range(mut self, stored: [f64; 2]) -> Volume {
        self.stored_range = stored;
        let [a, b] = stored.map(|v| self.scaling.apply(v));
        self.range = [a.min(b), a.max(b)];
        self
    }

    /// Bytes the voxels take on the GPU.
    pub fn gpu_memory_bytes(&self) -> u64 {
        self.voxel_count() as u64 * self.gpu_texel_size() as u64
    }

    pub fn voxel_count(&self) -> usize {
        // The dims' product, which `new` checks the data against (a rank's header of the whole volume holds none).
        self.dims.iter().map(|&d| d as usize).product()
    }

    fn index(&self, x: u32, y: u32, z: u32) -> usize {
        let [w, h, d] = self.dims;
        assert!(x < w && y < h && z < d, "voxel ({x}, {y}, {z}) outside {w}x{h}x{d}");
        x as usize + w as usize * (y as usize + h as usize * z as usize)
    }

    /// Value after [`Volume::scaling`] (int16/int8 un-biased); float64 sources give the stored f32.
    /// Panics if (x, y, z) is outside `dims`, like slice indexing.
    pub fn value(&self, x: u32, y: u32, z: u32) -> f64 {
        self.scaling.apply(self.stored(x, y, z))
    }

    /// [`Volume::value`] of the voxel at index `i` (x fastest, then y, then z).
    pub fn value_at_index(&self, i: usize) -> f64 {
        self.scaling.apply(stored_value(self.source_type, &self.data, i))
    }

    /// Value in source units before scaling (int16/int8 un-biased).
    pub fn stored(&self, x: u32, y: u32, z: u32) -> f64 {
        let i = self.index(x, y, z);
        stored_value(self.source_type, &self.data, i)
    }

    /// `(value - min) / (max - min)`; 0.0 if max == min; NaN stays NaN (the renderer treats it as transparent).
    pub fn normalized(&self, x: u32, y: u32, z: u32) -> f64 {
        self.normalize_value(self.value(x, y, z))
    }

    /// A value (after scaling) normalised to the range, as [`Volume::normalized`].
    fn normalize_value(&self, v: f64) -> f64 {
        let [min, max] = self.range;
        if v.is_nan() {
            f64::NAN
        } else if max == min {
            0.0
        } else {
            (v - min) / (max - min)
        }
    }

    /// [`Volume::normalized`] of an element as `data` holds it (a biased integer, or the f32): affine in it, so
    /// the extremes of a block of elements map to the extremes of its normalised values (swapped for a negative
    /// slope).
    pub fn normalize_element(&self, element: f64) -> f64 {
        self.normalize_value(self.scaling.apply(element - stored_offset(self.source_type)))
    }

    /// The normalised range (f32, ordered) of a block whose elements span `range` as `data` holds them (None: no
    /// finite element, the empty range (+inf, -inf)): the skip grid's, the refinement rule's and a read brick's.
    pub fn normalize_range(&self, range: Option<(f64, f64)>) -> (f32, f32) {
        match range {
            Some((a, b)) => {
                let (a, b) = (self.normalize_element(a) as f32, self.normalize_element(b) as f32);
                (a.min(b), a.max(b))
            }
            None => (f32::INFINITY, f32::NEG_INFINITY),
        }
    }

    /// Physical box, dims × spacing, scaled so the largest side is 1.
    pub fn extent(&self) -> glam::Vec3 {
        let spacing = self.geometry.spacing();
        let size = [0, 1, 2].map(|i| f64::from(self.dims[i]) * spacing[i]);
        let largest = size[0].max(size[1]).max(size[2]);
        // `new` guarantees positive, finite sides, so `largest` > 0.
        glam::Vec3::new(
            (size[0] / largest) as f32,
            (size[1] / largest) as f32,
            (size[2] / largest) as f32,
        )
    }

    /// The voxel data as bytes in native byte order (what a staging buffer copies).
    pub fn gpu_bytes(&self) -> &[u8] {
        match &self.data {
            VoxelData::U8(v) => v,
            VoxelData::U16(v) => bytemuck::cast_slice(v),
            VoxelData::F32(v) => bytemuck::cast_slice(v),
        }
    }

    /// Bytes per texel on the GPU: 1 (R8_UNORM), 2 (R16_UNORM) or 4 (R32_SFLOAT).
    pub fn gpu_texel_size(&self) -> usize {
        match &self.data {
            VoxelData::U8(_) => 1,
            VoxelData::U16(_) => 2,
            VoxelData::F32(_) => 4,
        }
    }

    /// The affine map from what a shader samples (UNORM -> stored/255 or stored/65535; float -> as stored) to the
    /// normalised value: `v = sampled * scale + bias`. Agrees with [`Volume::normalized`] in real arithmetic.
    /// `(0, 0)` if max == min.
    pub fn gpu_scale_bias(&self) -> (f32, f32) {
        let [min, max] = self.range;
        if max == min {
            return (0.0, 0.0);
        }
        // stored = sampled * unorm_max - offset, value = slope * stored + intercept,
        // then v = (value - min) / (max - min).
        let unorm_max = match self.data {
            VoxelData::U8(_) => 255.0,
            VoxelData::U16(_) => 65535.0,
            VoxelData::F32(_) => 1.0,
        };
        let offset = stored_offset(self.source_type);
        let Scaling { slope, intercept } = self.scaling;
        let span = max - min;
        (
            (slope * unorm_max / span) as f32,
            ((intercept - slope * offset - min) / span) as f32,
        )
    }
}

/// Checks the dims of a file read in place (never held whole): no zero and none above [`MAX_DIM`], with no voxel
/// limit. Returns the voxel count.
pub(crate) fn check_extent(dims: [u32; 3]) -> Result<u64, VolumeError> {
    if dims.contains(&0) {
        return Err(VolumeError::ZeroDimension { dims });
    }
    if dims.iter().any(|&d| d > MAX_DIM) {
        return Err(VolumeError::DimensionTooLarge { dims });
    }
    // Each factor is at most 2^14, so the product (at most 2^42) fits easily in u64.
    Ok(dims.iter().map(|&d| u64::from(d)).product::<u64>())
}

/// Checks dims and returns the voxel count.
pub(crate) fn check_dims(dims: [u32; 3]) -> Result<u64, VolumeError> {
    if dims.contains(&0) {
        return Err(VolumeError::ZeroDimension { dims });
    }
    if dims.iter().any(|&d| d > MAX_DIM) {
        return Err(VolumeError::DimensionTooLarge { dims });
    }
    // Each factor is at most 2^14, so the product fits easily in u64.
    let count = dims.iter().map(|&d| u64::from(d)).product::<u64>();
    if count > MAX_VOXELS {
        return Err(VolumeError::TooManyVoxels { dims, count });
    }
    Ok(count)
}

pub(crate) fn check_spacing(dims: [u32; 3], spacing: [f32; 3]) -> Result<(), VolumeError> {
    let physical_ok = (0..3).all(|i| {
        let s = spacing[i];
        s.is_finite() && s > 0.0 && (f64::from(dims[i]) * f64::from(s)) < f64::from(f32::MAX)
    });
    if physical_ok {
        Ok(())
    } else {
        Err(VolumeError::BadSpacing { spacing })
    }
}

#[cfg(test)]
mod tests;
