//! Back sides of open models (`scene::sides`): which models get them, and what they are.

mod common;

use std::path::{Path, PathBuf};

use common::scans::{self, Scan};
use glam::Vec3;
use lobelight::scene::{self, Scene, sides};

/// The view the scans are taken from.
const VIEW: Vec3 = Vec3::new(0.3, 0.2, 1.0);

/// A folder of this test's own, with the closed bumpy ball and its single-view sheet.
fn models(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("lobelight-sides-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ball = scans::bumpy_ball(0.3, 60);
    let (closed, sheet) = (dir.join("ball.obj"), dir.join("sheet.obj"));
    std::fs::write(&closed, scans::obj_text(&ball)).unwrap();
    let scan = scans::single_view_scan(&ball, VIEW, Scan::Sheet);
    std::fs::write(&sheet, scans::obj_text(&scan)).unwrap();
    (dir, closed, sheet)
}

/// The model in `path` alone (`walls` false) or in the Cornell box, lit by a point light at
/// `light`, with `more` lines added to its object.
fn scene_of(dir: &Path, path: &Path, walls: bool, light: Vec3, more: &str) -> Scene {
    let walls = match walls {
        true => "[[object]]\nshape = \"cornell_box\"\n",
        false => "",
    };
    let text = format!(
        "[camera]\neye = [0, 0, 3.9]\ntarget = [0, 0, 0]\n\n[[light]]\ntype = \"point\"\n\
         position = [{}, {}, {}]\npower = 10\n\n{walls}[[object]]\nshape = \"model\"\n\
         path = {path:?}\nfit = 0.8\n{more}\n",
        light.x, light.y, light.z
    );
    scene::parse(&dir.join("scene.toml"), &text).unwrap()
}

/// The model's object summary (the last object).
fn model(scene: &Scene) -> &scene::ObjectSummary {
    scene.objects.last().unwrap()
}

/// A sheet in a room sees the room behind it, and gets a back side a disk: the disk's twin, a
/// radius behind it, facing the other way, of its material and surface, right after the
/// model's splats. The closed ball's backs face its inside: it keeps one side.
#[test]
fn an_open_sheet_in_a_room_gets_back_sides_and_a_closed_model_none() {
    let (dir, closed, sheet) = models("room");
    let light = Vec3::new(0.0, 0.9, 0.0);
    let ball = scene_of(&dir, &closed, true, light, "");
    assert_eq!(model(&ball).back_sides, 0);

    let open = scene_of(&dir, &sheet, true, light, "");
    let one = scene_of(&dir, &sheet, true, light, "sides = \"one\"");
    let n = model(&one).splats;
    assert_eq!(model(&one).back_sides, 0);
    assert_eq!(model(&open).back_sides, n);
    assert_eq!(model(&open).splats, 2 * n);
    assert_eq!(open.splats.len(), one.splats.len() + n);
    // The box's splats come first, then the model's, then its back sides.
    let start = one.splats.len() - n;
    for (k, s) in one.splats[start..].iter().enumerate() {
        let back = &open.splats[start + n + k];
        assert_eq!(*back, sides::back_side(s));
        let (c, b) = (Vec3::from(s.center), Vec3::from(back.center));
        assert!((c - b - s.radius * Vec3::from(s.normal)).length() < 1e-5 * (1.0 + c.length()));
        assert_eq!(Vec3::from(back.normal), -Vec3::from(s.normal));
        assert_eq!(
            (back.material, back.object, back.radius),
            (s.material, s.object, s.radius)
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// With nothing behind a sheet and its light in front, its backs see nothing (a terrain seen
/// from above, a facade lit from the street): no back sides, which would cost splats and change
/// no light. A light behind it lights it from behind: back sides.
#[test]
fn a_sheet_gets_back_sides_where_something_lies_behind_it() {
    let (dir, _, sheet) = models("alone");
    let front = scene_of(&dir, &sheet, false, 3.0 * VIEW.normalize(), "");
    assert_eq!(model(&front).back_sides, 0);
    let behind = scene_of(&dir, &sheet, false, -3.0 * VIEW.normalize(), "");
    assert_eq!(model(&behind).back_sides, model(&front).splats);
    std::fs::remove_dir_all(&dir).ok();
}

/// `sides` decides where it is set: "two" gives even a closed model its back sides, "one" none
/// to a sheet; another value is an error that names the key and the values.
#[test]
fn sides_decides_where_set() {
    let (dir, closed, _) = models("set");
    let light = Vec3::new(0.0, 0.9, 0.0);
    let two = scene_of(&dir, &closed, true, light, "sides = \"two\"");
    assert_eq!(2 * model(&two).back_sides, model(&two).splats);
    let text = format!(
        "[camera]\neye = [0, 0, 3.9]\ntarget = [0, 0, 0]\n\n[[light]]\ntype = \"point\"\n\
         position = [0, 0.9, 0]\npower = 10\n\n[[object]]\nshape = \"model\"\npath = {closed:?}\n\
         sides = \"three\"\n"
    );
    let e = scene::parse(&dir.join("scene.toml"), &text)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sides") && e.contains("three") && e.contains("auto"),
        "{e}"
    );
    let sphere = text
        .replace("shape = \"model\"", "shape = \"sphere\"")
        .replace("three", "two");
    let e = scene::parse(&dir.join("scene.toml"), &sphere)
        .unwrap_err()
        .to_string();
    assert!(e.contains("sides"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A quad is a sheet: a ground under a sky gets a back side (its back sees the sky below the
/// horizon, which would otherwise pass up through it), a floor lit from above keeps one.
#[test]
fn a_quad_ground_under_a_sky_gets_a_back_side() {
    let ground = "[[object]]\nshape = \"quad\"\nsize = [2.0, 2.0]\nrotate = [-90.0, 0.0, 0.0]\nspacing = 0.1\n";
    for (light, back) in [
        ("type = \"environment\"\nradiance = 1.0", true),
        (
            "type = \"point\"\nposition = [0.0, 1.0, 0.0]\npower = 10",
            false,
        ),
        (
            "type = \"sun\"\ndirection = [0.0, -1.0, 0.2]\nirradiance = 3",
            false,
        ),
    ] {
        let text = format!("[[light]]\n{light}\n\n{ground}");
        let scene = scene::parse(std::path::Path::new("ground.toml"), &text).unwrap();
        let o = &scene.objects[0];
        assert_eq!(
            o.back_sides > 0,
            back,
            "{light}: {} back sides",
            o.back_sides
        );
        if back {
            assert_eq!(2 * o.back_sides, o.splats, "{light}");
        }
    }
}
