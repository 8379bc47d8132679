//! One OME-Zarr level from arbitrary bytes: the first two bytes (little-endian) give the length of the level's
//! array metadata (`zarr.json`), the rest is its first chunk, read through volcast's reader and its decompression
//! guard in an in-memory store. Must return Ok or Err, never panic, hang or allocate beyond the chunk's size.
#![no_main]

use libfuzzer_sys::fuzz_target;
use volcast::formats::from_bytes;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let n = usize::from(u16::from_le_bytes([data[0], data[1]])).min(data.len() - 2);
    let (meta, chunk) = data[2..].split_at(n);
    let _ = from_bytes::zarr_chunk(meta, chunk);
});
