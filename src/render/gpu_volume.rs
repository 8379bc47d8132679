//! The volume on the device: the layout the march reads it in (a 3D texture or a corner texture, chosen per device
//! and policy), its upload, brick grid and occupancy texture. A [`GpuVolume`] is made whole before it replaces the
//! shown one, so the next step of a series can be uploaded ahead of display (`Renderer::prepare_volume`).

use super::levels::Cut;
use super::march_key::Sampling;
use super::pool::Pool;
use super::texels::{write_texels, Levels, PoolFrom, TexelKind};
use super::{skip, OccupancyKey, VolumeInfo};
use crate::gpu::resources::{Image, ImageDesc};
use crate::gpu::upload::{upload_image, upload_image_with};
use crate::gpu::TexelPolicy;
use crate::gpu::{Gpu, GpuError};
use crate::volume::{Volume, VoxelData};
use ash::vk;

pub(super) struct GpuVolume {
    pub(super) layout: VolumeLayout,
    /// The 3D texture (`VolumeLayout::Texture`).
    pub(super) image: Option<Image>,
    pub(super) info: VolumeInfo,
    /// Where the bricks lie in the pool (the image or the corners) and the page table that finds them.
    pub(super) pool: Pool,
    pub(super) directory: Image,
    /// The levels the pool shows, level 0 everywhere until `show_cut`.
    pub(super) cut: Cut,
    /// Levels 1.. of the volume, made by the first cut that needs them (levels.rs).
    pub(super) pyramid: Vec<Volume>,
    /// The skip grid of the cut shown (read it through `skip_grid`, which makes it again after a cut changed).
    pub(super) bricks: skip::BrickGrid,
    /// Each level's skip grid (level 0 first), made as cuts need them; `bricks` is their `levels::cut_ranges`.
    pub(super) skip_levels: Vec<skip::BrickGrid>,
    /// The cut changed since `bricks` was made (`skip_grid` makes it again).
    pub(super) skip_stale: bool,
    /// One R8 texel per brick: may a sample there be visible (see skip.rs).
    pub(super) occupancy: Image,
    /// What the occupancy was computed for.
    pub(super) occupancy_key: Option<OccupancyKey>,
    /// Precomputed gradients (RGBA16 SNORM), made on first use by a frame with `gradient_texture`.
    pub(super) gradient: Option<Image>,
    /// The corner texture (`VolumeLayout::Corners8`/`Corners16`).
    pub(super) corners: Option<Image>,
    /// Rule 9's light grid, made by the first frame with shadows or occlusion.
    pub(super) light: Option<super::light_volume::LightImage>,
    /// Which bricks a streamed pool holds (`Renderer::start_stream`); None while the pool is a cut's.
    pub(super) stream: Option<super::stream::Stream>,
    /// The normalised value range of each brick read from the file below the held level (`VolumeInfo::held`), for
    /// the skip grid.
    pub(super) finer_ranges: super::levels::FinerRanges,
    /// Which bricks may be refined (refinable.rs): the ranges, made by the first screen cut that needs them, and
    /// the classes of the frame they were last taken for.
    pub(super) refinable: Option<super::refinable::Refinable>,
    pub(super) refine_classes: Option<(OccupancyKey, super::refinable::Classes)>,
}

/// A 3D image of `dims` (a depth of 1 gets a duplicated second slice: a depth-1 image would be 2D), filled by
/// transfers as often as needed.
pub(super) fn image_3d(gpu: &Gpu, format: vk::Format, dims: [u32; 3], name: &str) -> Result<Image, GpuError> {
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    Image::new(
        gpu,
        ImageDesc {
            format,
            extent: extent_3d(dims),
            usage,
        },
        name,
    )
}

/// Like [`image_3d`] for an image filled once (the volume, its gradients): on CPU devices (lavapipe) written in
/// place by the host where the device allows it, which saves a staging copy and the device's single-threaded
/// copy into fresh memory (a third of loading a 1 GiB volume); elsewhere a device image.
pub(super) fn image_3d_once(gpu: &Gpu, format: vk::Format, dims: [u32; 3], name: &str) -> Result<Image, GpuError> {
    if DeviceFacts::of(gpu).cpu {
        let desc = ImageDesc {
            format,
            extent: extent_3d(dims),
            usage: vk::ImageUsageFlags::SAMPLED,
        };
        if let Some(image) = Image::new_host_written(gpu, desc, name)? {
            return Ok(image);
        }
    }
    image_3d(gpu, format, dims, name)
}

fn extent_3d(dims: [u32; 3]) -> vk::Extent3D {
    vk::Extent3D {
        width: dims[0],
        height: dims[1],
        depth: dims[2].max(2),
    }
}

/// The most memory `TexelPolicy::Auto` spends on a volume beyond its native format.
pub const AUTO_LIMIT: u64 = 1 << 30;

/// How the march reads the loaded volume (shaders/volume.glsl, `sample_in`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeLayout {
    /// A 3D texture of this format, filtered by the sampler.
    Texture(vk::Format),
    /// 8-bit data as a corner texture (R32_UINT): per voxel the four values of the 2×2 square its cell starts in
    /// x and y (neighbours clamped to the edge), 4 bytes per voxel, so a trilinear sample is two `texelFetch`
    /// (z and z + 1) and seven lerps.
    Corners8,
    /// 16-bit data the same way (RG32_UINT), 8 bytes per voxel.
    Corners16,
}

impl VolumeLayout {
    /// How this layout stores `levels`' elements in a pool texel.
    pub(super) fn texel_kind(self, levels: &Levels) -> TexelKind {
        match (self, levels) {
            (VolumeLayout::Corners8, _) => TexelKind::Corners8,
            (VolumeLayout::Corners16, _) => TexelKind::Corners16,
            (VolumeLayout::Texture(vk::Format::R32_SFLOAT), Levels::U8(_) | Levels::U16(_)) => TexelKind::Widened,
            _ => TexelKind::Native,
        }
    }

    /// How the shaders read a volume of this layout (their compiled variant).
    pub fn sampling(self) -> Sampling {
        match self {
            VolumeLayout::Texture(_) => Sampling::Texture,
            VolumeLayout::Corners8 => Sampling::Corners8,
            VolumeLayout::Corners16 => Sampling::Corners16,
        }
    }

    pub fn bytes_per_voxel(self) -> u64 {
        match self {
            VolumeLayout::Texture(vk::Format::R8_UNORM) => 1,
            VolumeLayout::Texture(vk::Format::R16_UNORM) => 2,
            VolumeLayout::Texture(_) => 4,
            VolumeLayout::Corners8 => 4,
            VolumeLayout::Corners16 => 8,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VolumeLayout::Texture(vk::Format::R8_UNORM) => "R8_UNORM",
            VolumeLayout::Texture(vk::Format::R16_UNORM) => "R16_UNORM",
            VolumeLayout::Texture(_) => "R32_SFLOAT",
            VolumeLayout::Corners8 => "corners8",
            VolumeLayout::Corners16 => "corners16",
        }
    }
}

/// The layout `policy` gives `volume` on `gpu`. GPUs filter every format in hardware, so `Auto` keeps the
/// native texture there. On a CPU device (lavapipe) the sampler is the march's main cost: measured on the
/// vtk-helix scene, a corner layout is ~18% faster than an R32_SFLOAT texture, which is ~30% faster than
/// R8_UNORM (and exact, where lavapipe filters R8 with 8-bit weights); `Auto` takes the fastest of these that
/// stays under [`AUTO_LIMIT`] and a quarter of the device's memory.
fn choose_layout(dev: DeviceFacts, policy: TexelPolicy, data: &VoxelData, voxels: u64) -> VolumeLayout {
    let fits = |layout: VolumeLayout| {
        let bytes = voxels * layout.bytes_per_voxel();
        bytes <= AUTO_LIMIT && bytes <= dev.memory / 4
    };
    let float = VolumeLayout::Texture(vk::Format::R32_SFLOAT);
    let (native, corners) = match data {
        VoxelData::U8(_) => (
            VolumeLayout::Texture(vk::Format::R8_UNORM),
            Some(VolumeLayout::Corners8),
        ),
        VoxelData::U16(_) => (
            VolumeLayout::Texture(vk::Format::R16_UNORM),
            Some(VolumeLayout::Corners16),
        ),
        VoxelData::F32(_) => (float, None),
    };
    match policy {
        TexelPolicy::Native => native,
        TexelPolicy::Float => float,
        TexelPolicy::Corners => corners.unwrap_or(native),
        TexelPolicy::Auto if dev.cpu => match corners {
            Some(c) if fits(c) => c,
            _ if fits(float) => float,
            _ => native,
        },
        TexelPolicy::Auto => native,
    }
}

/// What [`choose_layout`] needs to know of the device.
#[derive(Clone, Copy, Debug)]
struct DeviceFacts {
    /// A CPU implementation (lavapipe), where the sampler is slow and memory is host memory.
    cpu: bool,
    /// The largest device-local heap.
    memory: u64,
}

impl DeviceFacts {
    fn of(gpu: &Gpu) -> DeviceFacts {
        DeviceFacts {
            cpu: gpu.properties.device_type == vk::PhysicalDeviceType::CPU,
            memory: gpu.device_local_bytes,
        }
    }
}

/// Fills the pool's image in `layout` (a texture, or a corner texture for 8- and 16-bit data) from `levels`,
/// slab by slab straight into the staging buffer.
fn upload_texels(
    gpu: &Gpu,
    image: &mut Image,
    levels: &Levels,
    pool: &Pool,
    layout: VolumeLayout,
) -> Result<(), GpuError> {
    let kind = layout.texel_kind(levels);
    if matches!(levels, Levels::F32(_)) && matches!(kind, TexelKind::Corners8 | TexelKind::Corners16) {
        return Err(GpuError::Lost("corner texture: float data has no corner layout"));
    }
    let texel = kind.bytes(levels);
    upload_image_with(gpu, image, pool.texel_count() * texel as u64, |range, dst| {
        write_texels(
            &PoolFrom {
                pool,
                first: range.start / texel,
            },
            levels,
            kind,
            dst,
        )
    })
}

/// The corner texture's format for `layout`.
pub(super) fn corners_format(layout: VolumeLayout) -> vk::Format {
    match layout {
        VolumeLayout::Corners8 => vk::Format::R32_UINT,
        _ => vk::Format::R32G32_UINT,
    }
}

/// Uploads the bricks `pool` holds into a pool in `layout`: the 3D texture or the corner texture.
fn upload_layout(
    gpu: &Gpu,
    layout: VolumeLayout,
    levels: &Levels,
    pool: &Pool,
) -> Result<(Option<Image>, Option<Image>), GpuError> {
    match layout {
        VolumeLayout::Texture(format) => {
            // SAFETY: plain query on a live physical device.
            let features = unsafe { gpu.instance.get_physical_device_format_properties(gpu.physical, format) };
            let filter = vk::FormatFeatureFlags::SAMPLED_IMAGE | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
            if !features.optimal_tiling_features.contains(filter) {
                return Err(GpuError::TooLarge(format!(
                    "this device cannot filter {format:?} 3D textures linearly"
                )));
            }
            let mut image = image_3d_once(gpu, format, pool.texels(), "volume")?;
            if let Err(e) = upload_texels(gpu, &mut image, levels, pool, layout) {
                image.destroy(gpu);
                return Err(e);
            }
            Ok((Some(image), None))
        }
        VolumeLayout::Corners8 | VolumeLayout::Corners16 => {
            let mut image = image_3d_once(gpu, corners_format(layout), pool.texels(), "volume corners")?;
            if let Err(e) = upload_texels(gpu, &mut image, levels, pool, layout) {
                image.destroy(gpu);
                return Err(e);
            }
            Ok((None, Some(image)))
        }
    }
}

/// Uploads `bytes` (dims[2] slices) into an image made by [`image_3d`].
pub(super) fn upload_3d(gpu: &Gpu, image: &mut Image, bytes: &[u8], depth: u32) -> Result<(), GpuError> {
    if depth == 1 {
        let mut twice = bytes.to_vec();
        twice.extend_from_slice(bytes);
        upload_image(gpu, image, &twice)
    } else {
        upload_image(gpu, image, bytes)
    }
}

/// The pool's images in `layout` (the texture or the corner texture) and its page table; nothing is left
/// allocated on an error.
pub(super) type PoolImages = (Option<Image>, Option<Image>, Image);

pub(super) fn upload_pool(
    gpu: &Gpu,
    layout: VolumeLayout,
    levels: &Levels,
    pool: &Pool,
) -> Result<PoolImages, GpuError> {
    let (image, corners) = upload_layout(gpu, layout, levels, pool)?;
    match upload_directory(gpu, pool) {
        Ok(d) => Ok((image, corners, d)),
        Err(e) => {
            for i in [image, corners].into_iter().flatten() {
                i.destroy(gpu);
            }
            Err(e)
        }
    }
}

/// The page table as an RG32_UINT 3D image (`Pool::table`).
fn upload_directory(gpu: &Gpu, pool: &Pool) -> Result<Image, GpuError> {
    let mut image = image_3d(gpu, vk::Format::R32G32_UINT, pool.grid, "page table")?;
    match upload_3d(gpu, &mut image, bytemuck::cast_slice(&pool.table()), pool.grid[2]) {
        Ok(()) => Ok(image),
        Err(e) => {
            image.destroy(gpu);
            Err(e)
        }
    }
}

/// The occupancy texture of `bricks`: everything occupied until `prepare` computes the real occupancy for the
/// settings.
pub(super) fn occupancy_image(gpu: &Gpu, bricks: &skip::BrickGrid) -> Result<Image, GpuError> {
    let mut o = image_3d(gpu, vk::Format::R8_UNORM, bricks.bricks, "brick occupancy")?;
    let all = vec![255u8; bricks.min.len()];
    match upload_3d(gpu, &mut o, &all, bricks.bricks[2]) {
        Ok(()) => Ok(o),
        Err(e) => {
            o.destroy(gpu);
            Err(e)
        }
    }
}

/// What [`choose_layout`] gives `volume` on `gpu` under `policy`, for `voxels` texels.
pub(super) fn layout_for(gpu: &Gpu, policy: TexelPolicy, volume: &Volume, voxels: u64) -> VolumeLayout {
    choose_layout(DeviceFacts::of(gpu), policy, &volume.data, voxels)
}

impl GpuVolume {
    /// Uploads `volume` in the layout `policy` gives it on `gpu`. The size is checked against the device's 3D
    /// image limit and memory before anything is allocated.
    pub(super) fn new(
        gpu: &Gpu,
        policy: TexelPolicy,
        volume: &Volume,
        brick: Option<u32>,
    ) -> Result<GpuVolume, GpuError> {
        let limit = gpu.properties.limits.max_image_dimension3_d;
        let pool = Pool::whole(volume.dims, brick, limit).map_err(|e| {
            GpuError::TooLarge(format!(
                "volume {}x{}x{}: {e}",
                volume.dims[0], volume.dims[1], volume.dims[2]
            ))
        })?;
        let voxels = volume.voxel_count() as u64;
        let layout = choose_layout(DeviceFacts::of(gpu), policy, &volume.data, voxels);
        let needed = pool.texel_count() * layout.bytes_per_voxel();
        // Half the heap: the upload needs a staging copy of the same size alongside.
        if needed > gpu.device_local_bytes / 2 {
            return Err(GpuError::TooLarge(format!(
                "volume needs {} MiB on the GPU as {} (plus as much again to upload) but the device has {} MiB",
                needed >> 20,
                layout.name(),
                gpu.device_local_bytes >> 20
            )));
        }
        // The brick statistics beside the upload, on the cores it leaves idle (its fills are parallel, but it
        // waits on the device and, through a staging buffer, on lavapipe's single-threaded copy).
        let (uploaded, bricks) = rayon::join(
            || upload_pool(gpu, layout, &Levels::of(volume, &[]), &pool),
            || skip::BrickGrid::new(volume),
        );
        let (image, corners, directory) = uploaded?;
        let destroy_volume = |gpu: &Gpu, image: Option<Image>, corners: Option<Image>| {
            if let Some(i) = image {
                i.destroy(gpu);
            }
            if let Some(c) = corners {
                c.destroy(gpu);
            }
        };
        let occupancy = match occupancy_image(gpu, &bricks) {
            Ok(o) => o,
            Err(e) => {
                destroy_volume(gpu, image, corners);
                directory.destroy(gpu);
                return Err(e);
            }
        };
        Ok(GpuVolume::assemble(
            volume,
            layout,
            (image, corners, directory),
            pool,
            bricks,
            occupancy,
        ))
    }

    /// A volume on the device from its parts: its pool's images (texture or corners, and page table), where its
    /// bricks lie, its skip grid and occupancy; level 0 everywhere, nothing derived made yet.
    pub(super) fn assemble(
        volume: &Volume,
        layout: VolumeLayout,
        (image, corners, directory): PoolImages,
        pool: Pool,
        bricks: skip::BrickGrid,
        occupancy: Image,
    ) -> GpuVolume {
        GpuVolume {
            layout,
            image,
            info: VolumeInfo {
                dims: volume.dims,
                geometry: volume.geometry,
                scale_bias: volume.gpu_scale_bias(),
                range: volume.range,
                pool: pool.info(),
                held: 0,
                step_level: 0,
                part: None,
                source_voxels: volume.source_voxels as f32,
            },
            cut: Cut::uniform(pool.grid, 0),
            pool,
            directory,
            pyramid: Vec::new(),
            bricks,
            skip_levels: Vec::new(),
            skip_stale: false,
            occupancy,
            occupancy_key: None,
            gradient: None,
            corners,
            light: None,
            stream: None,
            finer_ranges: Default::default(),
            refinable: None,
            refine_classes: None,
        }
    }

    /// How the shaders read it: its layout, through the page table unless it is one brick.
    pub(super) fn sampling(&self) -> Sampling {
        let s = self.layout.sampling();
        if self.pool.grid == [1, 1, 1] {
            s
        } else {
            s.bricked()
        }
    }

    pub(super) fn destroy(self, gpu: &Gpu) {
        self.occupancy.destroy(gpu);
        self.directory.destroy(gpu);
        if let Some(l) = self.light {
            l.image.destroy(gpu);
        }
        if let Some(g) = self.gradient {
            g.destroy(gpu);
        }
        if let Some(i) = self.image {
            i.destroy(gpu);
        }
        if let Some(c) = self.corners {
            c.destroy(gpu);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_follow_the_policy_the_device_and_its_limits() {
        let lavapipe = DeviceFacts {
            cpu: true,
            memory: 16 << 30,
        };
        let gpu = DeviceFacts { cpu: false, ..lavapipe };
        let u8s = VoxelData::U8(Vec::new());
        let u16s = VoxelData::U16(Vec::new());
        let f32s = VoxelData::F32(Vec::new());
        let n256 = 256u64 * 256 * 256;
        let layout = choose_layout;
        use TexelPolicy::*;
        use VolumeLayout::*;
        // lavapipe: corners while they stay within 1 GiB (4 bytes per voxel for 8-bit data, 8 for 16-bit).
        assert_eq!(layout(lavapipe, Auto, &u8s, n256), Corners8);
        assert_eq!(layout(lavapipe, Auto, &u8s, 1024 * 1024 * 256), Corners8);
        assert_eq!(layout(lavapipe, Auto, &u16s, 1024 * 1024 * 128), Corners16);
        // Over 1 GiB as corners, still within it as float: float (16-bit data, 4 bytes per voxel).
        assert_eq!(
            layout(lavapipe, Auto, &u16s, 1024 * 1024 * 256),
            Texture(vk::Format::R32_SFLOAT)
        );
        assert_eq!(layout(lavapipe, Auto, &f32s, n256), Texture(vk::Format::R32_SFLOAT));
        // Over 1 GiB in both: the native texture.
        assert_eq!(
            layout(lavapipe, Auto, &u8s, 1024 * 1024 * 512),
            Texture(vk::Format::R8_UNORM)
        );
        // A quarter of a small device's memory bounds it too.
        let small = DeviceFacts {
            memory: 200 << 20,
            ..lavapipe
        };
        assert_eq!(layout(small, Auto, &u8s, n256), Texture(vk::Format::R8_UNORM));
        // GPUs keep the native format unless told otherwise.
        assert_eq!(layout(gpu, Auto, &u16s, n256), Texture(vk::Format::R16_UNORM));
        assert_eq!(layout(gpu, Float, &u16s, n256), Texture(vk::Format::R32_SFLOAT));
        assert_eq!(layout(gpu, Corners, &u8s, n256), Corners8);
        assert_eq!(layout(lavapipe, Native, &u8s, n256), Texture(vk::Format::R8_UNORM));
        assert_eq!(layout(lavapipe, Corners, &f32s, n256), Texture(vk::Format::R32_SFLOAT));
    }
}
