//! The omnical CSV run reader on arbitrary bytes: it must return `Ok` or an error, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use omni_cli::dataset::csv::parse_run;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = parse_run(Path::new("fuzz.csv"), data, None);
});
