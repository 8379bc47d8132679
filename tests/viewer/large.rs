//! A large file in the viewer (docs/large-volumes.md): launched on a 512x512x256 file (2^26 voxels), the window
//! first shows a strided preview (1 voxel in 4 per axis) while the file is read, then the volume itself, and the F12
//! screenshot then equals the headless render of the whole file; a DICOM series of that size alike. Under a
//! `--gpu-budget` it is over whole, the viewer streams it through a pool of bricks, says so, refines (again after a
//! real drag), and its screenshots equal the headless render streamed within the same budget, as does its exported
//! figure. Under a `--host-budget` that holds only level 1, level 0's bricks are read from the file where the still
//! view wants them (from its OME-Zarr store's level 0, and from a gzip file's level 0 kept in the pyramid cache,
//! alike).

use crate::common;

use common::compare::diff;
use common::x11::{drag, have, read_screenshot, type_keys, xvfb, Viewer, HOLD};
use std::path::{Path, PathBuf};
use std::time::Duration;

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

/// Starts the viewer on `path` (a file or a DICOM folder) and asserts that it first logs a line containing `preview`
/// (before the read ends), then the volume replacing it, whose F12 screenshot equals the headless render.
fn previews_then_shows(dir: &Path, path: &Path, preview: &str) {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let file = path.to_string_lossy().into_owned();
    let whole = volcast::formats::open(path, &Default::default()).expect("volume");
    shot_matches(&x.display, dir, &[&file], &whole, &[preview, "loaded "]);
}

#[test]
fn viewer_previews_a_large_file_then_shows_it() {
    let dir = common::scratch("viewer-large");
    let path = write_large(&dir);
    let preview = "large_512x512x256_uint8.raw: a preview of 1 voxel in 4 per axis (128x128x64 of 512x512x256)";
    previews_then_shows(&dir, &path, preview);
}

/// A large DICOM series (512x512x256, its files shuffled) is previewed too, from every 4th slice decoded from its
/// own file, then replaced by the series read whole.
#[test]
fn viewer_previews_a_large_dicom_series_then_shows_it() {
    let dir = common::scratch("viewer-large-series");
    let series = common::dicom_series::large(&dir.join("series"), [512, 512, 256]);
    previews_then_shows(
        &dir,
        &series,
        "series: a preview of 1 voxel in 4 per axis (128x128x64 of 512x512x256)",
    );
    std::fs::remove_dir_all(&series).ok();
}

/// Within a host budget that holds only level 1 of the file, the viewer streams level 0's bricks from the file
/// where the still view wants them: the refined screenshot shows level 0 and equals the headless render of the
/// same held level streamed within the same budgets.
#[test]
fn viewer_shows_full_resolution_from_the_file_within_the_host_budget() {
    let dir = common::scratch("viewer-finer");
    let path = write_large(&dir);
    full_resolution_within_the_host_budget(&path, &dir);
}

/// The same for the file's OME-Zarr store (`volcast convert`'s): level 1 from the store, level 0's bricks from
/// the store's level 0.
#[test]
fn viewer_shows_full_resolution_from_an_ome_zarr_store_within_the_host_budget() {
    let dir = common::scratch("viewer-finer-zarr");
    let raw = write_large(&dir);
    let store = dir.join("large.ome.zarr");
    let o = common::volcast(&["convert", &raw.to_string_lossy(), &store.to_string_lossy()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    std::fs::remove_file(&raw).expect("the raw file is not needed");
    full_resolution_within_the_host_budget(&store, &dir);
}

/// The same for a gzip NRRD of the file: decoded once, as a stream, into level 1, its level 0 kept in the pyramid
/// cache as it is decoded, and level 0's bricks read from there.
#[test]
fn viewer_shows_full_resolution_from_a_gzip_file_within_the_host_budget() {
    let dir = common::scratch("viewer-finer-gzip");
    let raw = write_large(&dir);
    let gz = dir.join("large.nrrd");
    common::scratch::gzip_nrrd(&raw, [512, 512, 256], "uint8", &gz);
    std::fs::remove_file(&raw).expect("the raw file is not needed");
    full_resolution_within_the_host_budget(&gz, &dir);
}

fn full_resolution_within_the_host_budget(path: &Path, dir: &Path) {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let d = &x.display;
    let file = path.to_string_lossy().into_owned();
    let budgets = volcast::pyramid::budget::Budgets::host(Some(20 << 20));
    // Its own cache: a compressed file's level 0 is kept there (the viewer keeps its own in `cache` below).
    let held_cache = volcast::scale::cache::PyramidCache::new(Some(dir.join("held-cache")));
    let held = volcast::scale::open(path, &Default::default(), budgets, Some(&held_cache), &mut |_| {}).expect("held");
    assert_eq!(held.dims, [256, 256, 128]);
    assert!(held.finer.is_some(), "level 0 stays behind the held level");
    let args = [
        file.as_str(),
        "--host-budget",
        "20M",
        "--gpu-budget",
        "256M",
        "--cache-dir",
    ];
    let cache = dir.join("cache").to_string_lossy().into_owned();
    let mut viewer = Viewer::start(
        d,
        dir,
        &[&args[..], &[&cache]].concat(),
        &format!("frames:3;{HOLD};exit"),
    );
    let wait = Duration::from_secs(180);
    viewer.wait_for("large holds level 1 of its 512x512x256 voxels", wait);
    let refined = viewer.wait_for("refined: every brick at its level", wait);
    assert!(
        refined.contains("level 0 in"),
        "the still view shows level-0 bricks: {refined}"
    );
    viewer.wait_for("script: Hold", wait);
    let window = viewer.window(d);
    type_keys(d, &window, &["F12"]);
    let (shot, settings) = read_screenshot(dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(120)));
    let expected = super::formats::headless_render_within(&held, &settings, Some(256 << 20));
    let diff = diff(&shot, &expected);
    assert!(
        diff.max <= 1.0,
        "the view differs from the headless render of the file's levels: {diff}"
    );
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn viewer_streams_a_file_over_the_gpu_budget_and_refines_again_after_a_drag() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let d = &x.display;
    let dir = common::scratch("viewer-streamed");
    let path = write_large(&dir);
    let file = path.to_string_lossy().into_owned();
    let whole = volcast::formats::open(&path, &Default::default()).expect("volume");
    // 40 MiB of GPU budget: the 64 MiB file is over it whole, so it is read at full resolution and streamed
    // through a pool of 20 MiB (64 bricks of 64^3), refined to the screen rule's cut for the still view.
    let mut viewer = Viewer::start(
        d,
        &dir,
        &[&file, "--gpu-budget", "40M"],
        &format!("frames:3;{HOLD};exit"),
    );
    let wait = Duration::from_secs(180);
    viewer.wait_for(
        "large is over the GPU budget whole (40 MiB); streamed through a pool of",
        wait,
    );
    viewer.wait_for("refined: every brick at its level", wait);
    viewer.wait_for("script: Hold", wait);
    let window = viewer.window(d);
    let shot = |viewer: &mut Viewer| {
        type_keys(d, &window, &["F12"]);
        read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(120)))
    };
    let (first, before) = shot(&mut viewer);
    let expected = super::formats::headless_render_within(&whole, &before, Some(40 << 20));
    let d0 = diff(&first, &expected);
    assert!(
        d0.max <= 1.0,
        "the refined view differs from the headless render streamed within 40 MiB: {d0}"
    );
    // A real drag turns the camera (one level coarser while it lasts); once still, the view refines again to the
    // new view's cut.
    drag(d, &window, "1", egui::pos2(560.0, 300.0), egui::vec2(20.0, 0.0), 6);
    viewer.wait_for("refined: every brick at its level", wait);
    let (second, after) = shot(&mut viewer);
    assert_ne!(before.camera.eye, after.camera.eye, "the drag turned the camera");
    let d1 = diff(
        &second,
        &super::formats::headless_render_within(&whole, &after, Some(40 << 20)),
    );
    assert!(
        d1.max <= 1.0,
        "after the drag the view differs from the headless render streamed within 40 MiB: {d1}"
    );
    // "Export figure" at the view's size without the colour bar and the scale bar streams its own copy within the same budget,
    // refined for that view: it is the view.
    use super::export::{export, scroll_to_export, toggle_colorbar, toggle_scale_bar, type_into};
    let (w, h) = second.dimensions();
    scroll_to_export(&mut viewer, d, &window);
    type_into(&mut viewer, d, &window, "export-width", &w.to_string());
    type_into(&mut viewer, d, &window, "export-height", &h.to_string());
    toggle_colorbar(&mut viewer, d, &window, "off");
    toggle_scale_bar(&mut viewer, d, &window, "off");
    let figure = export(&mut viewer, d, &window, &dir);
    let d2 = diff(&figure, &second);
    assert!(
        d2.max <= 1.0,
        "the exported figure of the streamed volume differs from the view: {d2}"
    );
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
