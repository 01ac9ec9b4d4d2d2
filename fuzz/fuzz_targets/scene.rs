//! Scene files: TOML, then every object made within the budget. Model paths resolve beside
//! a scene in a folder that does not exist, so no file of the machine is read.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    lobelight_fuzz::init();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("/nonexistent-lobelight-fuzz/scene.toml");
    if let Ok(scene) = lobelight::scene::parse(path, text) {
        assert!(!scene.splats.is_empty() && !scene.lights.is_empty());
        assert!(scene.search_radius() > 0.0);
    }
});
