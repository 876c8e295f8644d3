//! The MCAP/CDR run reader on arbitrary bytes: it must return `Ok` or an error, never panic, hang or
//! allocate without bound. Twice: one run per file, and cut at standstills with invalid runs skipped.
#![no_main]

use libfuzzer_sys::fuzz_target;
use omni_cli::dataset::mcap::{McapOptions, read_bytes};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.mcap");
    let _ = read_bytes(path, data, &McapOptions::default());
    let _ = read_bytes(path, data, &McapOptions { split: Some(0.5), skip_invalid: true, ..Default::default() });
});
