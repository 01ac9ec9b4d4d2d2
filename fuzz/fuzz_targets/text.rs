//! Text clouds (`.xyz`, `.pts`): one reader for both.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::model::text;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.xyz");
    if let Ok(mesh) = text::parse(path, data, &lobelight_fuzz::reading()) {
        lobelight_fuzz::check(&mesh, path);
    }
});
