#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| isomorph_tests::fuzzing::scene(data));
