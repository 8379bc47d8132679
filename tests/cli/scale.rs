//! Volumes larger than the budgets, through the binary (docs/large-volumes.md): a file over `--gpu-budget` is shown
//! at the pyramid level that fits, read level by level from the file, and that level is the one `volcast convert`
//! writes (the two renders are the same image); a budget that holds nothing, `--no-downsample`, a compressed file
//! over the host budget, a header that claims terabytes; a file past 2^31 voxels, once refused, opens at a coarser
//! level; and the pyramid cache (used, rebuilt when stale or corrupt, never fatal).

use crate::common;

use common::{stderr, stdout, volcast, volcast_ok};
use std::path::Path;

/// The largest difference of two images' channels, in 1/255.
fn max_diff(a: &image::RgbaImage, b: &image::RgbaImage) -> Option<u8> {
    a.as_raw().iter().zip(b.as_raw()).map(|(p, q)| p.abs_diff(*q)).max()
}

/// A 160x96x80 int16 raw file (levels 160x96x80, 80x48x40, 40x24x20) with negative values and structure.
fn write_volume(dir: &Path) -> String {
    let path = dir.join("ball_160x96x80_int16.raw");
    common::scratch::write_raw(&path, [160, 96, 80], |[x, y, z], [fx, fy, fz], out| {
        let r = (fx * fx + fy * fy + fz * fz).sqrt();
        let v = (3000.0 * (1.0 - 2.5 * r)).round() as i16 - 500 + ((x * 7 + y * 3 + z) % 5) as i16;
        out.extend_from_slice(&v.to_le_bytes());
    });
    path.to_string_lossy().into_owned()
}

#[test]
fn over_the_gpu_budget_a_file_shows_the_level_convert_writes() {
    let dir = common::scratch("cli-scale-level");
    let raw = write_volume(&dir);
    // Level 1 takes 80x48x40x2 = 300 KiB, twice that with the upload; level 0 takes 2.3 MiB. The host budget
    // reads level 1 from the file.
    let a = dir.join("budget.png");
    let o = volcast_ok(&["render", &raw, "--host-budget", "700K", "-o", &a.to_string_lossy()]);
    let err = stderr(&o);
    let err_a = err.clone();
    assert!(
        err.contains(
            "note: pyramid level 1 (80x48x40, 1/2 of 160x96x80 per axis, the mean of each block): at full \
             resolution it needs 3 MiB of memory and the host budget is 700 KiB"
        ),
        "{err}"
    );
    assert!(stdout(&o).contains("(80x48x40 int16"), "{}", stdout(&o));
    // A GPU budget without room for one brick of the pool (400 KiB for bricks of 64x64x64 R16, 614 KiB each):
    // the finest whole level within it (level 1 with its 2-voxel border, 84x52x44 R16, 384 KiB and as much again).
    let o = volcast_ok(&[
        "render",
        &raw,
        "--gpu-budget",
        "800K",
        "-o",
        &dir.join("gpu.png").to_string_lossy(),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains("note: pyramid level 1 (80x48x40, 1/2 of 160x96x80 per axis, the mean of each block): at full resolution its texture needs 3 MiB"),
        "{err}"
    );
    assert!(stdout(&o).contains("(80x48x40 int16"), "{}", stdout(&o));
    let store = dir.join("ball.ome.zarr");
    let o = volcast(&["convert", &raw, &store.to_string_lossy()]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The level held is the one the store holds (the same voxels; it normalises by level 0's range, the store's
    // level by its own), and the render within the host budget streams level 0's bricks from the file where the
    // view wants them: at 512² it equals the render of the whole file at full resolution.
    assert!(err_a.contains("holds level 1 of its 160x96x80 voxels"), "{err_a}");
    let held = volcast(&["info", &raw, "--host-budget", "700K", "--json"]);
    let stored = volcast(&["info", &store.to_string_lossy(), "--max-dim", "80", "--json"]);
    let json = |o: &std::process::Output| serde_json::from_str::<serde_json::Value>(&stdout(o)).unwrap();
    assert_eq!(json(&held)["dims"], json(&stored)["dims"]);
    let full = dir.join("full.png");
    volcast_ok(&["render", &raw, "-o", &full.to_string_lossy()]);
    let (a, full) = (
        image::open(&a).unwrap().to_rgba8(),
        image::open(&full).unwrap().to_rgba8(),
    );
    let worst = max_diff(&a, &full);
    assert!(
        worst <= Some(1),
        "within the host budget, full resolution from the file: differs by {worst:?}"
    );
    // The store within the same budget: its level 1 held, level 0's bricks read from the store where the view
    // wants them; the same image.
    let z = dir.join("store.png");
    let o = volcast_ok(&[
        "render",
        &store.to_string_lossy(),
        "--host-budget",
        "700K",
        "-o",
        &z.to_string_lossy(),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains("holds level 1 of its 160x96x80 voxels") && err.contains("level 0 in"),
        "{err}"
    );
    let z = image::open(&z).unwrap().to_rgba8();
    let worst = max_diff(&z, &full);
    assert!(
        worst <= Some(1),
        "within the host budget, full resolution from the store: differs by {worst:?}"
    );
    // The host budget alone (info has no device): level 2.
    let o = volcast(&["info", &raw, "--host-budget", "100K"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("dims:      40 x 24 x 20"), "{text}");
    assert!(text.contains("the host budget is 100 KiB (--host-budget)"), "{text}");
}

#[test]
fn budgets_that_hold_nothing_and_refusals_name_the_numbers() {
    let dir = common::scratch("cli-scale-refusals");
    let raw = write_volume(&dir);
    let o = volcast(&["info", &raw, "--host-budget", "1"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("ball_160x96x80_int16.raw"), "{err}");
    assert!(err.contains("not even one voxel per step fits"), "{err}");
    let o = volcast(&["info", &raw, "--host-budget", "1M", "--no-downsample"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--no-downsample refuses a coarser level"), "{err}");
    assert!(
        err.contains("needs 3 MiB of memory and the host budget is 1 MiB"),
        "{err}"
    );
    let o = volcast(&["info", &raw, "--host-budget", "lots"]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
    assert!(stderr(&o).contains("'lots' is not a size"), "{}", stderr(&o));
    // A gzip file over the host budget is decoded as a stream into the level that fits (formats::streamed proves the
    // voxels).
    let gz = format!("{}/tests/data/world/nifti_ras.nii.gz", env!("CARGO_MANIFEST_DIR"));
    let o = volcast(&["info", &gz, "--host-budget", "50K", "--no-cache"]);
    let out = String::from_utf8_lossy(&o.stdout).into_owned() + &stderr(&o);
    assert!(o.status.success(), "{out}");
    assert!(out.contains("17 x 20 x 18"), "{out}");
    assert!(out.contains("decoded once, as a stream"), "{out}");
    // An ASCII NRRD is read whole: over the host budget it is refused before it is decoded.
    let ascii = dir.join("ascii.nrrd");
    let mut text = String::from("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 40 40 40\nencoding: ascii\n\n");
    text += &"7 ".repeat(40 * 40 * 40);
    std::fs::write(&ascii, text).expect("write");
    let o = volcast(&["info", ascii.to_str().unwrap(), "--host-budget", "50K"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("ascii.nrrd") && err.contains("its 40x40x40 uint8 voxels need 63 KiB of memory to decode"),
        "{err}"
    );
    assert!(err.contains("store it as raw or gzip"), "{err}");
    // A header claiming 16384^3 float32 (16 TiB) over a few bytes: refused before anything is read.
    let nrrd = dir.join("huge.nrrd");
    let header = "NRRD0004\ntype: float\ndimension: 3\nsizes: 16384 16384 16384\nencoding: raw\n\n";
    std::fs::write(&nrrd, [header.as_bytes(), &[0u8; 64]].concat()).unwrap();
    let o = volcast(&["info", &nrrd.to_string_lossy()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("huge.nrrd") && err.contains("17592186044416"), "{err}");
}

/// Past 2^31 voxels (the old cap): within the host budget a file opens at full resolution, and `render` streams it
/// through a pool of half the GPU budget; under a smaller host budget, at the level that holds.
#[test]
fn past_two_to_the_31_voxels_a_file_opens_whole_and_streams() {
    let dir = common::scratch("cli-scale-sparse");
    // 2048x1024x1025 uint8 (2^31 + 2^21 voxels), sparse: it takes no disk and reads as zeros but one marked voxel
    // block near the far corner.
    let path = dir.join("sparse_2048x1024x1025_uint8.raw");
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(2048 * 1024 * 1025).unwrap();
    use std::os::unix::fs::FileExt;
    let last = 2048u64 * 1024 * 1024;
    file.write_all_at(&[200, 200], last + 2046).unwrap();
    drop(file);
    let file = path.to_string_lossy();
    let o = volcast(&["info", &file, "--host-budget", "8G", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(json["dims"], serde_json::json!([2048, 1024, 1025]), "{json}");
    assert_eq!(json["value_range"], serde_json::json!([0.0, 200.0]), "{json}");
    let o = volcast(&["info", &file, "--host-budget", "1G", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(json["dims"], serde_json::json!([1024, 512, 513]), "{json}");
    let notes = json["notes"].to_string();
    assert!(notes.contains("pyramid level 1 (1024x512x513"), "{notes}");
    assert!(notes.contains("the host budget is 1024 MiB"), "{notes}");
    // The level's voxel (1023, 0, 512) is the mean of the block holding the two 200s (400 / 4, exactly 100), but
    // the level stands for the file: it takes level 0's range, found while reading it.
    assert_eq!(json["value_range"], serde_json::json!([0.0, 200.0]), "{json}");
    let png = dir.join("sparse.png");
    let o = volcast_ok(&[
        "render",
        &file,
        "--host-budget",
        "8G",
        "--gpu-budget",
        "1G",
        "--size",
        "64x64",
        "-o",
        &png.to_string_lossy(),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains(
            "note: sparse is over the GPU budget whole (1024 MiB); streamed through a pool of 1584 bricks of 64x64x64"
        ),
        "{err}"
    );
    assert!(stdout(&o).contains("(2048x1024x1025 uint8"), "{}", stdout(&o));
}

#[test]
fn the_pyramid_cache_is_used_rebuilt_when_stale_or_corrupt_and_never_fatal() {
    let dir = common::scratch("cli-scale-cache");
    let raw = write_volume(&dir);
    let cache = dir.join("cache").to_string_lossy().into_owned();
    let render = |name: &str| {
        let out = dir.join(name);
        let o = volcast_ok(&[
            "render",
            &raw,
            "--host-budget",
            "700K",
            "--cache-dir",
            &cache,
            "-o",
            &out.to_string_lossy(),
        ]);
        (stderr(&o), image::open(&out).unwrap().to_rgba8())
    };
    let (first, a) = render("miss.png");
    assert!(!first.contains("pyramid cache"), "{first}");
    let o = volcast(&["cache", "--cache-dir", &cache]);
    assert!(stdout(&o).contains("(1 entry,"), "{}", stdout(&o));
    // The second open reads the level from the cache: the same image.
    let (second, b) = render("hit.png");
    assert!(second.contains("note: read from the pyramid cache ("), "{second}");
    assert!(a == b, "the cached level renders differently");
    // The file changes (rewritten with the same bytes: its time changes): rebuilt.
    std::thread::sleep(std::time::Duration::from_millis(20));
    std::fs::write(&raw, std::fs::read(&raw).unwrap()).unwrap();
    let (stale, c) = render("stale.png");
    assert!(
        stale.contains("(the file changed since it was made): rebuilt"),
        "{stale}"
    );
    assert!(a == c);
    // A store whose metadata is garbage: rebuilt.
    let store = std::fs::read_dir(dir.join("cache/pyramids"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "zarr"))
        .expect("an entry");
    std::fs::write(store.join("zarr.json"), b"{ not json").unwrap();
    let (corrupt, d) = render("corrupt.png");
    assert!(
        corrupt.contains("is corrupt (") && corrupt.contains("rebuilt"),
        "{corrupt}"
    );
    assert!(a == d);
    let (again, _) = render("again.png");
    assert!(again.contains("read from the pyramid cache"), "{again}");
    // A cache folder that cannot be made (under a file) is a note, not an error.
    let blocked = dir.join("a-file");
    std::fs::write(&blocked, b"x").unwrap();
    let o = volcast(&[
        "info",
        &raw,
        "--host-budget",
        "1M",
        "--cache-dir",
        &blocked.join("cache").to_string_lossy(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("the pyramid cache was not written: cannot make the folder of"),
        "{}",
        stdout(&o)
    );
    // --no-cache neither reads nor writes; `cache --clear` empties it.
    let (none, _) = render_no_cache(&raw, &dir);
    assert!(!none.contains("pyramid cache"), "{none}");
    let o = volcast(&["cache", "--cache-dir", &cache, "--clear"]);
    assert!(stdout(&o).contains("emptied"), "{}", stdout(&o));
    let o = volcast(&["cache", "--cache-dir", &cache]);
    assert!(stdout(&o).contains("(0 entries, 0 MiB)"), "{}", stdout(&o));
}

/// A gzip file over the host budget is decoded once, as a stream, into level 1, and its level 0 is kept in the pyramid
/// cache as it is decoded: level 0's bricks are read from there where the view wants them, so the render equals the
/// full-resolution one. The next open reads both from the cache; a level 0 cut short is rebuilt; without the cache,
/// the note says why the finer levels are not shown.
#[test]
fn a_gzip_file_over_the_host_budget_shows_full_resolution_from_its_kept_level_0() {
    let dir = common::scratch("cli-scale-gzip-level0");
    let raw = write_volume(&dir);
    let gz = dir.join("ball.nrrd");
    common::scratch::gzip_nrrd(Path::new(&raw), [160, 96, 80], "int16", &gz);
    let full = dir.join("full.png");
    volcast_ok(&["render", &raw, "-o", &full.to_string_lossy()]);
    let full = image::open(&full).unwrap().to_rgba8();
    let cache = dir.join("cache").to_string_lossy().into_owned();
    let gz_name = gz.to_string_lossy().into_owned();
    let render = |name: &str, cache_args: &[&str]| {
        let out = dir.join(name).to_string_lossy().into_owned();
        let args = [
            &["render", &gz_name, "--host-budget", "700K"],
            cache_args,
            &["-o", &out],
        ]
        .concat();
        let o = volcast_ok(&args);
        let shot = image::open(dir.join(name)).unwrap().to_rgba8();
        let worst = max_diff(&shot, &full);
        (stderr(&o), worst)
    };
    let (first, worst) = render("first.png", &["--cache-dir", &cache]);
    assert!(first.contains("decoded once, as a stream"), "{first}");
    assert!(
        first.contains("its level 0 (3 MiB) was kept in the pyramid cache (")
            && first.contains("holds level 1 of its 160x96x80 voxels; the finer levels' bricks are read from its level 0 kept in the pyramid cache")
            && first.contains("level 0 in"),
        "{first}"
    );
    assert!(
        worst <= Some(1),
        "full resolution from the kept level 0: differs by {worst:?}"
    );
    let level0 = std::fs::read_dir(dir.join("cache/pyramids"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "level0"))
        .expect("level 0 beside the entry");
    assert_eq!(std::fs::metadata(&level0).unwrap().len(), 160 * 96 * 80 * 2);
    let (hit, worst) = render("hit.png", &["--cache-dir", &cache]);
    assert!(
        hit.contains("read from the pyramid cache")
            && hit.contains("its finer levels are read from its level 0 kept in the pyramid cache")
            && !hit.contains("decoded once"),
        "{hit}"
    );
    assert!(worst <= Some(1), "from the cache: differs by {worst:?}");
    // Cut short (a full disk, another program): never trusted, rebuilt.
    let bytes = std::fs::read(&level0).unwrap();
    std::fs::write(&level0, &bytes[..bytes.len() / 2]).unwrap();
    let (cut, worst) = render("cut.png", &["--cache-dir", &cache]);
    assert!(
        cut.contains("(its level 0 is missing or cut short): rebuilt") && cut.contains("was kept in the pyramid cache"),
        "{cut}"
    );
    assert!(worst <= Some(1), "rebuilt: differs by {worst:?}");
    let (off, worst) = render("off.png", &["--no-cache"]);
    assert!(
        off.contains("its finer levels will not be shown: a decoded file's level 0 is kept in the pyramid cache")
            && off.contains("(--no-cache)"),
        "{off}"
    );
    // Level 1 alone: no bricks of level 0 shown. It stands in for the file with the file's optical depth (rule 6),
    // so its picture differs from the full one only by its coarser grid.
    assert!(!off.contains("level 0 in"), "{off}");
    assert!(worst > Some(0), "level 1 alone is not the full-resolution image");
}

/// A rescaled file (a NIfTI with `scl_slope` 2 and `scl_inter` −1024, as a CT's rescale; gzip with a negative slope)
/// over the host budget, read in place and decoded from gzip: its finer bricks are read as stored, as the held level is, so the render equals
/// the full-resolution one. The level is cached as stored values with the rescale beside them: the next open reads it
/// from the cache with the file's scaled range, and renders the same image. The pool holds every brick of the
/// pyramid (15, in 18 slots: its arrangement's whole rows and layers), so every level-0 brick is shown.
#[test]
fn a_rescaled_file_over_the_host_budget_shows_full_resolution_and_is_cached() {
    let dir = common::scratch("cli-scale-rescaled");
    let raw = write_volume(&dir);
    let json = |o: &std::process::Output| serde_json::from_str::<serde_json::Value>(&stdout(o)).unwrap();
    // The gzip one with a negative slope: the finer bricks' ranges (what can be seen) map with their ends swapped.
    for (name, rescale) in [("ct.nii", (2.0, -1024.0)), ("ct.nii.gz", (-0.5, 3000.0))] {
        let file = dir.join(name);
        common::scratch::nifti(Path::new(&raw), [160, 96, 80], 4, rescale, &file);
        let f = file.to_string_lossy().into_owned();
        let full = dir.join(format!("{name}-full.png"));
        volcast_ok(&["render", &f, "-o", &full.to_string_lossy()]);
        let full = image::open(&full).unwrap().to_rgba8();
        let whole = json(&volcast(&["info", &f, "--json"]));
        let cache = dir.join(format!("{name}-cache")).to_string_lossy().into_owned();
        for open in ["first", "cached"] {
            let out = dir.join(format!("{name}-{open}.png"));
            let budget = ["--host-budget", "700K", "--cache-dir", &cache];
            let o = volcast_ok(&[&["render", &f], &budget[..], &["-o", &out.to_string_lossy()]].concat());
            let err = stderr(&o);
            assert!(
                err.contains("holds level 1 of its 160x96x80 voxels; the finer levels' bricks are read from")
                    && err.contains("a pool of 18 bricks")
                    && err.contains("level 0 in 12 of its 12 level-0 bricks shown"),
                "{name} {open}: {err}"
            );
            assert_eq!(
                err.contains("read from the pyramid cache"),
                open == "cached",
                "{name} {open}: {err}"
            );
            let shot = image::open(&out).unwrap().to_rgba8();
            let worst = max_diff(&shot, &full);
            assert!(worst <= Some(1), "{name} {open}: full resolution differs by {worst:?}");
            let held = json(&volcast(&[&["info", &f], &budget[..], &["--json"]].concat()));
            assert_eq!(held["dims"], serde_json::json!([80, 48, 40]), "{name} {open}");
            assert_eq!(
                held["scaled_range"], whole["scaled_range"],
                "{name} {open}: the file's rescaled range"
            );
        }
    }
}

fn render_no_cache(raw: &str, dir: &Path) -> (String, ()) {
    let out = dir.join("none.png");
    let o = volcast_ok(&[
        "render",
        raw,
        "--gpu-budget",
        "700K",
        "--no-cache",
        "-o",
        &out.to_string_lossy(),
    ]);
    (stderr(&o), ())
}

/// The host budget counts every time step of a 4-D file: series_u8.mha is 7 steps of 6x5x4 uint8 (120 bytes each,
/// 840 in all). Under a budget of 500 bytes one step would fit, but the steps together do not, so it shows pyramid
/// level 1 and says why; under 1000 bytes it shows full resolution.
#[test]
fn the_host_budget_counts_every_time_step() {
    let file = format!("{}/tests/data/time/series_u8.mha", env!("CARGO_MANIFEST_DIR"));
    let info = |budget: &str| {
        let o = common::volcast(&["info", &file, "--host-budget", budget]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        common::stdout(&o)
    };
    let tight = info("500");
    assert!(tight.contains("dims:      3 x 3 x 2"), "{tight}");
    assert!(tight.contains("timesteps: 7"), "{tight}");
    assert!(
        tight.contains("needs 840 bytes of memory and the host budget is 500 bytes"),
        "{tight}"
    );
    let roomy = info("1000");
    assert!(
        roomy.contains("dims:      6 x 5 x 4") && roomy.contains("timesteps: 7"),
        "{roomy}"
    );
}
