//! A `.vti` array appended to the file (`<AppendedData>`, raw or base64, as VTK and ParaView write by default), read
//! where it lies: any byte range of its values is read with positioned reads, decoding only the base64 characters
//! and the compressed blocks under it, so a level of the pyramid is made on every core without holding the file
//! (docs/large-volumes.md, "How files are read"). Headers are checked against the extent and the file's length before
//! anything else is read or allocated. (Raw uncompressed arrays need none of this: they lie in place.)

use super::vti_data::{inflate_block, Compressor};
use crate::formats::decode::Endian;
use crate::volume::VolumeError;
use base64::Engine;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// How an appended array's bytes are written: as they are, or as base64 text from a byte of the file (each encoding
/// starts a new run of characters: VTK encodes a compressed array's header and its blocks separately).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Text {
    Raw,
    Base64,
}

/// Where an appended array's values lie.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockIndex {
    pub text: Text,
    /// `None`: the values in one run (base64 uncompressed), from byte `data` of the run that starts at `start`.
    pub compressor: Option<Compressor>,
    /// Where the run of the values (uncompressed) or of the blocks starts in the file, and where the values start in
    /// its decoded bytes.
    pub start: u64,
    pub data: u64,
    /// Uncompressed bytes per block (the last may hold fewer) and in all.
    pub block: u64,
    pub total: u64,
    /// Per block, where its compressed bytes start in the run's decoded bytes and how many there are.
    pub blocks: Vec<(u64, u64)>,
}

/// Positioned reads of a run's decoded bytes.
struct Run<'f> {
    file: &'f File,
    path: &'f Path,
    len: u64,
    text: Text,
    start: u64,
}

impl Run<'_> {
    /// Decoded bytes `at..at + out.len()` of the run.
    fn read(&self, at: u64, out: &mut [u8]) -> Result<(), VolumeError> {
        let n = out.len() as u64;
        match self.text {
            Text::Raw => self
                .bytes(self.start + at, out.len() as u64)
                .map(|b| out.copy_from_slice(&b)),
            Text::Base64 => {
                // Whole groups of 4 characters (3 bytes) around the range.
                let (first, last) = (at / 3, (at + n).div_ceil(3));
                let chars = self.bytes(self.start + 4 * first, 4 * (last - first))?;
                let decoded = engine()
                    .decode(&chars)
                    .map_err(|e| self.bad(format!("its base64 is invalid: {e}")))?;
                let skip = (at - 3 * first) as usize;
                let got = decoded
                    .get(skip..skip + out.len())
                    .ok_or_else(|| self.bad("its base64 ends early".into()))?;
                out.copy_from_slice(got);
                Ok(())
            }
        }
    }

    /// `n` bytes of the file from `at`, refused unread if they lie past its end.
    fn bytes(&self, at: u64, n: u64) -> Result<Vec<u8>, VolumeError> {
        if at.saturating_add(n) > self.len {
            return Err(self.bad(format!(
                "the appended array needs bytes {at}..{} but the file has {}",
                at.saturating_add(n),
                self.len
            )));
        }
        let mut b = vec![0u8; n as usize];
        self.file
            .read_exact_at(&mut b, at)
            .map_err(|source| io(self.path, source))?;
        Ok(b)
    }

    /// `count` header words of `word` bytes from decoded byte `at`.
    fn words(&self, at: u64, count: u64, (word, endian): (usize, Endian)) -> Result<Vec<u64>, VolumeError> {
        // A claim of more words than the file could hold is refused before anything is allocated.
        if count.saturating_mul(word as u64) > self.len {
            return Err(self.bad(format!("the appended array's header claims {count} words")));
        }
        let mut b = vec![0u8; count as usize * word];
        self.read(at, &mut b)?;
        Ok(b.chunks_exact(word).map(|w| value(w, endian)).collect())
    }

    fn bad(&self, problem: String) -> VolumeError {
        VolumeError::Header {
            file: crate::formats::format::file_label(self.path),
            problem,
        }
    }
}

impl BlockIndex {
    /// The index of the array whose header starts at byte `at` of `path` (written as `text`, header words of
    /// `word` bytes in `endian`, blocks by `compressor` or none), `total` bytes of values. Refused, naming the file,
    /// where a header disagrees with `total` or points past the file's end.
    pub fn read(
        path: &Path,
        (at, text): (u64, Text),
        (word, endian): (usize, Endian),
        compressor: Option<Compressor>,
        total: u64,
    ) -> Result<BlockIndex, VolumeError> {
        let file = File::open(path).map_err(|source| io(path, source))?;
        let len = file.metadata().map_err(|source| io(path, source))?.len();
        let run = Run {
            file: &file,
            path,
            len,
            text,
            start: at,
        };
        let Some(compressor) = compressor else {
            let count = run.words(0, 1, (word, endian))?[0];
            if count != total {
                return Err(run.bad(format!(
                    "the appended array holds {count} bytes, not the {total} its extent needs"
                )));
            }
            let index = BlockIndex {
                text,
                compressor: None,
                start: at,
                data: word as u64,
                block: total.max(1),
                total,
                blocks: Vec::new(),
            };
            run.read(
                index.data + total.saturating_sub(1),
                &mut [0u8; 1][..usize::from(total > 0)],
            )?;
            return Ok(index);
        };
        let head = run.words(0, 3, (word, endian))?;
        let (count, block, last) = (head[0], head[1], head[2]);
        let full = if last == 0 { block } else { last };
        let claimed = count.saturating_sub(1).saturating_mul(block).saturating_add(full);
        if count == 0 || block == 0 || full > block || claimed != total {
            return Err(run.bad(format!(
                "the compressed array's header ({count} blocks of {block} bytes, the last {full}) does not hold the \
                 {total} bytes its extent and type need"
            )));
        }
        let sizes = run.words(3 * word as u64, count, (word, endian))?;
        let header = (3 + count) * word as u64;
        // Raw: the blocks follow the header; base64: their own run of characters follows the header's.
        let (start, mut offset) = match text {
            Text::Raw => (at, header),
            Text::Base64 => (at + 4 * header.div_ceil(3), 0),
        };
        let mut blocks = Vec::with_capacity(sizes.len());
        for (i, &c) in sizes.iter().enumerate() {
            let size = if i as u64 + 1 == count { full } else { block };
            if size > compressor.max_output(c) {
                return Err(run.bad(format!(
                    "{} block {i} of {c} bytes claims to inflate to {size} bytes, more than it can produce",
                    compressor.name()
                )));
            }
            blocks.push((offset, c));
            offset = offset.saturating_add(c);
        }
        let encoded = match text {
            Text::Raw => offset,
            Text::Base64 => 4 * offset.div_ceil(3),
        };
        if start.saturating_add(encoded) > len {
            return Err(run.bad(format!(
                "the compressed blocks end at byte {}, past the file's end ({len} bytes)",
                start.saturating_add(encoded)
            )));
        }
        Ok(BlockIndex {
            text,
            compressor: Some(compressor),
            start,
            data: 0,
            block,
            total,
            blocks,
        })
    }

    /// Bytes `at..at + out.len()` of the values, from `file` (`path` names it in errors): each block under the range
    /// decoded once.
    pub fn read_at(&self, (file, path): (&File, &PathBuf), at: u64, out: &mut [u8]) -> Result<(), VolumeError> {
        let run = Run {
            file,
            path,
            len: u64::MAX,
            text: self.text,
            start: self.start,
        };
        let end = at + out.len() as u64;
        if end > self.total {
            return Err(run.bad(format!("bytes {at}..{end} lie past the array's {} bytes", self.total)));
        }
        let Some(compressor) = self.compressor else {
            return run.read(self.data + at, out);
        };
        if out.is_empty() {
            return Ok(());
        }
        let (mut input, mut decoded) = (Vec::new(), Vec::new());
        for b in at / self.block..=(end - 1) / self.block {
            let (offset, csize) = self.blocks[b as usize];
            let first = b * self.block;
            let size = self.block.min(self.total - first);
            input.resize(csize as usize, 0);
            run.read(offset, &mut input)?;
            inflate_block(compressor, size as usize, &input, &mut decoded)
                .map_err(|e| run.bad(format!("{} block {b} is corrupt: {e}", compressor.name())))?;
            let (lo, hi) = (at.max(first), end.min(first + size));
            out[(lo - at) as usize..(hi - at) as usize]
                .copy_from_slice(&decoded[(lo - first) as usize..(hi - first) as usize]);
        }
        Ok(())
    }
}

/// Standard base64, padding optional (VTK pads each run).
fn engine() -> base64::engine::GeneralPurpose {
    base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent)
            .with_decode_allow_trailing_bits(true),
    )
}

fn value(w: &[u8], endian: Endian) -> u64 {
    let mut b = [0u8; 8];
    match endian {
        Endian::Little => {
            b[..w.len()].copy_from_slice(w);
            u64::from_le_bytes(b)
        }
        Endian::Big => {
            b[8 - w.len()..].copy_from_slice(w);
            u64::from_be_bytes(b)
        }
    }
}

fn io(path: &Path, source: std::io::Error) -> VolumeError {
    VolumeError::Io {
        path: path.to_path_buf(),
        source,
    }
}
