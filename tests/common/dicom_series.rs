//! DICOM folders made at run time through dicom-object, the reader volcast itself uses: one holding several series,
//! from the shared MRI series (`native/brain_pd_mr`), slices copied and some rewritten with another
//! SeriesInstanceUID, SeriesNumber and SeriesDescription; and one large series, from pydicom's `u8_native`.

use dicom_core::{DataElement, PrimitiveValue, Tag, VR};
use std::path::{Path, PathBuf};

/// One series of the made folder.
pub struct MadeSeries {
    pub number: i64,
    pub uid: &'static str,
    pub description: &'static str,
    /// Which of the shared slices (brain_001.dcm is 1) it holds.
    pub slices: std::ops::RangeInclusive<u32>,
}

/// The folder's series: the largest (6 slices) is neither the first by number nor by file name.
pub const SERIES: [MadeSeries; 3] = [
    MadeSeries {
        number: 901,
        uid: "1.2.826.0.1.3680043.10.999.901",
        description: "volcast test first",
        slices: 1..=4,
    },
    MadeSeries {
        number: 902,
        uid: "1.2.826.0.1.3680043.10.999.902",
        description: "volcast test largest",
        slices: 5..=10,
    },
    MadeSeries {
        number: 903,
        uid: "1.2.826.0.1.3680043.10.999.903",
        // As long as a DICOM LO may be (64): the panel must cut it short, not widen.
        description: "volcast test small, T2 FLAIR axial 3 mm post-contrast, corrected",
        slices: 11..=12,
    },
];

/// Writes the three series of [`SERIES`] into `dir` (made if missing); `None` without the shared data.
pub fn make(dir: &Path) -> Option<PathBuf> {
    let source = super::shared_data("native/brain_pd_mr")?;
    std::fs::create_dir_all(dir).unwrap();
    for series in &SERIES {
        for i in series.slices.clone() {
            let from = source.join(format!("brain_{i:03}.dcm"));
            let bytes = std::fs::read(&from).unwrap_or_else(|e| panic!("{}: {e}", from.display()));
            // The shared files carry ~2.5 MB after their pixel data, which dicom-object will not parse past.
            let end = end_of_pixel_data(&bytes);
            let mut obj = dicom_object::OpenFileOptions::new()
                .from_reader(&bytes[..end])
                .unwrap_or_else(|e| panic!("{}: {e}", from.display()));
            obj.put(DataElement::new(
                Tag(0x0020, 0x000E),
                VR::UI,
                PrimitiveValue::from(series.uid),
            ));
            obj.put(DataElement::new(
                Tag(0x0020, 0x0011),
                VR::IS,
                PrimitiveValue::from(series.number.to_string()),
            ));
            obj.put(DataElement::new(
                Tag(0x0008, 0x103E),
                VR::LO,
                PrimitiveValue::from(series.description),
            ));
            let to = dir.join(format!("slice_{i:03}.dcm"));
            obj.write_to_file(&to)
                .unwrap_or_else(|e| panic!("{}: {e}", to.display()));
        }
    }
    Some(dir.to_path_buf())
}

/// A series of `n` slices of `w`×`h` uint8 voxels, `(x + 2y + 3z) mod 251`, 1.5 mm apart, written into `dir` as
/// pydicom wrote `tests/data/dicom/u8_native` (its first file with another size, place and pixels), each file's
/// name shuffled from its place.
pub fn large(dir: &Path, [w, h, n]: [u32; 3]) -> PathBuf {
    let template = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/u8_native/00.dcm");
    let mut obj = dicom_object::open_file(&template).unwrap_or_else(|e| panic!("{}: {e}", template.display()));
    obj.put(DataElement::new(
        Tag(0x0028, 0x0010),
        VR::US,
        PrimitiveValue::from(h as u16),
    ));
    obj.put(DataElement::new(
        Tag(0x0028, 0x0011),
        VR::US,
        PrimitiveValue::from(w as u16),
    ));
    std::fs::create_dir_all(dir).unwrap();
    for z in 0..n {
        let pixels: Vec<u8> = (0..h)
            .flat_map(|y| (0..w).map(move |x| ((x + 2 * y + 3 * z) % 251) as u8))
            .collect();
        obj.put(DataElement::new(
            Tag(0x7FE0, 0x0010),
            VR::OB,
            PrimitiveValue::from(pixels),
        ));
        let position = format!("5.0\\-7.0\\{:.1}", 1.5 * f64::from(z));
        obj.put(DataElement::new(
            Tag(0x0020, 0x0032),
            VR::DS,
            PrimitiveValue::from(position),
        ));
        let to = dir.join(format!("{:04}.dcm", (z * 97) % n));
        obj.write_to_file(&to)
            .unwrap_or_else(|e| panic!("{}: {e}", to.display()));
    }
    dir.to_path_buf()
}

/// Where an explicit-VR little-endian file's PixelData element ends (elements of defined length only, as in the
/// shared series).
fn end_of_pixel_data(bytes: &[u8]) -> usize {
    let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
    let u32_at = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let mut i = 132;
    while i + 8 <= bytes.len() {
        let (group, element) = (u16_at(i), u16_at(i + 2));
        let long = matches!(
            &bytes[i + 4..i + 6],
            b"OB" | b"OW" | b"OF" | b"SQ" | b"UN" | b"UT" | b"UC" | b"UR"
        );
        let (header, length) = if long {
            (12, u32_at(i + 8))
        } else {
            (8, u32::from(u16_at(i + 6)))
        };
        assert_ne!(
            length,
            u32::MAX,
            "an element of undefined length at ({group:04X},{element:04X})"
        );
        i += header + length as usize;
        if (group, element) == (0x7FE0, 0x0010) {
            return i;
        }
    }
    panic!("no PixelData element");
}
