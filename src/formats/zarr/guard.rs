//! A store wrapper that refuses decompression bombs before zarrs decodes them. zarrs sizes its output by what the
//! compressed stream claims (zstd's frame content size, blosc's header) or grows it without bound (gzip, zstd
//! without a content size), so a tiny chunk could ask for terabytes. Every value read for a level is checked
//! against the level's largest chunk (or shard): stored bytes, a zstd or blosc header's claimed size, and for
//! streams that claim nothing (gzip, zstd without a size) a decode into a bounded sink that stops one byte past
//! the limit. Every stream start in a value is checked, so the inner chunks of a shard read whole are too.

use std::io::Read;
use std::sync::Arc;
use zarrs::array::Array;
use zarrs::storage::byte_range::ByteRangeIterator;
use zarrs::storage::{
    Bytes, MaybeBytes, MaybeBytesIterator, ReadableStorage, ReadableStorageTraits, StorageError, StoreKey,
};

/// Which compressors a level's codecs use.
#[derive(Clone, Copy, Debug, Default)]
struct Codecs {
    blosc: bool,
    zstd: bool,
    gzip: bool,
}

struct Guarded {
    inner: ReadableStorage,
    /// Most bytes one chunk or shard decodes to.
    limit: u64,
    codecs: Codecs,
}

/// `store` with values for `array` checked against its chunk size and codecs.
pub(super) fn guarded<S: ?Sized>(store: ReadableStorage, array: &Array<S>) -> ReadableStorage {
    let element = array.data_type().fixed_size().unwrap_or(8) as u64;
    let zeros = vec![0u64; array.dimensionality()];
    let chunk = array
        .chunk_shape(&zeros)
        .map(|s| s.iter().fold(element, |a, d| a.saturating_mul(d.get())))
        .unwrap_or(u64::MAX);
    let json = serde_json::to_string(array.metadata()).unwrap_or_default();
    Arc::new(Guarded {
        inner: store,
        limit: chunk,
        codecs: Codecs {
            blosc: json.contains("\"blosc\""),
            zstd: json.contains("\"zstd\""),
            gzip: json.contains("\"gzip\"") || json.contains("\"zlib\""),
        },
    })
}

fn refuse(key: &str, what: String) -> StorageError {
    StorageError::Other(format!("chunk '{key}' refused: {what}"))
}

impl Guarded {
    fn check(&self, key: &StoreKey, bytes: &[u8]) -> Result<(), StorageError> {
        let name = key.as_str();
        if name.ends_with("zarr.json")
            || name.ends_with(".zarray")
            || name.ends_with(".zattrs")
            || name.ends_with(".zgroup")
        {
            return Ok(());
        }
        let limit = self.limit;
        // Compression never grows data by more than a few percent; a shard adds a 16-byte index entry per chunk.
        let stored_limit = limit.saturating_add(limit / 8).saturating_add(1 << 16);
        if bytes.len() as u64 > stored_limit {
            return Err(refuse(
                name,
                format!("{} stored bytes for a chunk of at most {limit}", bytes.len()),
            ));
        }
        // A shard read whole holds its inner chunks one after another: every stream start in it is checked.
        if self.codecs.zstd {
            for at in starts(bytes, &[0x28, 0xB5, 0x2F, 0xFD]) {
                let frame = &bytes[at..];
                match zstd_content_size(frame) {
                    Some(claimed) if claimed > limit => {
                        let what = format!("its zstd frame claims {claimed} bytes, more than the chunk's {limit}");
                        return Err(refuse(name, format!("{what} (a decompression bomb?)")));
                    }
                    Some(_) => {}
                    None => bounded(name, zstd::stream::read::Decoder::new(frame).ok(), limit, "zstd")?,
                }
            }
        }
        if self.codecs.gzip {
            for at in starts(bytes, &[0x1F, 0x8B, 0x08]) {
                bounded(name, Some(flate2::read::GzDecoder::new(&bytes[at..])), limit, "gzip")?;
            }
        }
        if self.codecs.blosc && bytes.len() >= 16 {
            let claimed = u64::from(u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]));
            if claimed > limit {
                return Err(refuse(
                    name,
                    format!("its blosc header claims {claimed} bytes, more than the chunk's {limit} (a decompression bomb?)"),
                ));
            }
        }
        Ok(())
    }
}

/// Decodes `reader` into a sink that stops one byte past `limit`; more than `limit` bytes is a bomb. A corrupt
/// stream is left for zarrs to report.
fn bounded(name: &str, reader: Option<impl Read>, limit: u64, codec: &str) -> Result<(), StorageError> {
    let Some(reader) = reader else { return Ok(()) };
    let decoded = std::io::copy(&mut reader.take(limit.saturating_add(1)), &mut std::io::sink()).unwrap_or(0);
    if decoded > limit {
        return Err(refuse(
            name,
            format!("its {codec} stream decodes to more than the chunk's {limit} bytes (a decompression bomb?)"),
        ));
    }
    Ok(())
}

/// Where `magic` occurs in `bytes`.
fn starts<'a>(bytes: &'a [u8], magic: &'a [u8]) -> impl Iterator<Item = usize> + 'a {
    bytes
        .windows(magic.len())
        .enumerate()
        .filter(move |(_, w)| *w == magic)
        .map(|(i, _)| i)
}

/// The content size a zstd frame header states, if it states one.
fn zstd_content_size(b: &[u8]) -> Option<u64> {
    let fhd = *b.get(4)?;
    let single_segment = fhd & 0x20 != 0;
    let fcs_bytes = match fhd >> 6 {
        0 if single_segment => 1,
        0 => return None,
        1 => 2,
        2 => 4,
        _ => 8,
    };
    let did_bytes = [0usize, 1, 2, 4][usize::from(fhd & 3)];
    let start = 5 + usize::from(!single_segment) + did_bytes;
    let field = b.get(start..start + fcs_bytes)?;
    let mut v = [0u8; 8];
    v[..fcs_bytes].copy_from_slice(field);
    let size = u64::from_le_bytes(v);
    Some(if fcs_bytes == 2 { size + 256 } else { size })
}

impl ReadableStorageTraits for Guarded {
    fn get_partial_many<'a>(
        &'a self,
        key: &StoreKey,
        byte_ranges: ByteRangeIterator<'a>,
    ) -> Result<MaybeBytesIterator<'a>, StorageError> {
        let parts = self.inner.get_partial_many(key, byte_ranges)?;
        let Some(parts) = parts else { return Ok(None) };
        let checked: Vec<Result<Bytes, StorageError>> = parts
            .map(|p| {
                let p = p?;
                self.check(key, &p)?;
                Ok(p)
            })
            .collect();
        Ok(Some(Box::new(checked.into_iter())))
    }

    fn get(&self, key: &StoreKey) -> Result<MaybeBytes, StorageError> {
        let value = self.inner.get(key)?;
        if let Some(bytes) = &value {
            self.check(key, bytes)?;
        }
        Ok(value)
    }

    fn size_key(&self, key: &StoreKey) -> Result<Option<u64>, StorageError> {
        self.inner.size_key(key)
    }

    fn supports_get_partial(&self) -> bool {
        self.inner.supports_get_partial()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zstd_frame_sizes_are_read() {
        let frame = zstd::bulk::compress(&[7u8; 1000], 3).unwrap();
        assert_eq!(zstd_content_size(&frame), Some(1000));
    }
}
