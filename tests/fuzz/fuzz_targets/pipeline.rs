//! Any bytes through the whole pipeline: a scene either gets diagnostics or derives, checks,
//! prints and (with a `linearize about` line) linearizes; nothing may panic, hang or exhaust
//! memory.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // Bytes that are not UTF-8 get a located diagnostic, never a panic.
    let source = match cli::decode("fuzz.lag", data.to_vec()) {
        Ok(source) => source,
        Err(rendered) => {
            assert!(rendered.contains("fuzz.lag:"));
            return;
        }
    };
    let source = source.as_str();
    for units in [true, false] {
        let options = engine::Options { units };
        let checked = cli::check::check_file_with("fuzz.lag", source, options);
        assert!(checked.exit_code <= 2);
        if checked.exit_code < 2 {
            for format in [cli::Format::Text, cli::Format::Latex, cli::Format::Json] {
                let _ = cli::derive_with("fuzz.lag", source, format, options);
            }
            // A scene's own `linearize about` line, if it has one: an answer or exit 2.
            let linearize = engine::linearize::Options { no_units: !units, ..Default::default() };
            if let Ok(l) = engine::linearize::linearize(source, &linearize) {
                let _ = (cli::linearize::text(&l), cli::linearize::json(&l));
            }
        }
    }
});
