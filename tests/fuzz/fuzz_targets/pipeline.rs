//! Any bytes through the whole pipeline: a scene either gets diagnostics or derives, checks
//! and prints; nothing may panic, hang or exhaust memory.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(source) = std::str::from_utf8(data) else { return };
    for units in [true, false] {
        let options = cli::Options { units };
        let checked = cli::check::check_file_with("fuzz.lag", source, options);
        assert!(checked.exit_code <= 2);
        if checked.exit_code < 2 {
            for format in [cli::Format::Text, cli::Format::Latex, cli::Format::Json] {
                let _ = cli::derive_with("fuzz.lag", source, format, options);
            }
        }
    }
});
