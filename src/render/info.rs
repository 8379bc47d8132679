//! What `volcast info` says about a volume, in words and as JSON. Pure formatting of a loaded [`Volume`].

use super::AUTO_LIMIT;
use crate::scene::quality::Gradients;
use crate::volume::geometry::Handedness;
use crate::volume::Volume;
use serde::Serialize;

/// `volcast info --json`: one object per volume.
#[derive(Clone, Debug, Serialize)]
pub struct Info {
    pub name: String,
    pub format: String,
    /// [W, H, D], i fastest on disk.
    pub dims: [u32; 3],
    /// The voxel type in the file: uint8, int16, float32, ...
    #[serde(rename = "type")]
    pub voxel_type: String,
    /// Voxel size along i, j, k in millimetres (the affine's column lengths).
    pub spacing: [f64; 3],
    /// Min and max of the stored values (before a rescale).
    pub value_range: [f64; 2],
    /// Min and max after the file's rescale (slope/intercept), what transfer functions in data units see.
    pub scaled_range: [f64; 2],
    /// Time steps (1 for 3-D data).
    pub timesteps: u32,
    /// Voxel index (i, j, k, 1) to world millimetres, row-major; RAS+ for anatomical files.
    pub affine_ras: [[f64; 4]; 4],
    /// Whether the file says which way the patient lies (else the world is the file's own x, y, z).
    pub anatomical: bool,
    /// Where +i, +j and +k point, as nibabel's `aff2axcodes` names it ("LAS"); null without orientation.
    pub axes: Option<String>,
    /// "right", or "left" for a mirrored (left-handed) affine.
    pub handedness: &'static str,
    /// Largest angle between an index axis and its nearest world axis (degrees): 0 unless oblique.
    pub obliquity_deg: f64,
    /// Largest departure of the index axes from perpendicular (degrees): a sheared series (gantry tilt).
    pub shear_deg: f64,
    pub notes: Vec<String>,
    /// The file's point-data arrays (VTK files hold several; `--array NAME` picks one); empty for other formats.
    pub arrays: Vec<crate::volume::ArrayInfo>,
    /// The series of a DICOM folder holding several (`--series N|UID` picks one); empty otherwise.
    pub series: Vec<crate::volume::SeriesInfo>,
    /// The channels of an OME-Zarr image (`--channel N` picks one); absent for other formats.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<crate::volume::ChannelInfo>,
}

impl Info {
    pub fn of(v: &Volume) -> Info {
        let g = &v.geometry;
        Info {
            name: v.name.clone(),
            format: v.format.clone(),
            dims: v.dims,
            voxel_type: v.source_type.name().to_string(),
            spacing: g.spacing(),
            value_range: v.stored_range,
            scaled_range: v.range,
            timesteps: v.timesteps(),
            affine_ras: g.rows(),
            anatomical: g.anatomical,
            axes: g.axcodes().map(|c| c.iter().collect()),
            handedness: g.handedness().name(),
            obliquity_deg: g.obliquity_deg(),
            shear_deg: g.shear_deg(),
            notes: v.notes.clone(),
            arrays: v.arrays.clone(),
            series: v.series.clone(),
            channels: v.channels.clone(),
        }
    }

    /// The same in words, as `volcast info` prints it.
    pub fn text(&self, v: &Volume) -> String {
        let mut out = Lines(String::new());
        self.write_shape(v, &mut out);
        self.write_values(v, &mut out);
        out.line("axes", self.axes_in_words(v));
        self.write_affine(&mut out);
        write_gpu_memory(v, &mut out);
        self.write_arrays_and_notes(&mut out);
        out.0
    }

    /// Name, file format, dimensions, voxel type, time steps, spacing and size.
    fn write_shape(&self, v: &Volume, out: &mut Lines) {
        out.line("name", self.name.clone());
        out.line("format", self.format.clone());
        out.line(
            "dims",
            format!("{} x {} x {}", self.dims[0], self.dims[1], self.dims[2]),
        );
        out.line("type", self.voxel_type.clone());
        if self.timesteps > 1 {
            out.line(
                "timesteps",
                format!(
                    "{} (showing {}; the range below is over all of them; --time N picks one)",
                    self.timesteps,
                    v.shown_step()
                ),
            );
        }
        let [x, y, z] = self.spacing.map(crate::volume::geometry::shortest);
        out.line("spacing", format!("{x} x {y} x {z}"));
        let e = v.extent();
        let size = [0, 1, 2].map(|i| f64::from(self.dims[i]) * self.spacing[i]);
        out.line(
            "size",
            format!(
                "{:.1} x {:.1} x {:.1} mm; box {:.3} x {:.3} x {:.3}",
                size[0], size[1], size[2], e.x, e.y, e.z
            ),
        );
    }

    /// The value range; stored and scaled apart when the file rescales its values.
    fn write_values(&self, v: &Volume, out: &mut Lines) {
        if v.scaling.is_identity() {
            out.line("range", format!("{} .. {}", self.scaled_range[0], self.scaled_range[1]));
        } else {
            out.line("stored", format!("{} .. {}", self.value_range[0], self.value_range[1]));
            out.line(
                "scaled",
                format!(
                    "{} .. {} (value = {} * stored + {})",
                    self.scaled_range[0], self.scaled_range[1], v.scaling.slope, v.scaling.intercept
                ),
            );
        }
    }

    /// The affine's first three rows (the fourth is always 0 0 0 1).
    fn write_affine(&self, out: &mut Lines) {
        for (i, row) in self.affine_ras.iter().take(3).enumerate() {
            let key = if i == 0 { "affine" } else { "" };
            let cells: Vec<String> = row.iter().map(|c| format!("{c:>11.5}")).collect();
            out.line(key, cells.join(" "));
        }
    }

    fn write_arrays_and_notes(&self, out: &mut Lines) {
        for (i, a) in self.arrays.iter().enumerate() {
            let loaded = if a.loaded { " (loaded)" } else { "" };
            out.line(
                if i == 0 { "arrays" } else { "" },
                format!("{}: {}, {} component(s){loaded}", a.name, a.type_name, a.components),
            );
        }
        for (i, s) in self.series.iter().enumerate() {
            let loaded = if s.loaded { " (loaded)" } else { "" };
            out.line(if i == 0 { "series" } else { "" }, format!("{}{loaded}", s.line()));
        }
        for (i, c) in self.channels.iter().enumerate() {
            let loaded = if c.loaded { " (loaded)" } else { "" };
            let [r, g, b] = c.color;
            out.line(
                if i == 0 { "channels" } else { "" },
                match c.window {
                    // An empty window: the file gives none (a TIFF's channels).
                    [lo, hi] if lo < hi => format!(
                        "{i}: {}, window {lo} .. {hi}, colour #{r:02X}{g:02X}{b:02X}{loaded}",
                        c.name
                    ),
                    _ => format!("{i}: {}, colour #{r:02X}{g:02X}{b:02X}{loaded}", c.name),
                },
            );
        }
        for note in &self.notes {
            out.line("note", note.clone());
        }
    }

    fn axes_in_words(&self, v: &Volume) -> String {
        let Some(codes) = &self.axes else {
            return "no orientation in the file: the world is its own x, y, z (no anatomical directions)".into();
        };
        let names: Vec<String> = codes
            .chars()
            .zip(['i', 'j', 'k'])
            .map(|(c, axis)| format!("+{axis} towards {}", direction_name(c)))
            .collect();
        let mut words = format!("{codes} ({}), RAS+ world", names.join(", "));
        if v.geometry.handedness() == Handedness::Left {
            words += "; mirrored (left-handed)";
        }
        if self.obliquity_deg > 0.5 {
            words += &format!("; oblique by {:.1}°", self.obliquity_deg);
        }
        if self.shear_deg > 0.01 {
            words += &format!("; sheared by {:.2}°", self.shear_deg);
        }
        words
    }
}

/// `volcast info`'s text: `key: value` lines with the values aligned; an empty key continues the line above.
struct Lines(String);

impl Lines {
    fn line(&mut self, key: &str, value: String) {
        let key = if key.is_empty() {
            String::new()
        } else {
            format!("{key}:")
        };
        self.0.push_str(&format!("{key:<10} {value}\n"))
    }
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1 << 20) as f64
}

/// What the volume takes on the GPU: its texture, the corner textures CPU devices get, the gradient texture.
fn write_gpu_memory(v: &Volume, out: &mut Lines) {
    let gpu_format = match v.gpu_texel_size() {
        1 => "R8_UNORM",
        2 => "R16_UNORM",
        _ => "R32_SFLOAT",
    };
    out.line(
        "gpu",
        format!("{gpu_format}, {:.1} MiB", mib(v.gpu_memory_bytes() as usize)),
    );
    if v.gpu_texel_size() < 4 {
        out.line(
            "",
            cpu_auto_layout(v.voxel_count() as u64, v.gpu_texel_size() as u64, gpu_format),
        );
    }
    let voxels = v.voxel_count() as u64;
    let gradient_bytes = Gradients::texture_bytes(voxels);
    out.line(
        "",
        if Gradients::texture_fits(voxels) {
            format!(
                "shaded frames, --gradients auto: + gradient texture (RGBA16 SNORM), {:.1} MiB",
                mib(gradient_bytes as usize)
            )
        } else {
            format!(
                "shaded frames, --gradients auto: six samples per gradient (a gradient texture would take \
                 {:.1} MiB, over 1 GiB)",
                mib(gradient_bytes as usize)
            )
        },
    );
}

/// What `--texture auto` gives 8- and 16-bit data on a CPU device, as `gpu_volume::choose_layout` decides it: the
/// corner layout, else a float texture, else the data's own format, each only while it stays within
/// [`AUTO_LIMIT`] (and a quarter of the device's memory). Says the limit and the sizes that passed it, so a large
/// volume's line reads as what happens rather than as a condition.
fn cpu_auto_layout(voxels: u64, texel_size: u64, native_format: &str) -> String {
    let corners = format!("corners{}", 8 * texel_size);
    let (corner_bytes, float_bytes) = (voxels * 4 * texel_size, voxels * 4);
    let limit = format!("{} GiB", AUTO_LIMIT >> 30);
    let head = "on CPU devices (lavapipe), --texture auto:";
    let mib = |b: u64| mib(b as usize);
    if corner_bytes <= AUTO_LIMIT {
        format!(
            "{head} {corners}, {:.1} MiB (the fastest layout to sample, used while within {limit} and a quarter of \
             the device's memory)",
            mib(corner_bytes)
        )
    } else if float_bytes <= AUTO_LIMIT {
        format!(
            "{head} R32_SFLOAT, {:.1} MiB ({corners} would take {:.1} MiB, over the {limit} limit on faster \
             layouts)",
            mib(float_bytes),
            mib(corner_bytes)
        )
    } else {
        format!(
            "{head} {native_format} as above ({corners} would take {:.1} MiB and R32_SFLOAT {:.1} MiB, both over the \
             {limit} limit on faster layouts)",
            mib(corner_bytes),
            mib(float_bytes)
        )
    }
}

/// A RAS axis code's name.
pub fn direction_name(code: char) -> &'static str {
    match code {
        'R' => "right",
        'L' => "left",
        'A' => "anterior",
        'P' => "posterior",
        'S' => "superior",
        'I' => "inferior",
        _ => "?",
    }
}
