//! Scene files: the shipped scenes load, and malformed ones give one clear line naming the
//! file, the line and the key. No GPU needed.

use std::path::Path;

use lobelight::scene;
use lobelight::scene::model::Reading;

/// A reading that refuses a file at its first bad point (`--strict`).
fn strict() -> Reading {
    Reading {
        strict: true,
        ..Reading::current()
    }
}

fn err(text: &str) -> String {
    scene::parse(Path::new("scenes/bad.toml"), text)
        .unwrap_err()
        .to_string()
}

const MINIMAL: &str = r#"
[[light]]
type = "point"
position = [0.0, 0.5, 0.0]
power = 10.0

[[object]]
shape = "quad"
"#;

#[test]
fn minimal_scene_uses_defaults() {
    let s = scene::parse(Path::new("min.toml"), MINIMAL).unwrap();
    assert_eq!(
        s.splats.len(),
        40 * 40,
        "a unit quad at the default spacing"
    );
    assert_eq!(s.material_names, vec!["default"]);
    assert_eq!(s.camera.resolution, [512, 512]);
    assert_eq!(s.lights[0].power, [10.0; 3]);
    assert!(!s.has_glossy());
}

#[test]
fn shipped_scenes_load() {
    for name in ["cornell", "cornell_spheres", "diffuse"] {
        let s = scene::load(Path::new(&format!("scenes/{name}.toml"))).unwrap();
        assert!(s.splats.len() > 30_000, "{name}: {}", s.splats.len());
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.has_glossy(), name != "diffuse", "{name}");
    }
}

#[test]
fn cornell_light_power_is_pi_radiance_area() {
    let s = scene::load(Path::new("scenes/diffuse.toml")).unwrap();
    let l = &s.lights[0];
    let area = 0.46 * 0.38;
    let expected = 18.387 * std::f32::consts::PI * area;
    assert!(
        (l.power[0] - expected).abs() < 1e-4 * expected,
        "{:?}",
        l.power
    );
    assert!((l.area - area).abs() < 1e-6);
    // Corner + half edges = centre; facing down.
    let c: Vec<f32> = (0..3)
        .map(|i| l.position[i] + 0.5 * (l.edge_u[i] + l.edge_v[i]))
        .collect();
    assert!(
        (c[0]).abs() < 1e-6 && (c[1] - 0.99).abs() < 1e-6 && (c[2] - 0.01).abs() < 1e-6,
        "{c:?}"
    );
    assert_eq!(l.direction, [0.0, -1.0, 0.0]);
}

#[test]
fn misspelt_key_names_line_and_key() {
    let text = MINIMAL.replace("shape = \"quad\"", "shape = \"quad\"\nspacng = 0.01");
    let msg = err(&text);
    assert!(msg.starts_with("scenes/bad.toml: line 9:"), "{msg}");
    assert!(msg.contains("unknown field `spacng`"), "{msg}");
}

#[test]
fn misspelt_table_key() {
    let msg = err(&format!("[camera]\nfvo = 40.0\n{MINIMAL}"));
    assert!(msg.contains("line 2") && msg.contains("`fvo`"), "{msg}");
}

#[test]
fn wrong_type_names_line() {
    let msg = err(&format!("[camera]\nfov = \"wide\"\n{MINIMAL}"));
    assert!(msg.contains("line 2"), "{msg}");
}

#[test]
fn unknown_shape_and_light_type() {
    let msg = err(&MINIMAL.replace("\"quad\"", "\"cone\""));
    assert!(msg.contains("line 8") && msg.contains("cone"), "{msg}");
    let msg = err(&MINIMAL.replace("\"point\"", "\"laser\""));
    assert!(msg.contains("line 3") && msg.contains("laser"), "{msg}");
}

#[test]
fn key_of_another_shape_is_rejected() {
    let msg = err(&MINIMAL.replace("shape = \"quad\"", "shape = \"quad\"\nradius = 2.0"));
    // Object-level checks point at the object's `[[object]]` line.
    assert!(
        msg.contains("line 7") && msg.contains("`radius` does not apply"),
        "{msg}"
    );
}

#[test]
fn unknown_material() {
    let msg = err(&MINIMAL.replace("shape = \"quad\"", "shape = \"quad\"\nmaterial = \"gold\""));
    assert!(msg.contains("unknown material 'gold'"), "{msg}");
}

#[test]
fn impossible_parameters() {
    let energy = format!("[materials.default]\ndiffuse = 0.7\nspecular = 0.5\n{MINIMAL}");
    assert!(err(&energy).contains("create energy"), "{}", err(&energy));
    let rough = format!("[materials.default]\nroughness = 0.0\n{MINIMAL}");
    assert!(err(&rough).contains("roughness must be positive"));
    let power = MINIMAL.replace("power = 10.0", "power = -1.0");
    assert!(err(&power).contains("non-negative"), "{}", err(&power));
    let both = MINIMAL.replace("power = 10.0", "power = 1.0\nintensity = 1.0");
    assert!(err(&both).contains("exactly one"));
    let cam = format!("[camera]\neye = [0.0, 0.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n{MINIMAL}");
    assert!(err(&cam).contains("coincide"));
    let spacing = MINIMAL.replace("shape = \"quad\"", "shape = \"quad\"\nspacing = -1.0");
    assert!(err(&spacing).contains("spacing must be positive"));
    let lobes = format!("[bake]\nlobes = 12\n{MINIMAL}");
    assert!(err(&lobes).contains("lobes must be within 1..=8"));
}

#[test]
fn empty_scene_is_an_error() {
    assert!(err("").contains("no splats"));
    assert!(err("[[object]]\nshape = \"quad\"\n").contains("no lights"));
}

#[test]
fn missing_model_file_names_path() {
    let msg = err(&MINIMAL.replace("shape = \"quad\"", "shape = \"model\"\npath = \"nope.ply\""));
    assert!(msg.contains("scenes/nope.ply"), "{msg}");
}

#[test]
fn transforms_apply_in_order() {
    // A box scaled 0.5 then rotated 90° about y then moved up: bounds follow.
    let text = MINIMAL.replace(
        "shape = \"quad\"",
        "shape = \"box\"\nscale = [0.5, 0.25, 1.0]\nrotate = [0.0, 90.0, 0.0]\ntranslate = [0.0, 2.0, 0.0]\nspacing = 0.05",
    );
    let s = scene::parse(Path::new("t.toml"), &text).unwrap();
    let centers = s.splats.iter().map(|s| glam::Vec3::from(s.center));
    let (lo, hi) = centers.fold(
        (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY),
        |(l, h), c| (l.min(c), h.max(c)),
    );
    // After the rotation the x extent is the old z extent (1) and z is the old x (0.5).
    assert!(
        (hi.x - 1.0).abs() < 1e-4 && (lo.x + 1.0).abs() < 1e-4,
        "{lo} {hi}"
    );
    assert!(
        (hi.z - 0.5).abs() < 1e-4 && (hi.y - 2.25).abs() < 1e-4,
        "{lo} {hi}"
    );
    // Normals point outwards.
    for sp in &s.splats {
        let d = glam::Vec3::from(sp.center) - glam::Vec3::new(0.0, 2.0, 0.0);
        assert!(d.dot(sp.normal.into()) > 0.0);
    }
}

/// A spacing or size that would make billions of splats, or splats of radius 0, is refused
/// with the object's line before anything is allocated.
#[test]
fn impossible_sizes_are_refused_before_allocating() {
    let huge = MINIMAL.replace("shape = \"quad\"", "shape = \"quad\"\nspacing = 1e-7");
    let e = err(&huge);
    assert!(e.contains("line") && e.contains("spacing"), "{e}");
    let sphere = MINIMAL.replace("shape = \"quad\"", "shape = \"sphere\"\nradius = 1e-30");
    let e = err(&sphere);
    assert!(e.contains("degenerate splat"), "{e}");
    let scaled = MINIMAL.replace("shape = \"quad\"", "shape = \"box\"\nscale = 1e30");
    let e = err(&scaled);
    assert!(e.contains("splats") || e.contains("degenerate"), "{e}");
}

/// A path that is no regular file is refused at once with its name: a device such as
/// `/dev/zero` would otherwise be read for ever, a directory is no input.
#[cfg(unix)]
#[test]
fn paths_that_are_not_regular_files_are_refused() {
    let model = err(&MINIMAL.replace(
        "shape = \"quad\"",
        "shape = \"model\"\npath = \"/dev/zero\"",
    ));
    assert!(model.contains("/dev/zero"), "{model}");
    assert!(model.contains("not a regular file"), "{model}");
    for path in ["/dev/zero", "scenes"] {
        let msg = scene::load(Path::new(path)).unwrap_err().to_string();
        assert!(
            msg.contains(path) && msg.contains("not a regular file"),
            "{msg}"
        );
    }
}

/// A byte-order mark before an OBJ's or a text cloud's first line is read past, not reported
/// as an unknown statement; a 1 MB token in a text cloud's bad line is cut in the middle of the
/// message, which keeps the file and line.
#[test]
fn a_byte_order_mark_is_read_past_and_a_long_token_is_cut() {
    use lobelight::scene::model::{obj, text};
    let path = Path::new("bom.obj");
    let mesh = obj::parse(
        path,
        "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".as_bytes(),
    );
    assert_eq!(mesh.unwrap().faces.len(), 1);
    let cloud = text::parse(
        Path::new("bom.xyz"),
        "\u{feff}0 0 0\n1 0 0\n0 1 0\n".as_bytes(),
        &strict(),
    );
    assert_eq!(cloud.unwrap().positions.len(), 3);
    let long = format!("0 0 0\n{} 1 2\n", "q".repeat(1 << 20));
    let e = text::parse(Path::new("long.xyz"), long.as_bytes(), &strict());
    let e = e.unwrap_err().to_string();
    assert!(e.starts_with("long.xyz: line 2: `qqq"), "{}", &e[..100]);
    assert!(e.len() < 1000, "{} bytes of message", e.len());
    assert!(e.contains("characters cut"), "{e}");
}

/// A light whose power overflows f32 once multiplied out (an intensity times 4π) is named at
/// its line, not summed into "the scene's lights emit no power".
#[test]
fn a_light_whose_power_overflows_is_named() {
    let text = MINIMAL.replace("power = 10.0", "intensity = 3e38");
    let e = err(&text);
    assert!(e.contains("scenes/bad.toml: line 2: light #1"), "{e}");
    assert!(e.contains("past what f32 holds"), "{e}");
}

/// A colour of two numbers says what a colour is, at its line.
#[test]
fn a_colour_of_two_numbers_says_what_a_colour_is() {
    let text = format!("{MINIMAL}\n[materials.default]\ndiffuse = [0.5, 0.5]\n");
    let e = err(&text);
    assert!(e.contains("line 11"), "{e}");
    assert!(
        e.contains("a colour is one number (grey) or three, [r, g, b]: got 2"),
        "{e}"
    );
}

/// A search radius that makes the indirect light vanish (past the scene's size, or a
/// millionth of it) is refused with the key and the range that suits the scene.
#[test]
fn a_search_radius_out_of_scale_gives_the_range() {
    for radius in ["1e30", "1e-9"] {
        let text = format!("{MINIMAL}\n[bake]\nradius = {radius}\n");
        let e = err(&text);
        assert!(e.contains("[bake]: radius"), "{e}");
        assert!(e.contains("suits it") && e.contains("the default"), "{e}");
    }
    let fine = format!("{MINIMAL}\n[bake]\nradius = 0.05\n");
    assert!(scene::parse(Path::new("fine.toml"), &fine).is_ok());
}

/// An orbit of 1e38 degrees names `degrees` and its range, not the camera's vectors.
#[test]
fn an_orbit_out_of_range_names_degrees() {
    let base = scene::parse(Path::new("s.toml"), MINIMAL).unwrap().camera;
    let views = |text: &str| scene::views::parse(Path::new("v.toml"), text, &base);
    let e = views("[orbit]\nframes = 8\ndegrees = 1e38\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("v.toml: orbit: degrees = 1") && e.contains("36000"),
        "{e}"
    );
    assert!(!e.contains("eye"), "{e}");
    let e = views("[orbit]\nframes = 8\naxis = [0, 0, 0]\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("axis"), "{e}");
    assert_eq!(
        views("[orbit]\nframes = 8\ndegrees = 720\n").unwrap().len(),
        8
    );
}
