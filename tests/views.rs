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

#[test]
fn a_path_of_keyframes_makes_its_frames_at_its_rate() {
    use lobelight::scene::views::parse_list;
    let base = CameraDesc::default();
    let text = "[path]\nfps = 10\n[[path.key]]\ntime = 0.0\neye = [0.0, 0.0, 4.0]\n\
                [[path.key]]\ntime = 1.0\neye = [4.0, 0.0, 0.0]\nfov = 30.0\n\
                [[path.key]]\ntime = 1.5\neye = [0.0, 1.0, -4.0]\n";
    let list = parse_list(Path::new("p.toml"), text, &base).unwrap();
    assert_eq!(list.fps, Some(10.0));
    // 0 s to 1.5 s at 10 a second, both ends in.
    assert_eq!(list.cameras.len(), 16);
    assert_eq!(list.cameras[0].eye, [0.0, 0.0, 4.0]);
    assert_eq!(list.cameras[10].fov, 30.0);
    let last = Vec3::from(list.cameras[15].eye);
    assert!((last - Vec3::new(0.0, 1.0, -4.0)).length() < 1e-5, "{last}");
    // What a key leaves out is the scene camera's.
    assert_eq!(list.cameras[5].target, base.target);
}

#[test]
fn bad_paths_name_the_file_and_the_key() {
    use lobelight::scene::views::parse_list;
    let base = CameraDesc::default();
    let key = |t: f32| format!("[[path.key]]\ntime = {t:?}\n");
    for (text, expect) in [
        ("[path]\nfps = 24\n".to_string(), "line"),
        (format!("[path]\nfps = 0.0\n{}", key(0.0)), "fps"),
        (
            format!("[path]\n{}{}", key(1.0), key(0.5)),
            "key #2: times must increase",
        ),
        (format!("[path]\n{}{}", key(0.0), key(0.0)), "key #2"),
        (format!("[path]\n{}zoom = 2.0\n", key(0.0)), "line"),
        (
            format!("[path]\n{}eye = [0.0, 0.0, 0.0]\n", key(0.0)),
            "key #1",
        ),
        (
            format!("[path]\nfps = 1000\n{}{}", key(0.0), key(2000.0)),
            "frames",
        ),
    ] {
        let err = parse_list(Path::new("bad.toml"), &text, &base)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(expect),
            "{text:?}: {err}"
        );
    }
}
