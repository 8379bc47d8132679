//! The pre-parse length walk: every element length in a DICOM file checked against the bytes that follow, before
//! dicom-parser (which allocates by claimed length) sees the data.

use super::codec;
use super::is_dicom;
use crate::formats::format::{clip, header_error};
use crate::volume::VolumeError;
use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry};
use dicom_core::VR;
use dicom_dictionary_std::StandardDataDictionary;
use dicom_object::Tag;

/// Whether explicit-VR data gives this VR a 2-byte length (PS3.5 7.1.2, as dicom-encoding decodes); every other
/// VR, unknown ones included, has 2 reserved bytes and a 4-byte length.
pub(super) fn short_length_vr(vr: [u8; 2]) -> bool {
    matches!(
        &vr,
        b"AE"
            | b"AS"
            | b"AT"
            | b"CS"
            | b"DA"
            | b"DS"
            | b"DT"
            | b"FL"
            | b"FD"
            | b"IS"
            | b"LO"
            | b"LT"
            | b"PN"
            | b"SH"
            | b"SL"
            | b"SS"
            | b"ST"
            | b"TM"
            | b"UI"
            | b"UL"
            | b"US"
    )
}

/// dicom-parser allocates each element by its claimed length, so every length is checked against the bytes that
/// follow before dicom-object sees the data. Walks the file meta group (explicit VR little endian) and the data
/// set in its transfer syntax, descending into sequences and items; returns where parsing should stop: the end of
/// PixelData (bytes after it, such as the junk in one GE slice of the test data, are never parsed) or the end.
pub(super) fn check_lengths(bytes: &[u8], label: &str) -> Result<usize, VolumeError> {
    let (data_set, explicit) = data_set_start(bytes, label)?;
    walk_data_set(bytes, data_set, explicit, label, false)
}

/// Where the data set starts after the file meta group, and whether its VR is explicit.
fn data_set_start(bytes: &[u8], label: &str) -> Result<(usize, bool), VolumeError> {
    let pos = if is_dicom(bytes) {
        132
    } else if bytes.starts_with(b"DICM") {
        4
    } else {
        return Err(header_error(
            label,
            "not a readable DICOM file: no 'DICM' marker at byte 128 (not a DICOM Part 10 file)".into(),
        ));
    };
    let (data_set, transfer_syntax) = walk_meta_group(bytes, pos, label)?;
    Ok((data_set, is_explicit_vr(&transfer_syntax, label)?))
}

/// The top-level PixelData element of a file whose first bytes are `prefix`, every element before it checked as
/// [`check_lengths`] checks them: where its header starts, where its value starts, and its length (`None`:
/// undefined, encapsulated). `Ok(None)` where `prefix` ends before that header (read more of the file); an error
/// where the bytes before it are not a readable DICOM file or run past `prefix`.
pub(super) fn pixel_data_header(prefix: &[u8], label: &str) -> Result<Option<PixelDataAt>, VolumeError> {
    let (data_set, explicit) = data_set_start(prefix, label)?;
    let end = walk_data_set(prefix, data_set, explicit, label, true)?;
    let head = (end + 8 <= prefix.len())
        .then(|| ElementHeader::read(prefix, end, explicit))
        .flatten();
    Ok(head
        .filter(|h| (h.group, h.element) == (0x7FE0, 0x0010))
        .map(|h| PixelDataAt {
            header: end,
            value: end + h.size,
            length: (h.length != u32::MAX).then_some(u64::from(h.length)),
        }))
}

/// Where a top-level PixelData element lies in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PixelDataAt {
    pub header: usize,
    pub value: usize,
    pub length: Option<u64>,
}

fn meta_error(label: &str) -> VolumeError {
    header_error(
        label,
        "not a readable DICOM file: the file meta group is malformed".into(),
    )
}

/// The file meta group, as dicom-object reads it: (0002,0000) gives its length, its elements are explicit VR
/// little endian, and the data set starts right after it in the transfer syntax of (0002,0010). Returns where the
/// data set starts and that transfer syntax (empty if the group has none).
fn walk_meta_group(bytes: &[u8], start: usize, label: &str) -> Result<(usize, String), VolumeError> {
    let mut pos = start;
    if bytes.get(pos..pos + 8) != Some(&[0x02, 0x00, 0x00, 0x00, b'U', b'L', 0x04, 0x00][..]) {
        return Err(meta_error(label));
    }
    let group_length = bytes.get(pos + 8..pos + 12).ok_or_else(|| meta_error(label))?;
    let group_length = u32::from_le_bytes([group_length[0], group_length[1], group_length[2], group_length[3]]);
    // dicom-object reads elements while fewer than `group_length` bytes were read, so the last one may run past
    // the claimed length, and the data set starts where that element ends. Walked the same way here.
    let mut transfer_syntax = String::new();
    pos += 12;
    let mut consumed = 0u64;
    while consumed < u64::from(group_length) {
        let head = bytes.get(pos..pos + 8).ok_or_else(|| meta_error(label))?;
        let (group, element) = (
            u16::from_le_bytes([head[0], head[1]]),
            u16::from_le_bytes([head[2], head[3]]),
        );
        // An item or delimiter inside the meta group's length: dicom-object consumes it as an off-group element,
        // and dicom-parser then read the data set out of step with this walk (a fuzz finding, ending in a value
        // claiming 4 GB). Such a file breaks PS3.10 7.1; it is refused. (Other off-group elements, as a wrong
        // group length produces, are walked as dicom-object reads them.)
        if group == 0xFFFE {
            return Err(header_error(
                label,
                format!(
                    "the file meta group (0002) holds an item or delimiter (FFFE,{element:04X}) within its length: \
                     a malformed file"
                ),
            ));
        }
        let vr = [head[4], head[5]];
        let short = short_length_vr(vr);
        let (length, header) = if short {
            (u32::from(u16::from_le_bytes([head[6], head[7]])), 8)
        } else {
            let l = bytes.get(pos + 8..pos + 12).ok_or_else(|| meta_error(label))?;
            (u32::from_le_bytes([l[0], l[1], l[2], l[3]]), 12)
        };
        let value = pos + header;
        let length = length as usize;
        if length > bytes.len() - value {
            return Err(header_error(
                label,
                format!(
                    "file meta element ({group:04X},{element:04X}) claims {length} bytes but only {} follow",
                    bytes.len() - value
                ),
            ));
        }
        if (group, element) == (0x0002, 0x0010) {
            transfer_syntax = String::from_utf8_lossy(&bytes[value..value + length])
                .trim_end_matches(['\0', ' '])
                .to_string();
        }
        pos = value + length;
        consumed += (header + length) as u64;
    }
    Ok((pos, transfer_syntax))
}

/// Whether the data set in this transfer syntax has explicit VRs; refuses the syntaxes volcast cannot read.
fn is_explicit_vr(transfer_syntax: &str, label: &str) -> Result<bool, VolumeError> {
    match transfer_syntax {
        "1.2.840.10008.1.2" => Ok(false),
        "1.2.840.10008.1.2.1"
        | "1.2.840.10008.1.2.4.50"
        | "1.2.840.10008.1.2.4.70"
        | "1.2.840.10008.1.2.4.90"
        | "1.2.840.10008.1.2.4.91"
        | "1.2.840.10008.1.2.5" => Ok(true),
        // Big endian is retired and rare, deflate needs a codec volcast does not build; both are refused.
        "1.2.840.10008.1.2.2" => Err(header_error(
            label,
            "explicit VR big endian (a retired transfer syntax) is not supported; convert to little endian \
             (e.g. `gdcmconv --explicit`)"
                .into(),
        )),
        other if other.starts_with("1.2.840.10008.1.2.4.") => Ok(true),
        other => Err(header_error(
            label,
            format!(
                "uses {} ({}); volcast cannot decode it",
                codec::name(other),
                clip(other)
            ),
        )),
    }
}

/// The data set's elements in little endian (big endian is refused before the walk), descending into sequences
/// and items; returns where parsing should stop.
///
/// With `until_pixels`, stops at the top-level PixelData element's header and returns where it starts.
fn walk_data_set(
    bytes: &[u8],
    start: usize,
    explicit: bool,
    label: &str,
    until_pixels: bool,
) -> Result<usize, VolumeError> {
    let mut pos = start;
    let mut encapsulated = false;
    // The sequences the walk is inside: where a defined-length one ends, None for an undefined length (ended by
    // its delimiter). An item outside every sequence is refused: dicom-parser reads it otherwise than this walk (a
    // fuzz finding ended in a value claiming 4 GB).
    let mut open: Vec<Option<usize>> = Vec::new();
    while pos + 8 <= bytes.len() {
        while matches!(open.last(), Some(Some(end)) if pos >= *end) {
            open.pop();
        }
        let Some(head) = ElementHeader::read(bytes, pos, explicit) else {
            break;
        };
        let (group, element) = (head.group, head.element);
        if until_pixels && (group, element) == (0x7FE0, 0x0010) && open.is_empty() {
            return Ok(pos);
        }
        pos += head.size;
        head.check_delimiter_length(label)?;
        if head.length == u32::MAX {
            // Undefined length: encapsulated pixel data (its items hold fragments) or, for any other element,
            // a sequence whose items are data sets (dicom-parser discards the VR then): descend.
            if (group, element) == (0x7FE0, 0x0010) {
                encapsulated = true;
            } else if group != 0xFFFE {
                open.push(None);
            }
            continue;
        }
        let length = head.length as usize;
        head.check_value_length(length, bytes.len() - pos, encapsulated, label)?;
        if group == 0xFFFE {
            if element == 0xE0DD {
                if encapsulated {
                    encapsulated = false;
                } else if open.last() == Some(&None) {
                    open.pop();
                }
            }
            if element == 0xE000 && !encapsulated {
                if open.is_empty() {
                    return Err(header_error(
                        label,
                        "an item (FFFE,E000) outside any sequence (corrupt file)".into(),
                    ));
                }
                continue;
            }
        }
        if head.vr.is_some_and(|v| &v == b"SQ") {
            open.push(Some(pos + length));
            continue;
        }
        pos += length;
        if (group, element) == (0x7FE0, 0x0010) && !encapsulated {
            return Ok(pos);
        }
    }
    Ok(bytes.len())
}

/// One data set element's header, read as dicom-parser reads it.
struct ElementHeader {
    group: u16,
    element: u16,
    /// None for items and delimiters, which have no VR.
    vr: Option<[u8; 2]>,
    /// The claimed value length; `u32::MAX` is an undefined length.
    length: u32,
    /// The header's own size in bytes: 8, or 12 for explicit VRs with a 4-byte length.
    size: usize,
}

impl ElementHeader {
    /// The header at `pos`, which has at least 8 bytes after it; None when a 12-byte header runs past the end.
    fn read(bytes: &[u8], pos: usize, explicit: bool) -> Option<Self> {
        let at16 = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
        let at32 = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        let (group, element) = (at16(pos), at16(pos + 2));
        // The VR as dicom-parser resolves it: read from the data in explicit VR (items and delimiters have none);
        // in implicit VR looked up in the standard dictionary (pixel and overlay data are OW, unknown tags UN).
        let vr = if group == 0xFFFE {
            None
        } else if explicit {
            Some([bytes[pos + 4], bytes[pos + 5]])
        } else if (group, element) == (0x7FE0, 0x0010) || (group >> 8 == 0x60 && element == 0x3000) {
            Some(*b"OW")
        } else {
            Some(
                StandardDataDictionary
                    .by_tag(Tag(group, element))
                    .map_or(VR::UN, |entry| entry.vr().relaxed())
                    .to_bytes(),
            )
        };
        let long_vr = explicit && vr.is_some_and(|v| !short_length_vr(v));
        let (length, size) = if long_vr {
            if pos + 12 > bytes.len() {
                return None;
            }
            (at32(pos + 8), 12)
        } else if explicit && vr.is_some() {
            (u32::from(at16(pos + 6)), 8)
        } else {
            (at32(pos + 4), 8)
        };
        Some(Self {
            group,
            element,
            vr,
            length,
            size,
        })
    }

    /// Delimiters (item and sequence delimitation) must have length 0 (PS3.5 7.5). dicom-parser ignores the field
    /// inside a sequence but reads a value of that length at the top level, so no walk can follow both: a non-zero
    /// one is refused (two fuzz findings: a delimiter claiming 47 bytes inside a sequence, one claiming 4 GB
    /// outside).
    fn check_delimiter_length(&self, label: &str) -> Result<(), VolumeError> {
        let (group, element) = (self.group, self.element);
        if group == 0xFFFE && matches!(element, 0xE00D | 0xE0DD) && self.length != 0 {
            return Err(header_error(
                label,
                format!(
                    "a delimiter (FFFE,{element:04X}) has length {}; it must be 0 (corrupt file)",
                    self.length
                ),
            ));
        }
        Ok(())
    }

    /// Refuses a defined `length` that runs past the `available` bytes or that dicom-parser would read
    /// misaligned with this walk.
    fn check_value_length(
        &self,
        length: usize,
        available: usize,
        encapsulated: bool,
        label: &str,
    ) -> Result<(), VolumeError> {
        let (group, element) = (self.group, self.element);
        if length > available && encapsulated && (group, element) == (0xFFFE, 0xE000) {
            return Err(header_error(
                label,
                format!(
                    "a compressed pixel data fragment claims {length} bytes but only {available} follow (truncated \
                     or corrupt file)"
                ),
            ));
        }
        if length > available {
            return Err(header_error(
                label,
                format!(
                    "element ({group:04X},{element:04X}) claims {length} bytes but only {available} follow (truncated or corrupt file)"
                ),
            ));
        }
        // dicom-parser reads binary numbers as whole values (length / size of them), so a length that is not a
        // multiple would leave it misaligned with this walk.
        let value_size = match self.vr.as_ref().map(|v| &v[..]) {
            Some(b"SS" | b"US" | b"OW") => 2,
            Some(b"AT" | b"FL" | b"OF" | b"OL" | b"SL" | b"UL") => 4,
            Some(b"FD" | b"OD" | b"OV" | b"SV" | b"UV") => 8,
            _ => 1,
        };
        if !length.is_multiple_of(value_size) {
            return Err(header_error(
                label,
                format!("element ({group:04X},{element:04X}) has length {length}, not a multiple of {value_size}"),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::from_bytes;
    use super::check_lengths;
    use std::path::Path;

    /// Found by the dicom fuzz target: a file meta element claiming 2.7 GB made dicom-object reserve that much.
    #[test]
    fn lengths_beyond_the_file_are_refused_before_parsing() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-meta.dcm");
        let bytes = std::fs::read(path).unwrap();
        let e = from_bytes(&bytes).unwrap_err().to_string();
        assert!(e.contains("claims") && e.contains("bytes but only"), "{e}");
        // Also found by fuzzing: an unknown VR, which dicom-encoding reads with a 4-byte length.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-unknown-vr.dcm");
        let e = from_bytes(&std::fs::read(path).unwrap()).unwrap_err().to_string();
        assert!(e.contains("claims 4294574080 bytes but only"), "{e}");
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-odd-length.dcm");
        let e = from_bytes(&std::fs::read(path).unwrap()).unwrap_err().to_string();
        assert!(e.contains("(0020,000E) has length 6, not a multiple of 4"), "{e}");
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-big-endian.dcm");
        let e = from_bytes(&std::fs::read(path).unwrap()).unwrap_err().to_string();
        assert!(e.contains("explicit VR big endian"), "{e}");
        let seed = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/slice.dcm")).unwrap();
        assert_eq!(check_lengths(&seed, "x").unwrap(), seed.len());
        let mut junk = seed.clone();
        junk.extend([0x10, 0x00, 0x10, 0x00, b'P', b'N', 0xff, 0xff]);
        assert_eq!(check_lengths(&junk, "x").unwrap(), seed.len());
        assert!(from_bytes(&junk).is_ok());
    }

    /// Fifth dicom fuzz finding: in an implicit-VR data set dicom-parser takes each element's VR from its
    /// dictionary; `check_lengths` once walked such data without VRs, fell out of step with the parser and let it
    /// reserve a claimed 4 GB. The walk now resolves VRs the same way and refuses the file before parsing.
    #[test]
    fn implicit_vr_claim_is_refused_before_parsing() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-implicit-vr.dcm");
        let bytes = std::fs::read(path).unwrap();
        let e = check_lengths(&bytes, "x").unwrap_err().to_string();
        assert!(e.contains("(0000,0000) has length 33, not a multiple of 4"), "{e}");
        assert!(from_bytes(&bytes).is_err());
    }

    /// Sixth finding: dicom-object reads file meta elements while fewer than the group length were read, so the
    /// last one may run past that length and the data set starts after it; the walk had cut the group at its
    /// claimed length and fallen out of step (an OB value of 4 GB followed). It now walks the group the same way.
    #[test]
    fn meta_group_overrun_is_walked_like_dicom_object() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-meta-overrun.dcm");
        let bytes = std::fs::read(path).unwrap();
        let e = check_lengths(&bytes, "x").unwrap_err().to_string();
        assert!(e.contains("claims") && e.contains("bytes but only"), "{e}");
        assert!(from_bytes(&bytes).is_err());
    }

    /// Eighth and ninth findings: delimiters with a non-zero length field. Inside a sequence dicom-parser ignores
    /// it (the walk skipped it, fell out of step and missed a value claiming 4 GB); at the top level it reads a
    /// value that long (4 GB). Both are refused.
    #[test]
    fn delimiters_with_a_length_are_refused() {
        for (file, length) in [
            ("fuzz-dicom-oom-delimiter-length.dcm", "length 47"),
            ("fuzz-dicom-oom-top-level-delimiter.dcm", "length 4143983616"),
        ] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(file);
            let bytes = std::fs::read(path).unwrap();
            let e = check_lengths(&bytes, "x").unwrap_err().to_string();
            assert!(
                e.contains("a delimiter (FFFE,E0DD) has") && e.contains(length),
                "{file}: {e}"
            );
            assert!(from_bytes(&bytes).is_err());
        }
    }

    /// An item at the top level of the data set (outside every sequence) is refused: dicom-parser does not read it
    /// as this walk would.
    #[test]
    fn items_outside_sequences_are_refused() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/u16_native/00.dcm");
        let bytes = std::fs::read(path).unwrap();
        assert!(check_lengths(&bytes, "x").is_ok());
        let group_length = u32::from_le_bytes(bytes[140..144].try_into().unwrap()) as usize;
        let data_set = 144 + group_length;
        let mut hostile = bytes[..data_set].to_vec();
        hostile.extend([0xFE, 0xFF, 0x00, 0xE0, 0, 0, 0, 0]);
        hostile.extend(&bytes[data_set..]);
        let e = check_lengths(&hostile, "x").unwrap_err().to_string();
        assert!(e.contains("an item (FFFE,E000) outside any sequence"), "{e}");
    }

    /// Seventh finding of the dicom fuzz target: the file meta group's length covers an item (FFFE,E000) after its
    /// last element. dicom-object consumed it as an off-group element and then parsed the data set out of step
    /// with this walk, until a value claimed 4 GB (an allocation libFuzzer's 2 GiB limit caught). Refused now.
    #[test]
    fn items_inside_the_meta_group_are_refused() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-dicom-oom-meta-item.dcm");
        let bytes = std::fs::read(path).unwrap();
        let e = check_lengths(&bytes, "x").unwrap_err().to_string();
        assert!(e.contains("holds an item or delimiter (FFFE,E000)"), "{e}");
        assert!(from_bytes(&bytes).is_err());
    }
}
