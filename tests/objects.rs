//! Object-ID images: which surface each pixel shows, written and read back with its names.

use std::path::Path;

use glam::Vec3;
use lobelight::camera::View;
use lobelight::cli::compare::{read_object_ids, write_object_ids};
use lobelight::frame::{FrameConfig, camera_uniform};
use lobelight::objects::{MIXED, NONE, SAMPLES, id_of, object_ids};
use lobelight::scene;

/// The Cornell box at 48²: its seven surfaces (five walls, two blocks) each own pixels, the
/// tall block owns the pixel at its centre, no pixel is empty (the box fills the view, and
/// the light is on the ceiling's far side of every ray), and edges are a minority. The eighth
/// surface is the light's own (it reflects), hidden behind its face.
#[test]
fn cornell_box_pixels_name_their_surfaces() {
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    assert_eq!(scene.surfaces.len(), 8);
    assert_eq!(scene.surfaces[6], "#3 box (glossy)");
    assert_eq!(scene.surfaces[7], "light 1");
    let grid = lobelight::cpu::scene_grid(&scene).unwrap();
    let view = View::new(&scene.camera, 48, 48);
    let cam = camera_uniform(&view, scene.bounds(), &FrameConfig::default());
    let ids = object_ids(&scene, &grid, &cam, SAMPLES).unwrap();
    let count = |id: u16| ids.iter().filter(|&&v| v == id).count();
    for k in 0..7 {
        assert!(
            count(id_of(k)) > 20,
            "{}: {} pixels",
            scene.surfaces[k as usize],
            count(id_of(k))
        );
    }
    let mixed = count(MIXED);
    eprintln!("{mixed} edge pixels, {} empty", count(NONE));
    assert!(mixed > 0 && mixed < ids.len() / 4, "{mixed} edge pixels");
    let (x, y) = view.project(Vec3::new(-0.33, -0.4, -0.28)).unwrap();
    assert_eq!(ids[(y * 48 + x) as usize], id_of(6));

    let dir = std::env::temp_dir().join(format!("lobelight-ids-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ids.png");
    write_object_ids(&path, &ids, 48, 48, &scene.surfaces).unwrap();
    let (back, w, h, names) = read_object_ids(&path).unwrap();
    assert_eq!((w, h), (48, 48));
    assert_eq!(back, ids);
    assert_eq!(names, scene.surfaces);
    assert!(write_object_ids(&dir.join("ids.exr"), &ids, 48, 48, &names).is_err());
    std::fs::remove_dir_all(&dir).ok();
}
