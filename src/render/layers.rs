//! Layers on the GPU (rule 13, `scene::layers`): every layer's voxels on its own grid, stacked along z in one
//! texture per kind (overlays as f32 data units, label maps as dense ids), a table of their placements and
//! looks, and their colours. `shaders/layers.glsl` reads them at each sample of the base's march. Nothing is
//! resampled: a layer costs its own voxels (4 bytes each) and no more.

use super::gpu_volume::{image_3d, upload_3d};
use super::layer_bricks::Summary;
use crate::gpu::resources::{Buffer, Image, ImageDesc};
use crate::gpu::upload::upload_image;
use crate::gpu::{Gpu, GpuError};
use crate::scene::layers::{Blend, LayerKind, LayerStyle, OVERLAY_ENTRIES};
use crate::scene::settings::RenderSettings;
use crate::transfer::function::srgb_to_linear;
use crate::volume::labels::LabelMap;
use crate::volume::{Geometry, Volume};
use ash::vk;
use glam::{DMat4, DVec3};
use gpu_allocator::MemoryLocation;

/// The most layers one frame mixes.
pub const MAX_LAYERS: usize = 16;

/// Bytes of one layer's entry in the table: `mat4 to_index; vec4 dims, look, more, texel` (shaders/layers.glsl).
const PARAMS_BYTES: usize = 128;

/// Bytes of the table's header, before the entries: `vec4 span_lo, span_hi` (shaders/layers.glsl `layer_span`).
const HEADER_BYTES: usize = 32;

/// One layer to upload: its volume (placement, and values for an overlay) and, for a label map, its dense ids
/// with the sRGB colour and opacity (0–255) of each dense index.
pub struct LayerInput<'a> {
    pub volume: &'a Volume,
    pub labels: Option<(&'a LabelMap, Vec<[u8; 4]>)>,
}

/// What the GPU keeps of a layer besides its voxels.
struct Placed {
    kind: LayerKind,
    geometry: Geometry,
    dims: [u32; 3],
    /// Its first slice in its kind's texture.
    z0: u32,
    /// Its first entry in the colour buffer.
    colour0: u32,
    /// A label map's colours per dense index (linear rgb, table opacity).
    label_colours: Vec<[f32; 4]>,
}

/// The layers' textures and tables; with no layers, one-voxel stand-ins so the bindings are always valid.
pub(super) struct GpuLayers {
    pub values: Image,
    pub labels: Image,
    pub params: Buffer,
    /// The colours, [`COLOUR_ROW`] to a row (RGBA32F): on lavapipe a texel fetch is one gather for all lanes,
    /// where a storage buffer's loads loop over them.
    pub colours: Image,
    placed: Vec<Placed>,
    /// The size of each kind's texture (overlays, label maps).
    sizes: [[u32; 3]; 2],
    /// Where each layer may show something (empty-space skipping in layered frames).
    summaries: Vec<Summary>,
    /// The table and colours last written, with what they were written for.
    written: Option<(Vec<LayerStyle>, [u32; 3], Geometry)>,
}

impl GpuLayers {
    pub(super) fn new(gpu: &Gpu, inputs: &[LayerInput]) -> Result<GpuLayers, GpuError> {
        if inputs.len() > MAX_LAYERS {
            return Err(GpuError::InvalidSettings(format!(
                "{} layers were given; a frame mixes at most {MAX_LAYERS}",
                inputs.len()
            )));
        }
        let labels_first = inputs
            .iter()
            .skip_while(|i| i.labels.is_none())
            .any(|i| i.labels.is_none());
        if labels_first {
            return Err(GpuError::InvalidSettings(
                "layers are given overlays first, then label maps (shaders/layers.glsl loops over each kind)".into(),
            ));
        }
        let (placed, values_dims, labels_dims, colour_count) = place(inputs, gpu)?;
        let mut made = Made::default();
        let result = (|| {
            made.values = Some(atlas::<f32>(
                gpu,
                vk::Format::R32_SFLOAT,
                values_dims,
                "overlay layers",
                |out| {
                    for (p, input) in placed.iter().zip(inputs) {
                        if p.kind == LayerKind::Overlay {
                            fill_slab(out, values_dims, p, |i| input.volume.value_at_index(i) as f32);
                        }
                    }
                },
            )?);
            made.labels = Some(atlas::<u32>(
                gpu,
                vk::Format::R32_UINT,
                labels_dims,
                "label layers",
                |out| {
                    for (p, input) in placed.iter().zip(inputs) {
                        if let Some((map, _)) = &input.labels {
                            fill_slab(out, labels_dims, p, |i| map.index[i]);
                        }
                    }
                },
            )?);
            let params_bytes = (HEADER_BYTES + MAX_LAYERS * PARAMS_BYTES) as u64;
            made.params = Some(Buffer::new(
                gpu,
                params_bytes,
                vk::BufferUsageFlags::UNIFORM_BUFFER,
                MemoryLocation::CpuToGpu,
                "layer table",
            )?);
            let (w, h) = colour_size(colour_count);
            let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
            let desc = ImageDesc::d2(vk::Format::R32G32B32A32_SFLOAT, w, h, usage);
            let mut colours = Image::new(gpu, desc, "layer colours")?;
            let zeros = vec![0u8; (w * h * 16) as usize];
            if let Err(e) = upload_image(gpu, &mut colours, &zeros) {
                colours.destroy(gpu);
                return Err(e);
            }
            made.colours = Some(colours);
            Ok(())
        })();
        match (result, made) {
            (
                Ok(()),
                Made {
                    values: Some(values),
                    labels: Some(labels),
                    params: Some(params),
                    colours: Some(colours),
                },
            ) => Ok(GpuLayers {
                values,
                labels,
                params,
                colours,
                placed,
                sizes: [values_dims, labels_dims],
                summaries: inputs.iter().map(summary).collect(),
                written: None,
            }),
            (result, made) => {
                made.destroy(gpu);
                Err(result.err().unwrap_or(GpuError::Lost("layer resources")))
            }
        }
    }

    /// Marks the base's skip bricks (`levels`, a grid of `bricks` of `brick` base voxels; the base `dims` placed
    /// by `geometry`) where a layer styled by `styles` may show something (layer_bricks.rs).
    pub(super) fn mark(
        &self,
        styles: &[LayerStyle],
        levels: &mut [u8],
        bricks: [u32; 3],
        brick: u32,
        base: (&Geometry, [u32; 3]),
    ) {
        for (summary, style) in self.summaries.iter().zip(styles) {
            summary.mark(style, levels, bricks, brick, base);
        }
    }

    pub(super) fn count(&self) -> usize {
        self.placed.len()
    }

    /// Whether the table and colours hold `styles` over a base of `dims` placed by `geometry`.
    pub(super) fn is_current(&self, styles: &[LayerStyle], dims: [u32; 3], geometry: &Geometry) -> bool {
        self.written
            .as_ref()
            .is_some_and(|(s, d, g)| s == styles && *d == dims && g == geometry)
    }

    /// Writes the table and colours for `styles` over the base volume (`dims`, `geometry`); no frame may be in
    /// flight (prepare's contract).
    pub(super) fn write(
        &mut self,
        gpu: &Gpu,
        styles: &[LayerStyle],
        dims: [u32; 3],
        geometry: &Geometry,
    ) -> Result<(), GpuError> {
        if styles.len() != self.placed.len() {
            return Err(GpuError::InvalidSettings(format!(
                "the frame styles {} layers but the renderer holds {}",
                styles.len(),
                self.placed.len()
            )));
        }
        let mut table = vec![0u32; (HEADER_BYTES + MAX_LAYERS * PARAMS_BYTES) / 4];
        table[..HEADER_BYTES / 4].copy_from_slice(&self.span(styles, dims, geometry).map(f32::to_bits));
        let (w, h) = colour_size(self.colour_count() as u32);
        let mut colours = vec![[0f32; 4]; (w * h) as usize];
        let world_per_mm = geometry.world_per_mm(dims);
        if let Some((i, _)) = self
            .placed
            .iter()
            .zip(styles)
            .enumerate()
            .find(|(_, (p, s))| p.kind != s.kind)
        {
            return Err(GpuError::InvalidSettings(format!(
                "layer {i} is {:?} but the frame styles it as {:?}",
                self.placed[i].kind, styles[i].kind
            )));
        }
        for (i, (p, style)) in self.placed.iter().zip(styles).enumerate() {
            let size = self.sizes[p.kind as usize];
            let entry = params(p, style, (dims, geometry, world_per_mm), size);
            table[(HEADER_BYTES + i * PARAMS_BYTES) / 4..][..PARAMS_BYTES / 4]
                .copy_from_slice(&entry.map(f32::to_bits));
            let c0 = p.colour0 as usize;
            match p.kind {
                LayerKind::Overlay => colours[c0..c0 + OVERLAY_ENTRIES].copy_from_slice(&style.overlay_table()),
                LayerKind::Labels => {
                    let opacity = layer_opacity(style);
                    let out = &mut colours[c0..c0 + p.label_colours.len()];
                    for (o, &[r, g, b, a]) in out.iter_mut().zip(&p.label_colours) {
                        *o = [r, g, b, log_clear(a * opacity)];
                    }
                }
            }
        }
        self.params.write(bytemuck::cast_slice(&table))?;
        upload_image(gpu, &mut self.colours, bytemuck::cast_slice(&colours))?;
        self.written = Some((styles.to_vec(), dims, *geometry));
        Ok(())
    }

    /// The table's header: the box in the base's texture space outside which no layer shows anything (rule 13),
    /// widened a little against rounding, with w 1; or w 0 where none shows anything (shaders/layers.glsl
    /// `layer_span`: a ray mixes layers only across this box).
    fn span(&self, styles: &[LayerStyle], dims: [u32; 3], geometry: &Geometry) -> [f32; 8] {
        let boxes = self
            .summaries
            .iter()
            .zip(styles)
            .filter_map(|(m, s)| m.bounds(s, (geometry, dims)));
        match boxes.reduce(|(a, b), (c, d)| (a.min(c), b.max(d))) {
            Some((lo, hi)) => {
                let (lo, hi) = ((lo - 1e-4).as_vec3(), (hi + 1e-4).as_vec3());
                [lo.x, lo.y, lo.z, 1.0, hi.x, hi.y, hi.z, 1.0]
            }
            None => [0.0; 8],
        }
    }

    fn colour_count(&self) -> usize {
        self.placed.last().map_or(0, |p| p.colour0 as usize + colours_of(p))
    }

    /// Bytes on the device.
    pub(super) fn bytes(&self) -> u64 {
        self.values.allocated_bytes() + self.labels.allocated_bytes() + self.colours.allocated_bytes()
    }

    pub(super) fn destroy(self, gpu: &Gpu) {
        self.values.destroy(gpu);
        self.labels.destroy(gpu);
        self.params.destroy(gpu);
        self.colours.destroy(gpu);
    }
}

/// Resources made so far, destroyed together on an error.
#[derive(Default)]
struct Made {
    values: Option<Image>,
    labels: Option<Image>,
    params: Option<Buffer>,
    colours: Option<Image>,
}

impl Made {
    fn destroy(self, gpu: &Gpu) {
        let images = self.values.into_iter().chain(self.labels).chain(self.colours);
        images.for_each(|i| i.destroy(gpu));
        self.params.into_iter().for_each(|b| b.destroy(gpu));
    }
}

fn colours_of(p: &Placed) -> usize {
    match p.kind {
        LayerKind::Overlay => OVERLAY_ENTRIES,
        LayerKind::Labels => p.label_colours.len(),
    }
}

type Placement = (Vec<Placed>, [u32; 3], [u32; 3], u32);

/// Where each layer goes in its kind's texture (stacked along z) and in the colour buffer, and each texture's size
/// (at least one voxel), checked against the device's 3D image limit.
fn place(inputs: &[LayerInput], gpu: &Gpu) -> Result<Placement, GpuError> {
    let mut sizes = [[1u32, 1, 0], [1u32, 1, 0]];
    let mut colour0 = 0u32;
    let mut placed = Vec::with_capacity(inputs.len());
    for input in inputs {
        let v = input.volume;
        let kind = if input.labels.is_some() {
            LayerKind::Labels
        } else {
            LayerKind::Overlay
        };
        let size = &mut sizes[kind as usize];
        let label_colours: Vec<[f32; 4]> = input.labels.as_ref().map_or(Vec::new(), |(_, rgba)| {
            rgba.iter()
                .map(|c| {
                    let [r, g, b] = [c[0], c[1], c[2]].map(|x| srgb_to_linear(f32::from(x) / 255.0));
                    [r, g, b, f32::from(c[3]) / 255.0]
                })
                .collect()
        });
        placed.push(Placed {
            kind,
            geometry: v.geometry,
            dims: v.dims,
            z0: size[2],
            colour0,
            label_colours,
        });
        *size = [size[0].max(v.dims[0]), size[1].max(v.dims[1]), size[2] + v.dims[2]];
        colour0 += colours_of(placed.last().expect("just pushed")) as u32;
    }
    let limit = gpu.properties.limits.max_image_dimension3_d;
    for size in &mut sizes {
        size[2] = size[2].max(1);
        if size.iter().any(|&s| s > limit) {
            return Err(GpuError::InvalidSettings(format!(
                "the layers of one kind stack to {}x{}x{} voxels, beyond the device's 3D image limit of {limit} per axis",
                size[0], size[1], size[2]
            )));
        }
    }
    Ok((placed, sizes[0], sizes[1], colour0))
}

/// A 32-bit 3D texture of `dims`, filled by `fill` (zeros elsewhere).
fn atlas<T: bytemuck::Pod + Default>(
    gpu: &Gpu,
    format: vk::Format,
    dims: [u32; 3],
    name: &str,
    fill: impl Fn(&mut [T]),
) -> Result<Image, GpuError> {
    let mut texels = vec![T::default(); dims.iter().map(|&d| d as usize).product()];
    fill(&mut texels);
    let mut image = image_3d(gpu, format, dims, name)?;
    match upload_3d(gpu, &mut image, bytemuck::cast_slice(&texels), dims[2]) {
        Ok(()) => Ok(image),
        Err(e) => {
            image.destroy(gpu);
            Err(e)
        }
    }
}

/// Copies a layer's voxels (`at(voxel index)`, as 32-bit texels) into its slab of a texture of `size`.
fn fill_slab<T>(out: &mut [T], size: [u32; 3], p: &Placed, at: impl Fn(usize) -> T) {
    let [w, h, d] = p.dims.map(|x| x as usize);
    let (sw, sh) = (size[0] as usize, size[1] as usize);
    for z in 0..d {
        for y in 0..h {
            let row = ((p.z0 as usize + z) * sh + y) * sw;
            for x in 0..w {
                out[row + x] = at(x + w * (y + h * z));
            }
        }
    }
}

/// A layer's summary for empty-space skipping.
fn summary(input: &LayerInput) -> Summary {
    match &input.labels {
        Some((map, rgba)) => Summary::labels(input.volume, map, rgba),
        None => Summary::overlay(input.volume),
    }
}

/// Colours to a row of the colour texture (shaders/layers.glsl `layer_colour`).
pub const COLOUR_ROW: u32 = 4096;

/// The colour texture's size for `count` colours (at least one).
fn colour_size(count: u32) -> (u32, u32) {
    let count = count.max(1);
    (count.min(COLOUR_ROW), count.div_ceil(COLOUR_ROW))
}

/// A layer's opacity in a frame: none where it is hidden.
fn layer_opacity(style: &LayerStyle) -> f32 {
    if style.visible {
        style.opacity
    } else {
        0.0
    }
}

/// `log2(1 − a)`, how the shader takes an opacity `a` (rule 13's step correction is then one `exp2`), kept finite.
fn log_clear(a: f32) -> f32 {
    (1.0 - a.clamp(0.0, 1.0)).max(1e-30).log2()
}

/// A layer's table entry (shaders/layers.glsl `LayerParams`): base texture space to the layer's voxel index, its
/// size and first slice, its look, the reciprocal of its voxel in world units, its first colour, opacity and
/// visibility test, and the reciprocal of its kind's texture `size`; over the base of `dims` voxels placed by
/// `base` (`world_per_mm` world units to the millimetre).
fn params(
    p: &Placed,
    style: &LayerStyle,
    (dims, base, world_per_mm): ([u32; 3], &Geometry, f64),
    size: [u32; 3],
) -> [f32; 32] {
    let n = DVec3::from_array(dims.map(f64::from));
    let tex_to_index = DMat4::from_translation(DVec3::splat(-0.5)) * DMat4::from_scale(n);
    let to_index = p.geometry.affine.inverse() * base.affine * tex_to_index;
    let mut e = [0f32; 32];
    e[..16].copy_from_slice(&to_index.as_mat4().to_cols_array());
    e[16..20].copy_from_slice(&[p.dims[0] as f32, p.dims[1] as f32, p.dims[2] as f32, p.z0 as f32]);
    let threshold = style.threshold.unwrap_or(0.0) as f32;
    let blend = match style.blend {
        Blend::Composite => 0.0,
        Blend::Max => 1.0,
        Blend::Add => 2.0,
    };
    e[20..24].copy_from_slice(&[blend, style.window[0] as f32, style.window[1] as f32, threshold]);
    let test = match style.threshold {
        None => 0.0,
        Some(_) if style.signed => 2.0,
        Some(_) => 1.0,
    };
    let voxel_world = (p.geometry.smallest_side() * world_per_mm) as f32;
    let opacity = log_clear(layer_opacity(style));
    e[24..28].copy_from_slice(&[1.0 / voxel_world, p.colour0 as f32, opacity, test]);
    e[28..31].copy_from_slice(&size.map(|n| 1.0 / n as f32));
    e
}

impl super::Renderer {
    /// Holds `inputs` as the frames' layers (rule 13), replacing any before; each frame then styles them in this
    /// order (`RenderSettings::layers`). No frame in flight may still use the old ones.
    pub fn set_layers(&mut self, gpu: &Gpu, inputs: &[LayerInput]) -> Result<(), GpuError> {
        let fresh = GpuLayers::new(gpu, inputs)?;
        if let Some(old) = self.layers.replace(fresh) {
            old.destroy(gpu);
        }
        self.write_layer_set(gpu);
        Ok(())
    }

    /// Holds `layers` (read from their files, `scene::layer_set`) as the frames' layers, as `set_layers`.
    pub fn show_layers(&mut self, gpu: &Gpu, layers: &crate::scene::layer_set::Layers) -> Result<(), GpuError> {
        let inputs: Vec<LayerInput> = layers
            .volumes
            .iter()
            .zip(&layers.labels)
            .map(|(volume, labels)| LayerInput {
                volume,
                labels: labels.as_ref().map(|(m, c)| (m, c.clone())),
            })
            .collect();
        self.set_layers(gpu, &inputs)
    }

    /// How many layers the renderer holds.
    pub fn layer_count(&self) -> usize {
        self.layers.as_ref().map_or(0, GpuLayers::count)
    }

    /// Bytes the layers' voxels take on the device.
    pub fn layer_bytes(&self) -> u64 {
        self.layers.as_ref().map_or(0, GpuLayers::bytes)
    }

    pub(super) fn layers_are_current(&self, s: &RenderSettings) -> bool {
        s.layers.is_empty()
            || match (&self.layers, &self.volume) {
                (Some(l), Some(v)) => l.is_current(&s.layers, v.info.dims, &v.info.geometry),
                _ => true,
            }
    }

    /// Checks that frame `s` can mix its layers, and writes their table where it changed.
    pub(super) fn prepare_layers(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<(), GpuError> {
        use crate::scene::settings::CompositeMode as M;
        if s.layers.is_empty() {
            return Ok(());
        }
        if !matches!(s.compositing.mode, M::Emission | M::Density) {
            return Err(GpuError::InvalidSettings(format!(
                "layers mix in the emission and density modes only, not in {} (rule 13)",
                s.compositing.mode.name()
            )));
        }
        if s.uses_light_volume() {
            return Err(GpuError::InvalidSettings(
                "shadows and ambient occlusion do not apply to layered frames yet: turn them off".into(),
            ));
        }
        if let Some(style) = s.layers.iter().find_map(|l| l.check().err()) {
            return Err(GpuError::InvalidSettings(style));
        }
        let (Some(layers), Some(vol)) = (&mut self.layers, &self.volume) else {
            return Ok(());
        };
        if !layers.is_current(&s.layers, vol.info.dims, &vol.info.geometry) {
            layers.write(gpu, &s.layers, vol.info.dims, &vol.info.geometry)?;
        }
        Ok(())
    }

    /// Points the volume set's layer bindings (9–12) at the layers held.
    pub(super) fn write_layer_set(&self, gpu: &Gpu) {
        let Some(l) = &self.layers else { return };
        let image = |view| {
            [vk::DescriptorImageInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
        };
        let buffer = |raw| {
            [vk::DescriptorBufferInfo {
                buffer: raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }]
        };
        let (values, labels) = (image(l.values.view), image(l.labels.view));
        let (params, colours) = (buffer(l.params.raw), image(l.colours.view));
        let set = self.descriptors.volume_set;
        let write = |binding, ty| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(binding)
                .descriptor_type(ty)
        };
        let writes = [
            write(9, vk::DescriptorType::SAMPLED_IMAGE).image_info(&values),
            write(10, vk::DescriptorType::SAMPLED_IMAGE).image_info(&labels),
            write(11, vk::DescriptorType::UNIFORM_BUFFER).buffer_info(&params),
            write(12, vk::DescriptorType::SAMPLED_IMAGE).image_info(&colours),
        ];
        // SAFETY: callers update descriptors only while no submitted work uses them (prepare's contract).
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
    }
}
