//! Encoded samples -> the GPU's [`VoxelData`] in one streaming pass: the output is allocated once at its final
//! size and filled through a bounded buffer, so loading never holds the file's bytes and the converted copy at
//! once.

use super::{VoxelData, VoxelType};
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
