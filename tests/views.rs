//! View lists (`render --views`): explicit cameras and orbits read from TOML, errors that name
//! the file and the view, and the sequence's file names.

use std::path::Path;

use glam::Vec3;
use lobelight::scene::file::CameraDesc;
use lobelight::scene::views::{numbered, parse};

#[test]
fn views_and_orbits_complete_the_scenes_camera() {
    let base = CameraDesc::default();
    let text = "[[view]]\neye = [1.0, 0.0, 3.0]\nfov = 30.0\n\n[orbit]\nframes = 4\n";
    let views = parse(Path::new("v.toml"), text, &base).unwrap();
    assert_eq!(views.len(), 5);
    assert_eq!(views[0].eye, [1.0, 0.0, 3.0]);
    assert_eq!(views[0].fov, 30.0);
    assert_eq!(views[0].target, base.target);
    // The orbit turns the scene's eye about its up axis through the target, a quarter a frame.
    let eye = |k: usize| Vec3::from(views[1 + k].eye);
    assert!((eye(0) - Vec3::from(base.eye)).length() < 1e-5);
    assert!(
        (eye(1) - Vec3::new(3.9, 0.0, 0.0)).length() < 1e-4,
        "{}",
        eye(1)
    );
    assert!(
        (eye(2) - Vec3::new(0.0, 0.0, -3.9)).length() < 1e-4,
        "{}",
        eye(2)
    );
    for k in 0..4 {
        assert!((eye(k).length() - 3.9).abs() < 1e-4);
    }
}

#[test]
fn bad_view_lists_name_the_file_and_the_view() {
    let base = CameraDesc::default();
    for (text, expect) in [
        ("", "no view"),
        ("[[view]]\neye = [0.0, 0.0, 0.0]\n", "view #1"),
        ("[[view]]\nfov = 0.0\n[[view]]\n", "view #1"),
        ("[orbit]\nframes = 0\n", "orbit"),
        ("[orbit]\nframes = 3\naxis = [0.0, 0.0, 0.0]\n", "orbit"),
        ("[[view]]\nzoom = 2.0\n", "line 2"),
    ] {
        let err = parse(Path::new("bad.toml"), text, &base)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(expect),
            "{text:?}: {err}"
        );
    }
}

#[test]
fn sequence_files_are_numbered() {
    fn p(s: &str) -> &Path {
        Path::new(s)
    }
    assert_eq!(numbered(p("out/f_###.png"), 7, 20), p("out/f_007.png"));
    assert_eq!(numbered(p("out/frame.exr"), 7, 20), p("out/frame_0007.exr"));
    assert_eq!(numbered(p("frame.png"), 12345, 20000), p("frame_12345.png"));
    assert_eq!(numbered(p("#.png"), 3, 5), p("3.png"));
}
