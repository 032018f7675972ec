//! libFuzzer target: arbitrary bytes through the scene parser and validator, with the properties of
//! `check.rs`.
#![no_main]

#[path = "../check.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::check_scene_bytes(data));
