//! The memory budgets a volume is shown within, and the rule that picks the level of its resolution pyramid that
//! fits them: the finest level whose voxels fit the host budget (every time step held) and whose cheapest texture
//! fits half the GPU budget (the upload's staging copy needs the other half), within the device's texture size
//! and volcast's in-memory voxel limit. The levels are the pyramid's ([`super::geometry`]), without `volcast
//! convert`'s stop at 64³.

use super::geometry::level_dims;
use crate::volume::limits::MAX_VOXELS;
use crate::volume::voxel::VoxelType;

/// Where no budget is given: a quarter of the machine's memory (`MemTotal`), or 4 GiB where the system does not
/// say.
pub const FALLBACK_HOST: u64 = 4 << 30;

/// The budgets: bytes of host memory the voxels may take, and the device's share where a device is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budgets {
    pub host: u64,
    pub gpu: Option<GpuBudget>,
}

/// What the device takes: bytes of device memory for the volume and its upload, and its 3-D texture size limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuBudget {
    pub bytes: u64,
    pub max_dim: u32,
}

impl Budgets {
    /// The host budget `host` (`None`: [`default_host`]) and no device yet.
    pub fn host(host: Option<u64>) -> Budgets {
        Budgets {
            host: host.unwrap_or_else(default_host),
            gpu: None,
        }
    }

    pub fn with_gpu(self, gpu: GpuBudget) -> Budgets {
        Budgets { gpu: Some(gpu), ..self }
    }
}

/// A quarter of `MemTotal` from /proc/meminfo; [`FALLBACK_HOST`] where it cannot be read.
pub fn default_host() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|info| {
        let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok()
    });
    total.map_or(FALLBACK_HOST, |kib| kib.saturating_mul(1024) / 4)
}

/// A size as the flags take it: a number of bytes with an optional binary suffix K, M, G or T (`512M`, `4G`,
/// `1.5G`; `B`, `iB` and lower case also accepted). Zero is refused: a budget must hold something.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let lower = t.to_ascii_lowercase();
    let digits = lower.trim_end_matches("ib").trim_end_matches('b');
    let (number, shift) = match digits.chars().last() {
        Some('k') => (&digits[..digits.len() - 1], 10),
        Some('m') => (&digits[..digits.len() - 1], 20),
        Some('g') => (&digits[..digits.len() - 1], 30),
        Some('t') => (&digits[..digits.len() - 1], 40),
        _ => (digits, 0),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a size: give bytes, or a number with K, M, G or T (like 512M or 4G)"))?;
    let bytes = value * (1u64 << shift) as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes > 2f64.powi(62) {
        return Err(format!(
            "'{text}' is not a usable size: it must be at least 1 byte and at most 4 EiB"
        ));
    }
    Ok(bytes as u64)
}

/// `bytes` in bytes, KiB, MiB or (from 10 GiB) GiB, as the notes and errors print sizes.
pub fn show(bytes: u64) -> String {
    if bytes < 1 << 10 {
        format!("{bytes} bytes")
    } else if bytes < 1 << 20 {
        format!("{} KiB", bytes.div_ceil(1 << 10))
    } else if bytes >= 10 << 30 {
        format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        format!("{} MiB", bytes.div_ceil(1 << 20))
    }
}

/// Bytes per voxel the volume is held in on the host (32-bit integers and float64 are held as float32).
pub fn held_bytes(t: VoxelType) -> u64 {
    match t {
        VoxelType::U8 | VoxelType::I8 => 1,
        VoxelType::U16 | VoxelType::I16 => 2,
        _ => 4,
    }
}

/// The border of voxels the GPU's brick pool keeps around every brick, on every side (`render::pool::BORDER`): a
/// volume uploaded whole is one brick, so its texture is 2·BRICK_BORDER voxels longer along each axis.
pub const BRICK_BORDER: u32 = 2;

/// What a volume is: its shape, type and time steps.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    pub dims: [u32; 3],
    pub voxel_type: VoxelType,
    pub steps: u32,
}

impl Shape {
    fn voxels(dims: [u32; 3]) -> u64 {
        dims.iter().map(|&d| u64::from(d)).product()
    }

    /// Bytes level `level` takes on the host (every step) and in its cheapest texture (one step, as one brick of
    /// the pool with its border: what the upload allocates).
    pub fn level_bytes(&self, level: u32) -> (u64, u64) {
        let dims = level_dims(self.dims, level);
        let bytes = held_bytes(self.voxel_type);
        let one = Shape::voxels(dims).saturating_mul(bytes);
        let bordered = Shape::voxels(dims.map(|d| d.saturating_add(2 * BRICK_BORDER))).saturating_mul(bytes);
        (one.saturating_mul(u64::from(self.steps.max(1))), bordered)
    }
}

/// The level the budgets allow and, for a level above 0, why full resolution did not fit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level {
    pub level: u32,
    pub dims: [u32; 3],
    pub why: Option<String>,
}

/// Why level `level` of `shape` does not fit `budgets`, or `None` if it does.
pub fn misfit(shape: &Shape, level: u32, budgets: &Budgets) -> Option<String> {
    let dims = level_dims(shape.dims, level);
    let voxels = Shape::voxels(dims);
    let (host, texture) = shape.level_bytes(level);
    if host > budgets.host {
        return Some(format!(
            "it needs {} of memory and the host budget is {} (--host-budget)",
            show(host),
            show(budgets.host)
        ));
    }
    if voxels > MAX_VOXELS {
        return Some(format!(
            "{voxels} voxels are more than the {MAX_VOXELS} volcast holds as one volume"
        ));
    }
    let gpu = budgets.gpu?;
    if dims.iter().any(|&d| d > gpu.max_dim) {
        return Some(format!(
            "the device's 3-D textures are at most {} per side",
            gpu.max_dim
        ));
    }
    (texture > gpu.bytes / 2).then(|| {
        format!(
            "its texture needs {} and as much again to upload, and the GPU budget is {} (--gpu-budget)",
            show(texture),
            show(gpu.bytes)
        )
    })
}

/// The finest level of `shape` that fits `budgets`; an error (with the numbers) when not even one voxel does.
pub fn choose(shape: &Shape, budgets: &Budgets) -> Result<Level, String> {
    let mut level = 0;
    loop {
        let dims = level_dims(shape.dims, level);
        match misfit(shape, level, budgets) {
            None => {
                let why = (level > 0).then(|| misfit(shape, 0, budgets)).flatten();
                return Ok(Level { level, dims, why });
            }
            Some(why) if dims == [1, 1, 1] => {
                return Err(format!("not even one voxel per step fits: {why}"));
            }
            Some(_) => level += 1,
        }
    }
}

/// The note a volume shown at a coarser level carries.
pub fn level_note(full: [u32; 3], level: &Level) -> String {
    let [a, b, c] = full;
    let [x, y, z] = level.dims;
    format!(
        "pyramid level {} ({x}x{y}x{z}, 1/{} of {a}x{b}x{c} per axis, the mean of each block): at full resolution \
         {}",
        level.level,
        1u32 << level.level,
        level.why.as_deref().unwrap_or("it does not fit")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_size("512M").unwrap(), 512 << 20);
        assert_eq!(parse_size("4G").unwrap(), 4 << 30);
        assert_eq!(parse_size("1.5GiB").unwrap(), 3 << 29);
        assert_eq!(parse_size("4096").unwrap(), 4096);
        assert!(parse_size("0").is_err());
        assert!(parse_size("lots").is_err());
        assert!(parse_size("-1G").is_err());
    }

    #[test]
    fn the_finest_level_that_fits_both_budgets() {
        let shape = Shape {
            dims: [2048, 2048, 2048],
            voxel_type: VoxelType::U16,
            steps: 1,
        };
        let host = Budgets::host(Some(6 << 30));
        // 16 GiB at level 0, 2 GiB at level 1.
        assert_eq!(choose(&shape, &host).unwrap().level, 1);
        // A 2 GiB device takes 1 GiB of texture: 512^3 x 2 bytes = 256 MiB at level 2; level 1 needs 2 GiB.
        let gpu = host.with_gpu(GpuBudget {
            bytes: 2 << 30,
            max_dim: 16384,
        });
        let level = choose(&shape, &gpu).unwrap();
        assert_eq!((level.level, level.dims), (2, [512, 512, 512]));
        assert!(
            level.why.unwrap().contains("host budget"),
            "level 0 fails the host budget first"
        );
        // The texture size limit alone.
        let small = Shape {
            dims: [4096, 256, 256],
            voxel_type: VoxelType::U8,
            steps: 1,
        };
        let limit = Budgets::host(Some(1 << 40)).with_gpu(GpuBudget {
            bytes: 1 << 40,
            max_dim: 4096,
        });
        assert_eq!(choose(&small, &limit).unwrap().level, 0);
        let limit = Budgets::host(Some(1 << 40)).with_gpu(GpuBudget {
            bytes: 1 << 40,
            max_dim: 2048,
        });
        assert_eq!(choose(&small, &limit).unwrap().dims, [2048, 128, 128]);
    }

    #[test]
    fn the_texture_counts_its_border() {
        // 1024^3 uint8 is exactly half a 2 GiB budget, but uploaded with its 2-voxel border it is 1028^3: over.
        let shape = Shape {
            dims: [1024; 3],
            voxel_type: VoxelType::U8,
            steps: 1,
        };
        let gpu = Budgets::host(Some(6 << 30)).with_gpu(GpuBudget {
            bytes: 2 << 30,
            max_dim: 16384,
        });
        assert_eq!(shape.level_bytes(0), (1 << 30, 1028u64.pow(3)));
        assert!(misfit(&shape, 0, &gpu).is_some_and(|why| why.contains("as much again to upload")));
        assert_eq!(choose(&shape, &gpu).unwrap().level, 1);
    }

    #[test]
    fn nothing_fits_a_budget_of_one_byte_per_step_too_small() {
        let shape = Shape {
            dims: [4, 4, 4],
            voxel_type: VoxelType::F32,
            steps: 1,
        };
        let e = choose(&shape, &Budgets::host(Some(3))).unwrap_err();
        assert!(e.contains("host budget"), "{e}");
    }
}
