//! The bytes of one `.vti` DataArray: ascii text, or a binary stream (raw or base64) holding a header and the data,
//! uncompressed or in independently compressed blocks, as vtkXMLWriter writes them:
//! - uncompressed: one header word (the data's byte count), then the data;
//! - compressed: `[nblocks, block size, last block size (0: full), compressed size of each block]`, then the
//!   blocks. In base64 the header is encoded on its own and the blocks after it (uncompressed: header and data in
//!   one encoding).
//!
//! Every size in a header must agree with the extent × type before anything is allocated, and inflation stops at
//! the size the extent needs, so a small file cannot claim (or inflate to) more than it holds.

use crate::formats::decode::{self, DecodeError, Endian, Progress};
use crate::formats::format::header_error;
use crate::volume::{VolumeError, VoxelData, VoxelType};
use base64::Engine;
use std::io::{Read, Write};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compressor {
    Zlib,
    Lz4,
    Lzma,
}

impl Compressor {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Compressor::Zlib => "zlib",
            Compressor::Lz4 => "lz4",
            Compressor::Lzma => "lzma",
        }
    }

    /// Most output a block of `compressed` bytes can honestly produce: deflate ~1032:1, LZ4 ~255:1 (a 255-byte
    /// length extension per byte); xz reaches several thousand to one on constant data, so its bound is loose and
    /// only stops absurd claims.
    pub(crate) fn max_output(self, compressed: u64) -> u64 {
        let ratio = match self {
            Compressor::Zlib => 1032,
            Compressor::Lz4 => 256,
            Compressor::Lzma => 1 << 16,
        };
        compressed.saturating_mul(ratio).saturating_add(1024)
    }
}

/// What the array must hold and how its binary stream is laid out.
pub(crate) struct Layout<'a> {
    pub file: &'a str,
    /// Bytes per header word: 4 (UInt32) or 8 (UInt64).
    pub word: usize,
    pub endian: Endian,
    pub compressor: Option<Compressor>,
    pub voxel_type: VoxelType,
    pub dims: [u32; 3],
    /// Voxels, already within the dimension limits.
    pub count: u64,
}

/// Where the array's values are.
pub(crate) enum Location<'a> {
    Ascii(&'a [u8]),
    /// Base64 text from the array's start (inline: the element's text; appended: from its offset).
    Base64(&'a [u8]),
    /// Raw bytes from the array's offset to the end of the file.
    Raw(&'a [u8]),
}

impl Layout<'_> {
    fn err(&self, problem: String) -> VolumeError {
        header_error(self.file, problem)
    }

    /// Bytes of data the extent and type need.
    fn expected(&self) -> u64 {
        self.count * self.voxel_type.size() as u64
    }

    fn words(&self, bytes: &[u8]) -> Vec<u64> {
        bytes
            .chunks_exact(self.word)
            .map(|w| {
                let mut b = [0u8; 8];
                if self.endian == Endian::Little {
                    b[..self.word].copy_from_slice(w);
                    u64::from_le_bytes(b)
                } else {
                    b[8 - self.word..].copy_from_slice(w);
                    u64::from_be_bytes(b)
                }
            })
            .collect()
    }

    fn truncated(&self, what: &str, needed: u64, available: u64) -> VolumeError {
        self.err(format!(
            "the {what} needs {needed} bytes but only {available} remain (truncated file or wrong offset?)"
        ))
    }

    /// The data size an uncompressed header claims must be what the extent needs.
    fn check_size(&self, claimed: u64) -> Result<usize, VolumeError> {
        let expected = self.expected();
        if claimed != expected {
            return Err(self.err(format!(
                "the array header says {claimed} bytes but {}x{}x{} {} needs {expected}",
                self.dims[0], self.dims[1], self.dims[2], self.voxel_type
            )));
        }
        usize::try_from(expected).map_err(|_| VolumeError::TooLarge {
            dims: self.dims,
            voxel_type: self.voxel_type,
            bytes: expected,
        })
    }

    /// Checks `[nblocks, block size, last size]` against the extent and against `room`, the most block sizes the
    /// bytes after it could hold; returns the uncompressed size of each block.
    fn blocks(&self, h: &[u64], room: usize) -> Result<Vec<usize>, VolumeError> {
        let (n, size, last) = (h[0], h[1], h[2]);
        let expected = self.expected();
        let bad = |why: &str| {
            self.err(format!(
                "the compression header (blocks {n}, block size {size}, last block {last}) {why}; {}x{}x{} {} needs \
                 {expected} bytes",
                self.dims[0], self.dims[1], self.dims[2], self.voxel_type
            ))
        };
        if n == 0 {
            return if expected == 0 {
                Ok(Vec::new())
            } else {
                Err(bad("has no blocks"))
            };
        }
        if size == 0 || last > size {
            return Err(bad("is inconsistent"));
        }
        let last_size = if last == 0 { size } else { last };
        let total = (n - 1).checked_mul(size).and_then(|t| t.checked_add(last_size));
        if total != Some(expected) {
            return Err(bad("does not add up to the array's size"));
        }
        if n > room as u64 {
            return Err(self.truncated(
                "compression header",
                n.saturating_mul(self.word as u64),
                (room * self.word) as u64,
            ));
        }
        let to_usize = |v: u64| usize::try_from(v).map_err(|_| bad("is too large for this machine"));
        let mut sizes = vec![to_usize(size)?; to_usize(n)?];
        if let Some(l) = sizes.last_mut() {
            *l = to_usize(last_size)?;
        }
        Ok(sizes)
    }
}

/// Decodes base64 text, whitespace ignored; `=` padding may end it.
fn base64(layout: &Layout, text: &[u8]) -> Result<Vec<u8>, VolumeError> {
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent)
            .with_decode_allow_trailing_bits(true),
    );
    engine
        .decode(text)
        .map_err(|e| layout.err(format!("the base64 data are invalid: {e}")))
}

/// The first `chars` base64 characters of `text` (whitespace skipped), or an error if it has fewer.
fn take_chars<'t>(
    layout: &Layout,
    text: &'t [u8],
    chars: usize,
    what: &str,
) -> Result<(&'t [u8], &'t [u8]), VolumeError> {
    if text.len() < chars {
        return Err(layout.err(format!(
            "the base64 {what} needs {chars} characters but only {} remain (truncated file?)",
            text.len()
        )));
    }
    Ok(text.split_at(chars))
}

/// Decodes `text`, which must give at least `n` bytes.
fn base64_at_least(layout: &Layout, text: &[u8], n: usize, what: &str) -> Result<Vec<u8>, VolumeError> {
    let decoded = base64(layout, text)?;
    if decoded.len() < n {
        return Err(layout.truncated(what, n as u64, decoded.len() as u64));
    }
    Ok(decoded)
}

fn encoded_len(bytes: usize) -> usize {
    bytes.div_ceil(3).saturating_mul(4)
}

/// The raw little- or big-endian bytes of the array.
fn binary<'b>(layout: &Layout, location: Location<'b>) -> Result<std::borrow::Cow<'b, [u8]>, VolumeError> {
    let w = layout.word;
    match location {
        Location::Ascii(_) => unreachable!("ascii arrays are not binary"),
        Location::Raw(bytes) => {
            if bytes.len() < w {
                return Err(layout.truncated("array header", w as u64, bytes.len() as u64));
            }
            let Some(compressor) = layout.compressor else {
                let size = layout.check_size(layout.words(&bytes[..w])[0])?;
                let data = &bytes[w..];
                if data.len() < size {
                    return Err(layout.truncated("array", size as u64, data.len() as u64));
                }
                return Ok(std::borrow::Cow::Borrowed(&data[..size]));
            };
            if bytes.len() < 3 * w {
                return Err(layout.truncated("compression header", 3 * w as u64, bytes.len() as u64));
            }
            let sizes = layout.blocks(&layout.words(&bytes[..3 * w]), (bytes.len() - 3 * w) / w)?;
            let header = (3 + sizes.len()) * w;
            if bytes.len() < header {
                return Err(layout.truncated("compression header", header as u64, bytes.len() as u64));
            }
            let compressed = layout.words(&bytes[3 * w..header]);
            inflate(layout, compressor, &sizes, &compressed, &bytes[header..]).map(std::borrow::Cow::Owned)
        }
        Location::Base64(text) => {
            let text: Vec<u8> = text.iter().copied().filter(|b| !b.is_ascii_whitespace()).collect();
            let Some(compressor) = layout.compressor else {
                let (first, _) = take_chars(layout, &text, encoded_len(w), "array header")?;
                let size =
                    layout.check_size(layout.words(&base64_at_least(layout, first, w, "array header")?[..w])[0])?;
                let (all, _) = take_chars(layout, &text, encoded_len(w + size), "array")?;
                let mut decoded = base64_at_least(layout, all, w + size, "array")?;
                decoded.truncate(w + size);
                decoded.drain(..w);
                return Ok(std::borrow::Cow::Owned(decoded));
            };
            let (first, _) = take_chars(layout, &text, encoded_len(3 * w), "compression header")?;
            let first = base64_at_least(layout, first, 3 * w, "compression header")?;
            let sizes = layout.blocks(&layout.words(&first[..3 * w]), text.len() / 4 * 3 / w)?;
            let header = (3 + sizes.len()) * w;
            let (head, rest) = take_chars(layout, &text, encoded_len(header), "compression header")?;
            let head = base64_at_least(layout, head, header, "compression header")?;
            let compressed = layout.words(&head[3 * w..header]);
            let total = compressed.iter().fold(0u64, |a, &c| a.saturating_add(c));
            let chars = usize::try_from(total).map_or(usize::MAX, encoded_len);
            let (blocks, _) = take_chars(layout, rest, chars, "compressed blocks")?;
            let blocks = base64_at_least(
                layout,
                blocks,
                usize::try_from(total).unwrap_or(usize::MAX),
                "compressed blocks",
            )?;
            inflate(layout, compressor, &sizes, &compressed, &blocks).map(std::borrow::Cow::Owned)
        }
    }
}

/// A writer that refuses to grow past `limit` bytes: inflation stops at what the block header promised.
struct Capped<'v> {
    out: &'v mut Vec<u8>,
    limit: usize,
}

impl Write for Capped<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.out.len() + buf.len() > self.limit {
            return Err(std::io::Error::other("the block inflates to more than its header says"));
        }
        self.out.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Decompresses each block into exactly its size; the output grows only with what was actually inflated.
fn inflate(
    layout: &Layout,
    compressor: Compressor,
    sizes: &[usize],
    compressed: &[u64],
    data: &[u8],
) -> Result<Vec<u8>, VolumeError> {
    let total = compressed.iter().fold(0u64, |a, &c| a.saturating_add(c));
    if total > data.len() as u64 {
        return Err(layout.truncated("compressed blocks", total, data.len() as u64));
    }
    let mut out = Vec::new();
    let mut at = 0usize;
    for (i, (&size, &csize)) in sizes.iter().zip(compressed).enumerate() {
        let csize = csize as usize;
        let input = &data[at..at + csize];
        at += csize;
        if size as u64 > compressor.max_output(csize as u64) {
            return Err(layout.err(format!(
                "{} block {i} of {csize} bytes claims to inflate to {size} bytes, more than {} can produce",
                compressor.name(),
                compressor.name()
            )));
        }
        let start = out.len();
        let corrupt = |e: String| layout.err(format!("{} block {i} is corrupt: {e}", compressor.name()));
        out.try_reserve_exact(size).map_err(|_| VolumeError::OutOfMemory {
            dims: layout.dims,
            bytes: layout.expected(),
        })?;
        decode_block(compressor, size, input, &mut out).map_err(corrupt)?;
        let got = out.len() - start;
        if got > size {
            return Err(layout.err(format!(
                "{} block {i} inflates to more than the {size} bytes its header says",
                compressor.name()
            )));
        }
        if got < size {
            return Err(layout.err(format!(
                "{} block {i} inflates to {got} bytes, not the {size} its header says",
                compressor.name()
            )));
        }
    }
    Ok(out)
}

/// Decodes one block of `input` that the header says holds `size` bytes, appending to `out`; stops one byte past
/// `size` (the caller checks the count).
fn decode_block(compressor: Compressor, size: usize, input: &[u8], out: &mut Vec<u8>) -> Result<(), String> {
    let start = out.len();
    match compressor {
        Compressor::Zlib => {
            // One byte past the size shows a stream that holds more than its header says.
            flate2::read::ZlibDecoder::new(input)
                .take(size as u64 + 1)
                .read_to_end(out)
                .map_err(|e| e.to_string())?;
        }
        Compressor::Lz4 => {
            out.resize(start + size, 0);
            let n = lz4_flex::block::decompress_into(input, &mut out[start..]).map_err(|e| e.to_string())?;
            out.truncate(start + n);
        }
        Compressor::Lzma => {
            let mut reader = input;
            let limit = start + size;
            lzma_rs::xz_decompress(&mut reader, &mut Capped { out, limit }).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// One block of `size` bytes decoded from `input` into `out` (cleared first): exactly `size` bytes, or why not.
pub(crate) fn inflate_block(
    compressor: Compressor,
    size: usize,
    input: &[u8],
    out: &mut Vec<u8>,
) -> Result<(), String> {
    out.clear();
    if size as u64 > compressor.max_output(input.len() as u64) {
        return Err(format!(
            "it claims {size} bytes, more than {} bytes can produce",
            input.len()
        ));
    }
    decode_block(compressor, size, input, out)?;
    match out.len() {
        n if n == size => Ok(()),
        n if n > size => Err(format!("it inflates to more than the {size} bytes its header says")),
        n => Err(format!("it inflates to {n} bytes, not the {size} its header says")),
    }
}

/// The array's voxels.
pub(crate) fn decode(layout: &Layout, location: Location, progress: &mut Progress) -> Result<VoxelData, VolumeError> {
    let count = layout.count as usize;
    let t = layout.voxel_type;
    let result = match location {
        Location::Ascii(text) => {
            if layout.count > text.len() as u64 / 2 + 1 {
                return Err(layout.err(format!("{} bytes of ASCII data cannot hold {count} values", text.len())));
            }
            let mut reader = text;
            decode::read_ascii(&mut reader, t, count, progress)
        }
        binary_location => {
            let bytes = binary(layout, binary_location)?;
            let mut reader: &[u8] = &bytes;
            decode::read_binary(&mut reader, t, layout.endian, count, decode::CHUNK_BYTES, progress)
        }
    };
    result.map_err(|e| match e {
        DecodeError::Truncated { got } => layout.err(format!("the data end after {got} of {count} values")),
        DecodeError::OutOfMemory => VolumeError::OutOfMemory {
            dims: layout.dims,
            bytes: layout.expected(),
        },
        DecodeError::BadValue { index, token } => {
            layout.err(format!("ASCII value {index} ('{token}') is not a valid {t}"))
        }
        DecodeError::Io(source) => layout.err(format!("reading the data failed: {source}")),
    })
}
