//! `volcast info`'s notes, through the binary: each said once, and the GPU-memory line of a volume too large for
//! the faster layouts says what volcast does instead.

use crate::common;

use common::{stderr, stdout, volcast};

/// A DICOM series with uneven slice spacing is resampled, and `info` says so once: the note used to come on stderr
/// from loading and again in the report.
#[test]
fn info_says_the_uneven_spacing_note_once() {
    let series = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/world/dicom_uneven");
    let o = volcast(&["info", series]);
    assert!(o.status.success(), "{}", stderr(&o));
    let all = format!("{}{}", stdout(&o), stderr(&o));
    assert_eq!(all.matches("uneven slice spacing").count(), 1, "{all}");
    assert!(stdout(&o).contains("note:      uneven slice spacing"), "{all}");
    // The JSON carries the note too, and stderr stays quiet.
    let o = volcast(&["info", "--json", series]);
    assert!(!stderr(&o).contains("uneven"), "{}", stderr(&o));
    assert_eq!(stdout(&o).matches("uneven slice spacing").count(), 1);
}

/// A 16-bit volume whose corner texture would pass 1 GiB: the line names the layout volcast takes (R32_SFLOAT), its
/// size, and the limit the corner layout passed, with the size it would have taken.
#[test]
fn info_says_plainly_which_layout_a_large_volume_gets() {
    let dir = common::scratch("cli-info-large");
    // 1024 x 1024 x 129 uint16: 258 MiB on disk, held sparse so the test writes nothing; as corners16 (8 bytes a
    // voxel) 1032 MiB, just over the limit.
    let path = dir.join("large_1024x1024x129_uint16.raw");
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(1024 * 1024 * 129 * 2).unwrap();
    drop(file);
    let o = volcast(&["info", &path.to_string_lossy()]);
    let _ = std::fs::remove_file(&path);
    let text = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    let line = text
        .lines()
        .find(|l| l.contains("on CPU devices"))
        .unwrap_or_else(|| panic!("no CPU-device line in:\n{text}"));
    assert!(
        line.contains("--texture auto: R32_SFLOAT, 516.0 MiB")
            && line.contains("corners16 would take 1032.0 MiB, over the 1 GiB limit"),
        "{line}"
    );
    assert!(!line.contains("while under"), "{line}");
}
