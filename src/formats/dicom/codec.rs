//! Compressed (encapsulated) DICOM pixel data: which transfer syntaxes volcast decodes, how fragments make frames,
//! and one frame's decoding with its size checked.
//!
//! JPEG (baseline, extended, lossless) and JPEG 2000 go to the decoders dicom-pixeldata uses
//! (`dicom-transfer-syntax-registry`: jpeg-decoder, and jpeg2k over the pure-Rust openjp2), called on one frame
//! volcast assembled. Those adapters write the decoded image into a buffer sized from the DICOM header by the
//! codestream's own dimensions and panic when the two disagree, so the codestream header (JPEG SOF, JPEG 2000
//! SIZ) is checked against Rows, Columns, SamplesPerPixel and BitsAllocated first; that also bounds what the
//! decoder allocates to one frame the header already accounts for. JPEG-LS (lossless and near-lossless) goes to
//! CharLS, the reference JPEG-LS codec (through the `charls` crate, as dicom-rs's own optional adapter does), with
//! its frame header checked the same way first. RLE Lossless (PS3.5 Annex G) is decoded here: the registry's RLE
//! adapter allocates by the segment count it reads and indexes past short segments.

use dicom_encoding::adapters::{PixelDataObject, RawPixelData};
use dicom_encoding::transfer_syntax::TransferSyntaxIndex;
use dicom_encoding::Codec;
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;
use std::borrow::Cow;

/// How a transfer syntax's pixel data is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Native,
    Rle,
    Jpeg,
    Jpeg2000,
    JpegLs,
}

/// Most decoded bytes per compressed byte accepted before the volume is allocated. Lossless codecs give 2–4 on
/// medical images, lossy ones rarely beyond 50; RLE cannot pass 64. Past this a small file claiming a large
/// volume is taken as a decompression bomb.
pub(super) const MAX_RATIO: u64 = 1000;

/// The transfer syntax's name, for messages.
pub(super) fn name(uid: &str) -> &'static str {
    match uid {
        "1.2.840.10008.1.2" => "Implicit VR Little Endian",
        "1.2.840.10008.1.2.1" => "Explicit VR Little Endian",
        "1.2.840.10008.1.2.1.99" => "Deflated Explicit VR Little Endian",
        "1.2.840.10008.1.2.2" => "Explicit VR Big Endian",
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline (Process 1)",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended (Process 2 & 4)",
        "1.2.840.10008.1.2.4.57" => "JPEG Lossless (Process 14)",
        "1.2.840.10008.1.2.4.70" => "JPEG Lossless (Process 14, SV1)",
        "1.2.840.10008.1.2.4.80" => "JPEG-LS Lossless",
        "1.2.840.10008.1.2.4.81" => "JPEG-LS Near-Lossless",
        "1.2.840.10008.1.2.4.90" => "JPEG 2000 Lossless",
        "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.92" => "JPEG 2000 Part 2 Multi-component Lossless",
        "1.2.840.10008.1.2.4.93" => "JPEG 2000 Part 2 Multi-component",
        "1.2.840.10008.1.2.4.94" => "JPIP Referenced",
        "1.2.840.10008.1.2.4.100"
        | "1.2.840.10008.1.2.4.101"
        | "1.2.840.10008.1.2.4.102"
        | "1.2.840.10008.1.2.4.103"
        | "1.2.840.10008.1.2.4.104"
        | "1.2.840.10008.1.2.4.105"
        | "1.2.840.10008.1.2.4.106" => "MPEG video",
        "1.2.840.10008.1.2.4.107" | "1.2.840.10008.1.2.4.108" => "HEVC video",
        "1.2.840.10008.1.2.4.110" | "1.2.840.10008.1.2.4.111" | "1.2.840.10008.1.2.4.112" => "JPEG XL",
        "1.2.840.10008.1.2.4.201" | "1.2.840.10008.1.2.4.202" | "1.2.840.10008.1.2.4.203" => {
            "High-Throughput JPEG 2000"
        }
        _ => "an unknown transfer syntax",
    }
}

/// The codec for `uid`, or why volcast cannot read it (to follow the file's name).
pub(super) fn codec(uid: &str) -> Result<Kind, String> {
    Ok(match uid {
        "1.2.840.10008.1.2" | "1.2.840.10008.1.2.1" => Kind::Native,
        "1.2.840.10008.1.2.5" => Kind::Rle,
        "1.2.840.10008.1.2.4.50" | "1.2.840.10008.1.2.4.51" | "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => {
            Kind::Jpeg
        }
        "1.2.840.10008.1.2.4.90" | "1.2.840.10008.1.2.4.91" => Kind::Jpeg2000,
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => Kind::JpegLs,
        other => {
            return Err(format!(
                "uses {} ({}); volcast cannot decode it (convert it with e.g. `gdcmconv --raw`)",
                name(other),
                crate::formats::format::clip(other)
            ))
        }
    })
}

/// What one frame must decode to.
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameShape {
    pub rows: u16,
    pub columns: u16,
    pub samples: u16,
    pub bits_allocated: u16,
    pub bits_stored: u16,
}

impl FrameShape {
    pub fn bytes(&self) -> usize {
        self.rows as usize * self.columns as usize * self.samples as usize * (self.bits_allocated as usize / 8)
    }
}

/// The byte ranges of each frame's compressed data: one fragment per frame, all fragments for a single frame,
/// or grouped by the Basic Offset Table ([`frame_groups`]).
pub(super) fn frames<'a>(
    fragments: &'a [Vec<u8>],
    offset_table: &[u32],
    frames: u32,
) -> Result<Vec<Cow<'a, [u8]>>, String> {
    let lengths: Vec<u64> = fragments.iter().map(|f| f.len() as u64).collect();
    Ok(frame_groups(&lengths, offset_table, frames)?
        .into_iter()
        .map(|r| match r.len() {
            1 => Cow::Borrowed(&fragments[r.start][..]),
            _ => Cow::Owned(fragments[r].concat()),
        })
        .collect())
}

/// Which fragments (of `lengths` bytes each) make each of `frames` frames: one fragment per frame, every fragment
/// for a single frame, or grouped by the Basic Offset Table (offsets from the first fragment's item, 8-byte item
/// headers included).
pub(super) fn frame_groups(
    lengths: &[u64],
    offset_table: &[u32],
    frames: u32,
) -> Result<Vec<std::ops::Range<usize>>, String> {
    let n = frames as usize;
    if lengths.is_empty() {
        return Err("the encapsulated PixelData holds no fragments".into());
    }
    if lengths.len() == n {
        return Ok((0..n).map(|k| k..k + 1).collect());
    }
    if n == 1 {
        return Ok(std::iter::once(0..lengths.len()).collect());
    }
    if offset_table.len() != n || offset_table[0] != 0 || offset_table.windows(2).any(|w| w[1] <= w[0]) {
        return Err(format!(
            "{} fragments for {n} frames and no usable Basic Offset Table ({} entries) to group them",
            lengths.len(),
            offset_table.len()
        ));
    }
    let starts: Vec<u64> = lengths
        .iter()
        .scan(0u64, |at, &len| {
            let start = *at;
            *at += len + 8;
            Some(start)
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    for (k, &offset) in offset_table.iter().enumerate() {
        let first = starts
            .iter()
            .position(|&s| s == u64::from(offset))
            .ok_or_else(|| format!("the Basic Offset Table entry for frame {k} ({offset}) is not a fragment start"))?;
        let end = offset_table.get(k + 1).map_or(u64::MAX, |&e| u64::from(e));
        let count = starts[first..].iter().take_while(|&&s| s < end).count();
        out.push(first..first + count);
    }
    Ok(out)
}

/// Checks a JPEG frame's SOF header (the first start-of-frame marker) against `shape`.
fn check_jpeg(data: &[u8], shape: &FrameShape) -> Result<(), String> {
    if !data.starts_with(&[0xFF, 0xD8]) {
        return Err("a JPEG frame does not start with an SOI marker".into());
    }
    let mut pos = 2;
    loop {
        // Skip fill bytes to the next marker.
        while data.get(pos) == Some(&0xFF) && data.get(pos + 1) == Some(&0xFF) {
            pos += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (data.get(pos), data.get(pos + 1)) else {
            return Err("a JPEG frame has no frame header (SOF) before its data".into());
        };
        let len = data
            .get(pos + 2..pos + 4)
            .map(|b| u16::from_be_bytes([b[0], b[1]]) as usize)
            .ok_or("a JPEG frame ends inside a marker segment")?;
        let sof = matches!(marker, 0xC0..=0xCF) && !matches!(marker, 0xC4 | 0xC8 | 0xCC);
        if sof {
            let seg = data
                .get(pos + 4..pos + 2 + len)
                .filter(|s| s.len() >= 6)
                .ok_or("a JPEG frame header is cut short")?;
            let precision = seg[0];
            let height = u16::from_be_bytes([seg[1], seg[2]]);
            let width = u16::from_be_bytes([seg[3], seg[4]]);
            let components = seg[5];
            if (width, height, u16::from(components)) != (shape.columns, shape.rows, shape.samples) {
                return Err(format!(
                    "a JPEG frame header says {width}x{height} with {components} component(s), the DICOM header \
                     {}x{} with {}",
                    shape.columns, shape.rows, shape.samples
                ));
            }
            let bytes = if precision > 8 { 16 } else { 8 };
            if bytes != shape.bits_allocated || precision == 0 || precision > 16 {
                return Err(format!(
                    "a JPEG frame has {precision}-bit samples but BitsAllocated is {}",
                    shape.bits_allocated
                ));
            }
            return Ok(());
        }
        if marker == 0xDA || marker == 0xD9 || len < 2 {
            return Err("a JPEG frame has no frame header (SOF) before its data".into());
        }
        pos += 2 + len;
    }
}

/// Checks a JPEG 2000 frame's SIZ header (raw codestream, or the `jp2c` box of a JP2 file) against `shape`.
fn check_j2k(data: &[u8], shape: &FrameShape) -> Result<(), String> {
    let start = if data.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]) {
        0
    } else {
        // JP2: the codestream follows the jp2c box header; look for SOC+SIZ near the start.
        data.windows(4)
            .take(4096)
            .position(|w| w == [0xFF, 0x4F, 0xFF, 0x51])
            .ok_or("a JPEG 2000 frame has no codestream header (SOC, SIZ)")?
    };
    let siz = data.get(start + 4..).ok_or("a JPEG 2000 frame is cut short")?;
    let be32 = |i: usize| siz.get(i..i + 4).map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
    let be16 = |i: usize| siz.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    let short = || "a JPEG 2000 frame header (SIZ) is cut short".to_string();
    // Lsiz, Rsiz, Xsiz, Ysiz, XOsiz, YOsiz, XTsiz, YTsiz, XTOsiz, YTOsiz, Csiz, then Ssiz XRsiz YRsiz per component.
    let (x, y, xo, yo) = (
        be32(4).ok_or_else(short)?,
        be32(8).ok_or_else(short)?,
        be32(12).ok_or_else(short)?,
        be32(16).ok_or_else(short)?,
    );
    let (xt, yt) = (be32(20).ok_or_else(short)?, be32(24).ok_or_else(short)?);
    let components = be16(36).ok_or_else(short)?;
    let (width, height) = (x.saturating_sub(xo), y.saturating_sub(yo));
    if (width, height, components) != (u32::from(shape.columns), u32::from(shape.rows), shape.samples) {
        return Err(format!(
            "a JPEG 2000 frame header says {width}x{height} with {components} component(s), the DICOM header {}x{} \
             with {}",
            shape.columns, shape.rows, shape.samples
        ));
    }
    if xt == 0 || yt == 0 {
        return Err("a JPEG 2000 frame header has a zero tile size".into());
    }
    for c in 0..usize::from(components) {
        let ssiz = *siz.get(38 + 3 * c).ok_or_else(short)?;
        let (xr, yr) = (
            *siz.get(39 + 3 * c).ok_or_else(short)?,
            *siz.get(40 + 3 * c).ok_or_else(short)?,
        );
        let precision = (ssiz & 0x7F) + 1;
        if u16::from(precision) > shape.bits_allocated || (xr, yr) != (1, 1) {
            return Err(format!(
                "a JPEG 2000 frame component has {precision}-bit samples subsampled {xr}x{yr}; BitsAllocated is {} \
                 and volcast needs full resolution",
                shape.bits_allocated
            ));
        }
    }
    Ok(())
}

/// Decodes one JPEG-LS frame with CharLS after checking its frame header (SOF-55) against `shape`. CharLS writes
/// 2-16-bit samples as one or two bytes in native (little-endian here) order, components interleaved by pixel.
fn decode_jpeg_ls(data: &[u8], shape: &FrameShape) -> Result<Vec<u8>, String> {
    let info = charls::CharLS::default()
        .get_frame_info(data)
        .map_err(|e| format!("a JPEG-LS frame header cannot be read: {e}"))?;
    let components = u16::try_from(info.component_count).unwrap_or(0);
    if (info.width, info.height, components) != (u32::from(shape.columns), u32::from(shape.rows), shape.samples) {
        return Err(format!(
            "a JPEG-LS frame header says {}x{} with {} component(s), the DICOM header {}x{} with {}",
            info.width, info.height, info.component_count, shape.columns, shape.rows, shape.samples
        ));
    }
    let bytes = if info.bits_per_sample > 8 { 16 } else { 8 };
    if !(2..=16).contains(&info.bits_per_sample) || bytes != shape.bits_allocated {
        return Err(format!(
            "a JPEG-LS frame has {}-bit samples but BitsAllocated is {}",
            info.bits_per_sample, shape.bits_allocated
        ));
    }
    charls::CharLS::default()
        .decode(data)
        .map_err(|e| format!("JPEG-LS decoder (CharLS): {e}"))
}

/// Decodes one RLE Lossless frame (PS3.5 Annex G) to little-endian samples, pixel-interleaved.
fn decode_rle(data: &[u8], shape: &FrameShape) -> Result<Vec<u8>, String> {
    let bytes_per_sample = usize::from(shape.bits_allocated / 8);
    let segments = usize::from(shape.samples) * bytes_per_sample;
    let header = data
        .get(..64)
        .ok_or("an RLE frame is shorter than its 64-byte header")?;
    let word = |i: usize| u32::from_le_bytes([header[4 * i], header[4 * i + 1], header[4 * i + 2], header[4 * i + 3]]);
    if word(0) as usize != segments {
        return Err(format!(
            "an RLE frame has {} segments; {segments} expected for {} sample(s) of {} bits",
            word(0),
            shape.samples,
            shape.bits_allocated
        ));
    }
    let pixels = usize::from(shape.rows) * usize::from(shape.columns);
    let mut out = vec![0u8; pixels * segments];
    for s in 0..segments {
        let start = word(1 + s) as usize;
        let end = if s + 1 < segments {
            word(2 + s) as usize
        } else {
            data.len()
        };
        let segment = data
            .get(start..end)
            .filter(|_| start >= 64)
            .ok_or_else(|| format!("RLE segment {s} has offsets {start}..{end} outside the frame"))?;
        // Segment s holds byte (bytes_per_sample - 1 - s % bytes_per_sample) of sample s / bytes_per_sample,
        // most significant first.
        let sample = s / bytes_per_sample;
        let byte = bytes_per_sample - 1 - s % bytes_per_sample;
        let stride = segments;
        let mut dst = sample * bytes_per_sample + byte;
        let mut written = 0;
        let mut i = 0;
        let mut put = |b: u8, written: &mut usize| {
            if *written < pixels {
                out[dst] = b;
                dst += stride;
                *written += 1;
            }
        };
        while written < pixels && i < segment.len() {
            let n = segment[i] as i8;
            i += 1;
            if n >= 0 {
                let run = segment
                    .get(i..i + n as usize + 1)
                    .ok_or_else(|| format!("RLE segment {s} ends inside a literal run (truncated frame?)"))?;
                for &b in run {
                    put(b, &mut written);
                }
                i += n as usize + 1;
            } else if n != -128 {
                let b = *segment
                    .get(i)
                    .ok_or_else(|| format!("RLE segment {s} ends inside a repeat run"))?;
                for _ in 0..(1 - isize::from(n)) {
                    put(b, &mut written);
                }
                i += 1;
            }
        }
        if written < pixels {
            return Err(format!(
                "RLE segment {s} decodes to {written} bytes, the frame needs {pixels} (truncated frame?)"
            ));
        }
    }
    Ok(out)
}

/// One frame as the registry's decoders see a DICOM object.
struct OneFrame<'a> {
    uid: &'a str,
    shape: FrameShape,
    data: &'a [u8],
}

impl PixelDataObject for OneFrame<'_> {
    fn transfer_syntax_uid(&self) -> &str {
        self.uid
    }
    fn rows(&self) -> Option<u16> {
        Some(self.shape.rows)
    }
    fn cols(&self) -> Option<u16> {
        Some(self.shape.columns)
    }
    fn samples_per_pixel(&self) -> Option<u16> {
        Some(self.shape.samples)
    }
    fn bits_allocated(&self) -> Option<u16> {
        Some(self.shape.bits_allocated)
    }
    fn bits_stored(&self) -> Option<u16> {
        Some(self.shape.bits_stored)
    }
    fn photometric_interpretation(&self) -> Option<&str> {
        Some("MONOCHROME2")
    }
    fn number_of_frames(&self) -> Option<u32> {
        Some(1)
    }
    fn number_of_fragments(&self) -> Option<u32> {
        Some(1)
    }
    fn fragment(&self, fragment: usize) -> Option<Cow<'_, [u8]>> {
        (fragment == 0).then_some(Cow::Borrowed(self.data))
    }
    fn offset_table(&self) -> Option<Cow<'_, [u32]>> {
        None
    }
    fn raw_pixel_data(&self) -> Option<RawPixelData> {
        Some(RawPixelData {
            fragments: std::iter::once(self.data.to_vec()).collect(),
            offset_table: Default::default(),
        })
    }
}

/// Decodes one frame to exactly `shape.bytes()` little-endian bytes, or says why not.
pub(super) fn decode(codec: Kind, uid: &str, data: &[u8], shape: &FrameShape) -> Result<Vec<u8>, String> {
    let out = match codec {
        Kind::Native => return Err("native pixel data is not decoded".into()),
        Kind::Rle => decode_rle(data, shape)?,
        Kind::JpegLs => decode_jpeg_ls(data, shape)?,
        Kind::Jpeg | Kind::Jpeg2000 => {
            if codec == Kind::Jpeg {
                check_jpeg(data, shape)?;
            } else {
                check_j2k(data, shape)?;
            }
            let ts = TransferSyntaxRegistry
                .get(uid)
                .ok_or_else(|| format!("no decoder for {} ({uid})", name(uid)))?;
            let Codec::EncapsulatedPixelData(Some(decoder), _) = ts.codec() else {
                return Err(format!("no decoder for {} ({uid}) in this build", name(uid)));
            };
            let mut out = Vec::new();
            // The header checks above keep the adapters off their known panics; a decoder panic on some other
            // malformed frame still becomes this file's error instead of ending the program. (Fuzzing sees it
            // anyway: libFuzzer's panic hook aborts before unwinding.)
            let frame = OneFrame {
                uid,
                shape: *shape,
                data,
            };
            let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                decoder.decode_frame(&frame, 0, &mut out)
            }));
            match decoded {
                Ok(Ok(())) => {}
                Ok(Err(e)) => return Err(format!("{} decoder: {e}", name(uid))),
                Err(_) => {
                    return Err(format!(
                        "the {} decoder failed on this frame (malformed data)",
                        name(uid)
                    ))
                }
            }
            out
        }
    };
    if out.len() != shape.bytes() {
        return Err(format!(
            "a frame decoded to {} bytes; {}x{}x{} samples of {} bits need {}",
            out.len(),
            shape.columns,
            shape.rows,
            shape.samples,
            shape.bits_allocated,
            shape.bytes()
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::frame_groups;

    #[test]
    fn fragments_group_into_frames_as_the_offset_table_says() {
        // One fragment per frame; all fragments for one frame.
        assert_eq!(frame_groups(&[5, 6, 7], &[], 3).unwrap(), vec![0..1, 1..2, 2..3]);
        assert_eq!(
            frame_groups(&[5, 6, 7], &[], 1).unwrap(),
            std::iter::once(0..3).collect::<Vec<_>>()
        );
        // Two frames in four fragments: the table counts each fragment's 8-byte item header.
        let lengths = [10, 20, 30, 40];
        assert_eq!(frame_groups(&lengths, &[0, 46], 2).unwrap(), vec![0..2, 2..4]);
        assert_eq!(frame_groups(&lengths, &[0, 84], 2).unwrap(), vec![0..3, 3..4]);
        let e = frame_groups(&lengths, &[0, 45], 2).unwrap_err();
        assert!(e.contains("is not a fragment start"), "{e}");
        let e = frame_groups(&lengths, &[], 2).unwrap_err();
        assert!(e.contains("no usable Basic Offset Table"), "{e}");
    }
}
