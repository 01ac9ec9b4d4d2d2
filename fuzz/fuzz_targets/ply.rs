//! PLY: ASCII and binary, meshes, clouds and Gaussian-splat captures.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::model::ply;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.ply");
    if let Ok(mesh) = ply::parse(path, data, &lobelight_fuzz::reading()) {
        lobelight_fuzz::check(&mesh, path);
    }
});
