//! Wavefront OBJ (its material libraries are not read: no file beside the input).
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::model::obj;

fuzz_target!(|data: &[u8]| {
    lobelight_fuzz::init();
    let path = Path::new("fuzz.obj");
    if let Ok(mesh) = obj::parse(path, data) {
        lobelight_fuzz::check(&mesh, path);
    }
});
