//! E57 scanner files.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::model::scan;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.e57");
    if let Ok(mesh) = scan::parse(path, data.to_vec(), &lobelight_fuzz::reading()) {
        lobelight_fuzz::check(&mesh, path);
    }
});
