//! Encoded samples -> the GPU's [`VoxelData`] in one streaming pass: the output is allocated once at its final
//! size and filled through a bounded buffer, so loading never holds the file's bytes and the converted copy at
//! once.

use crate::volume::{VoxelData, VoxelType};
use rayon::prelude::*;
use std::io::{self, BufRead, Read};

/// Bytes converted per step (a multiple of every sample size).
pub(crate) const CHUNK_BYTES: usize = 1 << 20;

/// Byte order of multi-byte samples in a file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Endian {
    #[default]
    Little,
    Big,
}

impl Endian {
    /// This machine's byte order: what bytes written from memory are in.
    pub const NATIVE: Endian = if cfg!(target_endian = "big") {
        Endian::Big
    } else {
        Endian::Little
    };

    pub fn parse(s: &str) -> Option<Endian> {
        match s.trim().to_ascii_lowercase().as_str() {
            "little" | "le" => Some(Endian::Little),
            "big" | "be" => Some(Endian::Big),
            _ => None,
        }
    }
}

#[derive(Debug)]
pub(crate) enum DecodeError {
    /// The stream ended after `got` of the needed bytes (or values, for ASCII).
    Truncated {
        got: u64,
    },
    Io(io::Error),
    OutOfMemory,
    /// An ASCII token that is not a number of the voxel type.
    BadValue {
        index: u64,
        token: String,
    },
}

impl From<io::Error> for DecodeError {
    fn from(e: io::Error) -> DecodeError {
        DecodeError::Io(e)
    }
}

/// Reports progress as a fraction in [0, 1] to an optional callback.
pub(crate) struct Progress<'a> {
    callback: Option<&'a mut dyn FnMut(f32)>,
}

impl<'a> Progress<'a> {
    pub fn new(callback: Option<&'a mut dyn FnMut(f32)>) -> Progress<'a> {
        Progress { callback }
    }

    pub fn none() -> Progress<'static> {
        Progress { callback: None }
    }

    pub fn report(&mut self, fraction: f64) {
        if let Some(cb) = self.callback.as_mut() {
            cb(fraction.clamp(0.0, 1.0) as f32);
        }
    }
}

/// A vector with room for exactly `count` elements, or an error instead of the allocator's abort.
pub(crate) fn try_vec<T>(count: usize) -> Result<Vec<T>, DecodeError> {
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|_| DecodeError::OutOfMemory)?;
    Ok(v)
}

/// The output buffer in the representation `voxel_type` maps to.
enum Sink {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl Sink {
    fn new(voxel_type: VoxelType, count: usize) -> Result<Sink, DecodeError> {
        Ok(match voxel_type {
            VoxelType::U8 | VoxelType::I8 => Sink::U8(try_vec(count)?),
            VoxelType::U16 | VoxelType::I16 => Sink::U16(try_vec(count)?),
            VoxelType::F32 | VoxelType::F64 | VoxelType::U32 | VoxelType::I32 => Sink::F32(try_vec(count)?),
        })
    }

    fn into_data(self) -> VoxelData {
        match self {
            Sink::U8(v) => VoxelData::U8(v),
            Sink::U16(v) => VoxelData::U16(v),
            Sink::F32(v) => VoxelData::F32(v),
        }
    }

    /// Appends whole samples from `bytes` (a multiple of the sample size).
    fn push_bytes(&mut self, voxel_type: VoxelType, endian: Endian, bytes: &[u8]) {
        fn word<const N: usize>(b: &[u8], endian: Endian) -> [u8; N] {
            let mut w = [0u8; N];
            w.copy_from_slice(b);
            if endian == Endian::Big {
                w.reverse();
            }
            w
        }
        match (self, voxel_type) {
            (Sink::U8(v), VoxelType::U8) => v.extend_from_slice(bytes),
            // i8 + 128 as u8 flips the sign bit.
            (Sink::U8(v), _) => v.extend(bytes.iter().map(|b| b ^ 0x80)),
            (Sink::U16(v), VoxelType::U16) => {
                v.extend(bytes.chunks_exact(2).map(|b| u16::from_le_bytes(word(b, endian))))
            }
            // i16 + 32768 as u16 flips the sign bit.
            (Sink::U16(v), _) => v.extend(
                bytes
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes(word(b, endian)) ^ 0x8000),
            ),
            (Sink::F32(v), VoxelType::F32) => {
                v.extend(bytes.chunks_exact(4).map(|b| f32::from_le_bytes(word(b, endian))))
            }
            (Sink::F32(v), VoxelType::U32) => v.extend(
                bytes
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes(word(b, endian)) as f32),
            ),
            (Sink::F32(v), VoxelType::I32) => v.extend(
                bytes
                    .chunks_exact(4)
                    .map(|b| i32::from_le_bytes(word(b, endian)) as f32),
            ),
            (Sink::F32(v), _) => v.extend(
                bytes
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes(word(b, endian)) as f32),
            ),
        }
    }

    /// Appends one value given in source units; false if it is not a value of `voxel_type`.
    fn push_value(&mut self, voxel_type: VoxelType, token: &str) -> bool {
        let integer = |lo: i64, hi: i64| token.parse::<i64>().ok().filter(|v| (lo..=hi).contains(v));
        match (self, voxel_type) {
            (Sink::U8(v), VoxelType::U8) => integer(0, 255).map(|x| v.push(x as u8)).is_some(),
            (Sink::U8(v), _) => integer(-128, 127).map(|x| v.push((x + 128) as u8)).is_some(),
            (Sink::U16(v), VoxelType::U16) => integer(0, 65535).map(|x| v.push(x as u16)).is_some(),
            (Sink::U16(v), _) => integer(-32768, 32767).map(|x| v.push((x + 32768) as u16)).is_some(),
            (Sink::F32(v), VoxelType::U32) => integer(0, u32::MAX.into()).map(|x| v.push(x as f32)).is_some(),
            (Sink::F32(v), VoxelType::I32) => integer(i32::MIN.into(), i32::MAX.into())
                .map(|x| v.push(x as f32))
                .is_some(),
            (Sink::F32(v), _) => token.parse::<f64>().ok().map(|x| v.push(x as f32)).is_some(),
        }
    }
}

/// Reads until `buf` is full or the stream ends; returns how many bytes arrived.
fn read_full(reader: &mut dyn Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match reader.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// Reads exactly `count` binary samples and converts them. Never reads past the last sample, so a compressed
/// stream is only inflated as far as the header's claim.
pub(crate) fn read_binary(
    reader: &mut dyn Read,
    voxel_type: VoxelType,
    endian: Endian,
    count: usize,
    chunk_bytes: usize,
    progress: &mut Progress,
) -> Result<VoxelData, DecodeError> {
    let size = voxel_type.size();
    let total = count as u64 * size as u64;
    let mut sink = Sink::new(voxel_type, count)?;
    let per_chunk = (chunk_bytes / size).clamp(1, count.max(1));
    let mut buffer = vec![0u8; per_chunk * size];
    let mut remaining = count;
    let mut got = 0u64;
    while remaining > 0 {
        let n = remaining.min(per_chunk);
        let bytes = &mut buffer[..n * size];
        let filled = read_full(reader, bytes)?;
        got += filled as u64;
        if filled < bytes.len() {
            return Err(DecodeError::Truncated { got });
        }
        sink.push_bytes(voxel_type, endian, bytes);
        remaining -= n;
        progress.report(got as f64 / total as f64);
    }
    Ok(sink.into_data())
}

/// Bytes [`read_native_at`] reads between progress reports; each batch is split over the cores.
const BATCH_BYTES: usize = 64 << 20;

/// Bytes one core reads at a time within a batch.
const PIECE_BYTES: usize = 4 << 20;

/// A zeroed vector of `count` elements, or an error instead of the allocator's abort. Zeroed by the allocator:
/// a large allocation comes as fresh pages that are zero already, so nothing is written twice.
fn try_zeroed_vec<T: bytemuck::Zeroable>(count: usize) -> Result<Vec<T>, DecodeError> {
    if count == 0 || std::mem::size_of::<T>() == 0 {
        return Ok(Vec::new());
    }
    let layout = std::alloc::Layout::array::<T>(count).map_err(|_| DecodeError::OutOfMemory)?;
    // SAFETY: the layout has a non-zero size (checked above).
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) }.cast::<T>();
    if ptr.is_null() {
        return Err(DecodeError::OutOfMemory);
    }
    // SAFETY: the allocation is `layout.size()` initialised (zero) bytes, borrowed only for this call.
    crate::volume::huge_pages::advise(unsafe { std::slice::from_raw_parts_mut(ptr.cast::<u8>(), layout.size()) });
    // SAFETY: allocated by the global allocator with exactly this layout; all-zero bytes are a valid T (Zeroable).
    Ok(unsafe { Vec::from_raw_parts(ptr, count, count) })
}

/// Reads `count` samples of `voxel_type` from `file` at byte `offset` straight into the output, on every core,
/// where the file's layout is the output's (8- and 16-bit integers and float32 in the host's byte order; signed
/// integers get their bias as one more pass over memory). `None` for the other layouts, which
/// [`read_binary`] converts through a buffer. Reading in parallel matters on a warm page cache: the kernel's copy
/// into fresh pages is the cost, and it runs on the reading thread.
pub(crate) fn read_native_at(
    file: &std::fs::File,
    offset: u64,
    voxel_type: VoxelType,
    endian: Endian,
    count: usize,
    progress: &mut Progress,
) -> Option<Result<VoxelData, DecodeError>> {
    let native = endian == Endian::Little && cfg!(target_endian = "little") || voxel_type.size() == 1;
    if !native {
        return None;
    }
    let read = |bytes: &mut [u8], progress: &mut Progress| read_pieces_at(file, offset, bytes, progress);
    Some(match voxel_type {
        VoxelType::U8 | VoxelType::I8 => try_zeroed_vec::<u8>(count).and_then(|mut v| {
            read(&mut v, progress)?;
            if voxel_type == VoxelType::I8 {
                // i8 + 128 as u8 flips the sign bit.
                v.par_iter_mut().for_each(|b| *b ^= 0x80);
            }
            Ok(VoxelData::U8(v))
        }),
        VoxelType::U16 | VoxelType::I16 => try_zeroed_vec::<u16>(count).and_then(|mut v| {
            read(bytemuck::cast_slice_mut(&mut v), progress)?;
            if voxel_type == VoxelType::I16 {
                v.par_iter_mut().for_each(|w| *w ^= 0x8000);
            }
            Ok(VoxelData::U16(v))
        }),
        VoxelType::F32 => try_zeroed_vec::<f32>(count).and_then(|mut v| {
            read(bytemuck::cast_slice_mut(&mut v), progress)?;
            Ok(VoxelData::F32(v))
        }),
        _ => return None,
    })
}

/// Reads `count` samples of `voxel_type` at byte `offset` of `file`: in parallel where the layout is native
/// ([`read_native_at`]), else streamed through [`read_binary`] from `offset`.
pub(crate) fn read_file_at(
    file: &std::fs::File,
    offset: u64,
    voxel_type: VoxelType,
    endian: Endian,
    count: usize,
    progress: &mut Progress,
) -> Result<VoxelData, DecodeError> {
    use std::io::{Seek, SeekFrom};
    if let Some(read) = read_native_at(file, offset, voxel_type, endian, count, progress) {
        return read;
    }
    // `&File` reads and seeks the file itself.
    let mut reader = file;
    reader.seek(SeekFrom::Start(offset))?;
    read_binary(&mut reader, voxel_type, endian, count, CHUNK_BYTES, progress)
}

/// Fills `bytes` from `file` at `offset`, batch by batch (progress after each), each batch's pieces on every core.
fn read_pieces_at(
    file: &std::fs::File,
    offset: u64,
    bytes: &mut [u8],
    progress: &mut Progress,
) -> Result<(), DecodeError> {
    let total = bytes.len();
    let mut done = 0;
    for batch in bytes.chunks_mut(BATCH_BYTES) {
        let start = offset + done as u64;
        batch
            .par_chunks_mut(PIECE_BYTES)
            .enumerate()
            .try_for_each(|(i, piece)| read_exact_at(file, piece, start + (i * PIECE_BYTES) as u64))
            .map_err(|e| match e.kind() {
                // The size was checked before reading: only a file that shrank while being read gets here.
                io::ErrorKind::UnexpectedEof => DecodeError::Truncated { got: done as u64 },
                _ => DecodeError::Io(e),
            })?;
        done += batch.len();
        progress.report(done as f64 / total as f64);
    }
    Ok(())
}

/// Fills `buf` from `file` at `offset` without moving the file's position (so threads can share the file).
#[cfg(unix)]
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(file: &std::fs::File, mut buf: &mut [u8], mut offset: u64) -> io::Result<()> {
    while !buf.is_empty() {
        match std::os::windows::fs::FileExt::seek_read(file, buf, offset) {
            Ok(0) => return Err(io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Longest ASCII token accepted; anything longer is not a number.
const MAX_TOKEN: usize = 64;

/// Reads `count` whitespace-separated numbers (commas count as whitespace). Values outside the voxel type's range
/// or with a fraction for an integer type are errors, not silently clamped.
pub(crate) fn read_ascii(
    reader: &mut dyn BufRead,
    voxel_type: VoxelType,
    count: usize,
    progress: &mut Progress,
) -> Result<VoxelData, DecodeError> {
    let mut sink = Sink::new(voxel_type, count)?;
    let mut token = Vec::with_capacity(MAX_TOKEN);
    let mut done = 0usize;
    let report_every = (count / 100).max(1);
    let finish_token = |token: &mut Vec<u8>, sink: &mut Sink, done: &mut usize| -> Result<(), DecodeError> {
        if token.is_empty() || *done == count {
            token.clear();
            return Ok(());
        }
        let text = String::from_utf8_lossy(token);
        if !sink.push_value(voxel_type, &text) {
            return Err(DecodeError::BadValue {
                index: *done as u64,
                token: text.chars().take(MAX_TOKEN).collect(),
            });
        }
        *done += 1;
        token.clear();
        Ok(())
    };
    while done < count {
        let buf = match reader.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e.into()),
        };
        if buf.is_empty() {
            finish_token(&mut token, &mut sink, &mut done)?;
            break;
        }
        let len = buf.len();
        for &b in buf {
            if b.is_ascii_whitespace() || b == b',' {
                finish_token(&mut token, &mut sink, &mut done)?;
                if done.is_multiple_of(report_every) {
                    progress.report(done as f64 / count as f64);
                }
            } else if token.len() >= MAX_TOKEN {
                return Err(DecodeError::BadValue {
                    index: done as u64,
                    token: String::from_utf8_lossy(&token).into_owned() + "...",
                });
            } else {
                token.push(b);
            }
            if done == count {
                break;
            }
        }
        reader.consume(len);
    }
    if done < count {
        return Err(DecodeError::Truncated { got: done as u64 });
    }
    progress.report(1.0);
    Ok(sink.into_data())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary(bytes: &[u8], t: VoxelType, e: Endian, n: usize, chunk: usize) -> Result<VoxelData, DecodeError> {
        read_binary(&mut &bytes[..], t, e, n, chunk, &mut Progress::none())
    }

    #[test]
    fn every_type_in_both_byte_orders() {
        let cases: [(VoxelType, Vec<u8>, VoxelData); 8] = [
            (VoxelType::U8, vec![0, 200], VoxelData::U8(vec![0, 200])),
            (VoxelType::I8, vec![0x80, 0x7f], VoxelData::U8(vec![0, 255])),
            (VoxelType::U16, vec![0x01, 0x02], VoxelData::U16(vec![0x0201])),
            (VoxelType::I16, vec![0xff, 0xff], VoxelData::U16(vec![0x7fff])),
            (VoxelType::U32, vec![1, 0, 0, 0], VoxelData::F32(vec![1.0])),
            (VoxelType::I32, vec![0xfe, 0xff, 0xff, 0xff], VoxelData::F32(vec![-2.0])),
            (VoxelType::F32, 1.5f32.to_le_bytes().to_vec(), VoxelData::F32(vec![1.5])),
            (
                VoxelType::F64,
                (-0.25f64).to_le_bytes().to_vec(),
                VoxelData::F32(vec![-0.25]),
            ),
        ];
        for (t, le, expected) in cases {
            let n = le.len() / t.size();
            assert_eq!(binary(&le, t, Endian::Little, n, 8).unwrap(), expected, "{t} LE");
            let be: Vec<u8> = le.chunks(t.size()).flat_map(|c| c.iter().rev().copied()).collect();
            assert_eq!(binary(&be, t, Endian::Big, n, 8).unwrap(), expected, "{t} BE");
        }
    }

    #[test]
    fn parallel_reads_equal_the_streaming_decoder() {
        // 9 MiB + 2 bytes of noise after a 3-byte header: several pieces, a short last one, an odd offset.
        let path = std::env::temp_dir().join(format!("volcast-read-at-{}.bin", std::process::id()));
        let mut bytes = vec![7u8, 8, 9];
        let mut state = 1u32;
        bytes.extend((0..(9 << 20) + 2).map(|_| {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 24) as u8
        }));
        std::fs::write(&path, &bytes).unwrap();
        let file = std::fs::File::open(&path).unwrap();
        let payload = &bytes[3..];
        for t in [
            VoxelType::U8,
            VoxelType::I8,
            VoxelType::U16,
            VoxelType::I16,
            VoxelType::F32,
        ] {
            let n = payload.len() / t.size();
            let mut reports = Vec::new();
            let mut report = |f: f32| reports.push(f);
            let got = read_native_at(&file, 3, t, Endian::Little, n, &mut Progress::new(Some(&mut report)));
            let got = got.expect("a native layout").unwrap();
            let expected = binary(&payload[..n * t.size()], t, Endian::Little, n, CHUNK_BYTES).unwrap();
            // Compared as bits: the noise holds NaN floats.
            let bits = |d: &VoxelData| match d {
                VoxelData::U8(v) => v.iter().map(|&x| u32::from(x)).collect::<Vec<_>>(),
                VoxelData::U16(v) => v.iter().map(|&x| u32::from(x)).collect(),
                VoxelData::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
            };
            assert!(bits(&got) == bits(&expected), "{t}");
            assert_eq!(reports.last(), Some(&1.0), "{t}: progress ends at 1");
            // Beyond the end of the file: truncation, not a panic or garbage.
            let past = read_native_at(&file, 3, t, Endian::Little, n + 1, &mut Progress::none()).unwrap();
            assert!(matches!(past, Err(DecodeError::Truncated { .. })), "{t}");
        }
        // Other layouts are left to the streaming decoder.
        assert!(read_native_at(&file, 0, VoxelType::U16, Endian::Big, 4, &mut Progress::none()).is_none());
        assert!(read_native_at(&file, 0, VoxelType::F64, Endian::Little, 4, &mut Progress::none()).is_none());
        assert!(read_native_at(&file, 0, VoxelType::U8, Endian::Big, 4, &mut Progress::none()).is_some());
        drop(file);
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn chunks_cover_every_voxel_and_short_input_is_truncation() {
        let values: Vec<f64> = (0..10).map(|i| f64::from(i) * 1.5 - 3.0).collect();
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        for chunk in [24, 8, 1, 80, 1 << 20] {
            let got = binary(&bytes, VoxelType::F64, Endian::Little, 10, chunk).unwrap();
            let expected: Vec<f32> = values.iter().map(|&v| v as f32).collect();
            assert_eq!(got, VoxelData::F32(expected), "chunk {chunk}");
        }
        assert!(matches!(
            binary(&bytes[..75], VoxelType::F64, Endian::Little, 10, 24),
            Err(DecodeError::Truncated { got: 75 })
        ));
    }

    #[test]
    fn progress_reaches_one() {
        let mut seen = Vec::new();
        let mut cb = |f: f32| seen.push(f);
        let mut p = Progress::new(Some(&mut cb));
        read_binary(&mut &[0u8; 100][..], VoxelType::U8, Endian::Little, 100, 30, &mut p).unwrap();
        assert_eq!(seen.len(), 4);
        assert_eq!(seen.last(), Some(&1.0));
        assert!(seen.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn ascii_values_and_errors() {
        let text = b"1 -2,3\n\t4.5e0  nan\n";
        let got = read_ascii(&mut &text[..], VoxelType::F32, 5, &mut Progress::none()).unwrap();
        let VoxelData::F32(v) = got else { panic!() };
        assert_eq!(&v[..4], &[1.0, -2.0, 3.0, 4.5]);
        assert!(v[4].is_nan());
        // Stops after `count`; the rest may be another array.
        let got = read_ascii(&mut &b"7 8 junk"[..], VoxelType::U8, 2, &mut Progress::none()).unwrap();
        assert_eq!(got, VoxelData::U8(vec![7, 8]));
        let got = read_ascii(&mut &b"-128 127"[..], VoxelType::I8, 2, &mut Progress::none()).unwrap();
        assert_eq!(got, VoxelData::U8(vec![0, 255]));
        assert!(matches!(
            read_ascii(&mut &b"1 2"[..], VoxelType::U8, 3, &mut Progress::none()),
            Err(DecodeError::Truncated { got: 2 })
        ));
        for (text, t) in [
            (&b"1 256"[..], VoxelType::U8),
            (b"1 2.5", VoxelType::I16),
            (b"x", VoxelType::F32),
        ] {
            assert!(
                matches!(
                    read_ascii(&mut &text[..], t, 2, &mut Progress::none()),
                    Err(DecodeError::BadValue { .. })
                ),
                "{t}"
            );
        }
        let long = vec![b'1'; 1000];
        assert!(matches!(
            read_ascii(&mut &long[..], VoxelType::F32, 1, &mut Progress::none()),
            Err(DecodeError::BadValue { .. })
        ));
    }

    #[test]
    fn endian_names() {
        assert_eq!(Endian::parse("BIG"), Some(Endian::Big));
        assert_eq!(Endian::parse("little"), Some(Endian::Little));
        assert_eq!(Endian::parse("middle"), None);
    }
}
