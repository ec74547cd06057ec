//! Fuzz target: `shadowlab::fuzz_input::toml_scene` must return for any input.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = shadowlab::fuzz_input::toml_scene(data);
});
