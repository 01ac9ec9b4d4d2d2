//! LAS and LAZ lidar files (one reader; the point format's flag says which).
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::model::lidar;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.las");
    if let Ok(mesh) = lidar::parse(path, data.to_vec(), &lobelight_fuzz::reading()) {
        lobelight_fuzz::check(&mesh, path);
    }
});
