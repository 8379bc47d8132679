//! OME-Zarr group attributes (multiscales, axes, transforms, omero, volcast's hint) from arbitrary bytes: must
//! return Ok or Err, never panic or hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use volcast::formats::from_bytes;

fuzz_target!(|data: &[u8]| {
    let _ = from_bytes::zarr_meta(data);
});
