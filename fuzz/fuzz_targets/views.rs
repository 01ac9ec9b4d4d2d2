//! View lists (`--views`): cameras and orbits, completing a scene's camera.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lobelight::scene::file::CameraDesc;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let base = CameraDesc::default();
    if let Ok(views) = lobelight::scene::views::parse(Path::new("views.toml"), text, &base) {
        assert!(!views.is_empty());
    }
});
