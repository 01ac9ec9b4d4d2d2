//! The bake cache on disk: a flipped byte anywhere is an error naming the file, never lobes
//! read back wrong; an older format or another scene's key is a miss that bakes again.

use lobelight::cache::{Miss, load, save};
use lobelight::em::{EmStats, LobeMap};
use lobelight::types::{Lobe, SplatLight};

fn map() -> LobeMap {
    let lobe = |k: u32| Lobe {
        axis: [0.0, 0.6, 0.8],
        sharpness: 10.0 + k as f32,
        irradiance: [0.1, 0.2, 0.3],
        weight: 0.5,
    };
    let light = |first: u32, lobes: u32| SplatLight {
        irradiance: [1.0, 2.0, 3.0],
        photons: 7,
        log_likelihood: -1.0,
        weight: 2.0,
        lobes,
        first_lobe: first,
    };
    LobeMap {
        lobes_per_splat: 2,
        lobes: (0..3).map(lobe).collect(),
        light: vec![light(0, 2), light(0, 0), light(2, 1)],
        stats: EmStats::default(),
    }
}

#[test]
fn every_flipped_byte_is_an_error_naming_the_file() {
    let dir = std::env::temp_dir().join(format!("lobelight-cache-flip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bake.cache");
    let key = 0x1234_5678_9abc_def0;
    save(&path, key, &map()).unwrap();
    let good = std::fs::read(&path).unwrap();
    let back = load(&path, key, 3).unwrap().unwrap();
    assert_eq!(back.lobes, map().lobes);
    assert_eq!(back.light, map().light);
    assert_eq!(load(&path, key ^ 1, 3).unwrap().err(), Some(Miss::Stale));
    for at in 0..good.len() {
        let mut bytes = good.clone();
        bytes[at] ^= 0x5a;
        std::fs::write(&path, &bytes).unwrap();
        match load(&path, key, 3) {
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains("bake.cache"), "byte {at}: {msg}");
            }
            Ok(r) => panic!(
                "byte {at} flipped, and the file read as {:?}",
                r.map(|_| ())
            ),
        }
    }
    // A file of the format before the checksum (version 2) is stale: it bakes again.
    let mut old = b"LOBELITE".to_vec();
    old.extend_from_slice(&2u32.to_le_bytes());
    old.extend_from_slice(&0u32.to_le_bytes());
    old.extend_from_slice(&key.to_le_bytes());
    old.extend_from_slice(&2u32.to_le_bytes());
    old.extend_from_slice(&0u32.to_le_bytes());
    std::fs::write(&path, &old).unwrap();
    assert_eq!(load(&path, key, 0).unwrap().err(), Some(Miss::Stale));
    std::fs::remove_dir_all(&dir).ok();
}

/// Values no fit writes, in a file whose checksum matches them (saved as they are): a NaN
/// irradiance, an infinite lobe sharpness, a NaN lobe axis, a negative sharpness. Each is an
/// error naming the file, not a black image.
#[test]
fn values_no_fit_writes_are_refused_though_the_checksum_matches() {
    let dir = std::env::temp_dir().join(format!("lobelight-cache-nan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bake.cache");
    let key = 7;
    let spoil: [fn(&mut LobeMap); 4] = [
        |m| m.light[1].irradiance[0] = f32::NAN,
        |m| m.lobes[2].sharpness = f32::INFINITY,
        |m| m.lobes[0].axis[1] = f32::NAN,
        |m| m.lobes[1].sharpness = -1.0,
    ];
    for (k, spoil) in spoil.iter().enumerate() {
        let mut bad = map();
        spoil(&mut bad);
        save(&path, key, &bad).unwrap();
        let e = load(&path, key, 3).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("bake.cache: values: "), "case {k}: {e}");
        assert!(e.contains("delete it to bake again"), "case {k}: {e}");
    }
}

/// A file larger than any cache of the scene could be, or a folder, is refused before it is
/// read: a `--cache` pointed at some other big file never loads it into memory.
#[test]
fn a_file_larger_than_the_scene_allows_is_not_read() {
    let dir = std::env::temp_dir().join(format!("lobelight-cache-size-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("video.mp4");
    // Sparse: 64 GiB that take no disk, far past what 3 splats' cache holds.
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(64 << 30).unwrap();
    let e = load(&path, 1, 3).unwrap_err().to_string();
    assert!(
        e.contains("video.mp4") && e.contains("more than a bake cache"),
        "{e}"
    );
    let e = load(&dir, 1, 3).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
