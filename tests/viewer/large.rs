//! A large file in the viewer (docs/large-volumes.md): launched on a 512x512x256 file (2^26 voxels), the window
//! first shows a strided preview (1 voxel in 4 per axis) while the file is read, then the volume itself, and the F12
//! screenshot then equals the headless render of the whole file. Under `--gpu-budget`, the viewer shows the
//! pyramid level that fits, says so, and its screenshot equals the headless render of that level.

use crate::common;

use common::compare::diff;
use common::x11::{have, read_screenshot, type_keys, xvfb, Viewer, HOLD};
use std::path::{Path, PathBuf};
use std::time::Duration;
use volcast::volume::budget::{Budgets, GpuBudget};

/// A 512x512x256 uint8 raw file: a shell and a rod with some texture, 64 MiB.
fn write_large(dir: &Path) -> PathBuf {
    let path = dir.join("large_512x512x256_uint8.raw");
    common::scratch::write_raw(&path, [512, 512, 256], |[x, y, z], [fx, fy, fz], out| {
        let r = (fx * fx + fy * fy + fz * fz).sqrt();
        let shell = (1.0 - ((r - 0.35) / 0.05).abs()).max(0.0);
        let rod = (1.0 - (fx * fx + fy * fy).sqrt() / 0.08).max(0.0);
        let v = 200.0 * shell.max(rod) + ((x ^ y ^ z) & 7) as f64;
        out.push(v.min(255.0) as u8);
    });
    path
}

/// Starts the viewer on `args`, waits for the volume and its held window, takes an F12 screenshot and compares it
/// with the headless render of `expected`.
fn shot_matches(display: &str, dir: &Path, args: &[&str], expected: &volcast::volume::Volume, waits: &[&str]) {
    let mut viewer = Viewer::start(display, dir, args, &format!("frames:3;{HOLD};exit"));
    for needle in waits {
        viewer.wait_for(needle, Duration::from_secs(180));
    }
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(display);
    type_keys(display, &window, &["F12"]);
    let (shot, settings) = read_screenshot(dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(120)));
    let d = diff(&shot, &super::formats::headless_render(expected, &settings));
    assert!(d.max <= 1.0, "{args:?}: the view differs from the headless render: {d}");
    viewer.finish_clean();
}

#[test]
fn viewer_previews_a_large_file_then_shows_it_and_its_budget_level() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let dir = common::scratch("viewer-large");
    let path = write_large(&dir);
    let file = path.to_string_lossy().into_owned();
    let whole = volcast::volume::open(&path, &Default::default()).expect("volume");
    // The preview comes first (before the read ends), then the volume replaces it.
    shot_matches(
        &x.display,
        &dir,
        &[&file],
        &whole,
        &[
            "large_512x512x256_uint8.raw: a preview of 1 voxel in 4 per axis (128x128x64 of 512x512x256)",
            "loaded ",
        ],
    );
    // 40 MiB of GPU budget takes level 1 (8 MiB, twice that to upload), not level 0 (64 MiB).
    let budgets = Budgets::host(None).with_gpu(GpuBudget {
        bytes: 40 << 20,
        max_dim: 16384,
    });
    let level = volcast::scale::open(&path, &Default::default(), budgets, None, &mut |_| {}).expect("level 1");
    assert_eq!(level.dims, [256, 256, 128]);
    shot_matches(
        &x.display,
        &dir,
        &[&file, "--gpu-budget", "40M"],
        &level,
        &["showing pyramid level 1 (256x256x128, 1/2 of 512x512x256 per axis"],
    );
}
