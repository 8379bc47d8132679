//! Loading one DICOM file (header and pixels) from arbitrary bytes: must return Ok or Err, never panic, hang or
//! allocate beyond what the input justifies.
#![no_main]

use libfuzzer_sys::fuzz_target;
use volcast::formats::from_bytes;

fuzz_target!(|data: &[u8]| {
    let _ = from_bytes::dicom(data);
});
