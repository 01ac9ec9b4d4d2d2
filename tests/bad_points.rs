//! Scans as tools write them: a bad point is skipped and counted (the first named by its line)
//! unless `--strict`; which columns a text cloud holds is read from its header or its values;
//! and what a loader refuses says why in the user's words (which rule dropped the Gaussians,
//! a count too large, a number out of f32's range, CR line ends, an offset past the end).

mod common;

use std::path::PathBuf;
use std::process::Command;

use glam::Vec3;
use lobelight::scene::model::{self, Reading, gaussians};

fn tmp(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lobelight-bad-points-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn strict() -> Reading {
    Reading {
        strict: true,
        ..Reading::current()
    }
}

fn err_of(name: &str, bytes: &[u8]) -> String {
    model::load(&tmp(name, bytes)).unwrap_err().to_string()
}

/// A 100-point sphere as an `.xyz` file, with line `bad` (1-based) replaced by `with`.
fn sphere_xyz(bad: usize, with: &str) -> String {
    let mut text = String::new();
    for (k, p) in common::fibonacci_sphere(100).iter().enumerate() {
        match k + 1 == bad {
            true => text += &format!("{with}\n"),
            false => text += &format!("{} {} {}\n", p.x, p.y, p.z),
        }
    }
    text
}

/// One `nan nan nan` line, a word, a short line and a coordinate of 1e300 in a 100-point scan
/// are each skipped and counted, the first named by its line; `--strict` refuses the file at
/// that line; a file of bad points only is an error that says so.
#[test]
fn a_bad_point_is_skipped_and_counted_unless_strict() {
    for (with, why) in [
        ("nan nan nan", "not a finite number"),
        ("0.5 zero 0.1", "`zero` is not a number"),
        ("0.5 0.2", "2 numbers, but the file's points have 3"),
        ("1e300 0 0", "1e300 is out of f32's range"),
    ] {
        let path = tmp("scan.xyz", sphere_xyz(57, with).as_bytes());
        let mesh = model::load(&path).unwrap_or_else(|e| panic!("{with}: {e}"));
        assert_eq!(mesh.positions.len(), 99, "{with}");
        assert_eq!(mesh.left_out.skipped, 1, "{with}");
        let first = mesh.left_out.first_skipped.clone().unwrap();
        assert!(
            first.contains("line 57") && first.contains(why),
            "{with}: {first}"
        );
        let e = model::load_with(&path, &strict()).unwrap_err().to_string();
        assert!(
            e.contains("scan.xyz: line 57") && e.contains(why),
            "{with}: {e}"
        );
    }
    let e = err_of("all_bad.xyz", b"nan 0 0\ninf 1 2\n");
    assert!(
        e.contains("no point of the file is kept: 2 could not be read") && e.contains("line 1"),
        "{e}"
    );
    // PLY, ASCII and binary: a vertex not finite or not a number is skipped.
    let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n0 0 0\n1 x 0\n0 1 0\n";
    let mesh = model::load(&tmp("word.ply", ascii.as_bytes())).unwrap();
    assert_eq!((mesh.positions.len(), mesh.left_out.skipped), (2, 1));
    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                       property float y\nproperty float z\nend_header\n"
        .to_vec();
    for v in [0.0, 0.0, 0.0, f32::NAN, 1.0, 0.0, 0.0, 1.0, 0.0f32] {
        binary.extend(v.to_le_bytes());
    }
    let mesh = model::load(&tmp("nan.ply", &binary)).unwrap();
    assert_eq!((mesh.positions.len(), mesh.left_out.skipped), (2, 1));
    let first = mesh.left_out.first_skipped.unwrap();
    assert!(first.contains("element vertex #1"), "{first}");
    // A mesh's bad vertex is an error: skipping it would shift its faces' indices.
    let with_face = ascii.replace(
        "property float z\nend_header",
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header",
    ) + "3 0 1 2\n";
    let e = err_of("mesh.ply", with_face.as_bytes());
    assert!(
        e.contains("element vertex #1") && e.contains("not a number"),
        "{e}"
    );
}

/// `info --json` reports the skipped points per object and the first; `render --stats` and the
/// warning on stderr say how many; `--strict` refuses the scene at the bad line.
#[test]
fn the_commands_report_skipped_points() {
    let cloud = tmp("cli.xyz", sphere_xyz(12, "nan 0 0").as_bytes());
    let scene = tmp(
        "cli.toml",
        format!(
            "[camera]\neye = [0, 0, 4]\ntarget = [0, 0, 0]\n\n[[light]]\ntype = \"point\"\n\
             position = [0, 0, 3]\npower = 10\n\n[[object]]\nshape = \"model\"\npath = {:?}\n",
            cloud.display().to_string()
        )
        .as_bytes(),
    );
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let run = |args: &[&str]| Command::new(exe).args(args).output().unwrap();
    let out = run(&["info", scene.to_str().unwrap(), "--cpu", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let object = &info["objects"][0];
    assert_eq!(object["skipped"], 1, "{object}");
    let first = object["first_skipped"].as_str().unwrap();
    assert!(first.contains("cli.xyz: line 12"), "{first}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: skipped 1 model points"),
        "{stderr}"
    );
    let image = scene.with_extension("png");
    let out = run(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        image.to_str().unwrap(),
        "--cpu",
        "--width",
        "32",
        "--height",
        "32",
        "--photons",
        "2000",
        "--stats",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("skipped  1 model points"), "{stderr}");
    let out = run(&["info", scene.to_str().unwrap(), "--cpu", "--strict"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cli.xyz: line 12"), "{stderr}");
}

/// Columns come from the values of many points, not the first: `x y z r g b` whose first point
/// is black reads colours; a header names the columns in any order; colours of fractions read
/// as such; columns that are neither are named.
#[test]
fn text_cloud_columns_come_from_header_and_values() {
    let pts = common::fibonacci_sphere(200);
    let line = |p: &Vec3, rest: &str| format!("{} {} {} {rest}\n", p.x, p.y, p.z);
    let mut black_first = String::new();
    let mut fractions = String::new();
    let mut named = String::from("//X,Y,Z,Nx,Ny,Nz,R,G,B\n");
    for (k, p) in pts.iter().enumerate() {
        let c = if k == 0 {
            [0; 3]
        } else {
            [200, 100, (k % 256) as u32]
        };
        black_first += &line(p, &format!("{} {} {}", c[0], c[1], c[2]));
        fractions += &line(p, &format!("{} 0.5 0.25", c[0] as f32 / 255.0));
        named += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            p.x, p.y, p.z, p.x, p.y, p.z, c[0], c[1], c[2]
        );
    }
    let mesh = model::load(&tmp("black.xyz", black_first.as_bytes())).unwrap();
    assert!(mesh.normals.is_none());
    let colours = mesh.colors.unwrap();
    assert_eq!(colours[0], [0.0; 3]);
    assert_eq!(colours[1], [200.0 / 255.0, 100.0 / 255.0, 1.0 / 255.0]);
    let mesh = model::load(&tmp("fractions.xyz", fractions.as_bytes())).unwrap();
    assert_eq!(mesh.colors.unwrap()[1], [200.0 / 255.0, 0.5, 0.25]);
    // The header first, or after a comment line.
    for text in [named.clone(), format!("# exported by a scanner\n{named}")] {
        let mesh = model::load(&tmp("named.xyz", text.as_bytes())).unwrap();
        assert_eq!(mesh.positions.len(), 200);
        assert_eq!(mesh.left_out.skipped, 0);
        assert!((mesh.normals.unwrap()[7] - pts[7]).length() < 1e-6);
        assert_eq!(mesh.colors.unwrap()[1][0], 200.0 / 255.0);
    }
    let e = err_of("neither.xyz", b"0 0 0 5 -3 2.5\n1 0 0 5 -3 2.5\n");
    assert!(
        e.contains("neither.xyz: line 1: columns 4–6 hold neither a normal"),
        "{e}"
    );
}

/// An ASCII Gaussian-splat PLY of `rows` (opacity logit, log scales, rotation w x y z).
fn gaussian_ascii(rows: &[(f32, [f32; 3], [f32; 4])]) -> String {
    let mut text = format!("ply\nformat ascii 1.0\nelement vertex {}\n", rows.len());
    for n in [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2", "rot_3",
    ] {
        text += &format!("property float {n}\n");
    }
    text += "end_header\n";
    for (k, (opacity, s, q)) in rows.iter().enumerate() {
        text += &format!(
            "{k} 0 0 0 0 0 {opacity} {} {} {} {} {} {} {}\n",
            s[0], s[1], s[2], q[0], q[1], q[2], q[3]
        );
    }
    text
}

/// A capture whose Gaussians are all dropped says which rule dropped how many.
#[test]
fn dropped_gaussians_are_counted_by_rule() {
    let ok_scale = [-3.0, -3.0, -7.0];
    let ok_rot = [1.0, 0.0, 0.0, 0.0];
    let mut rows = vec![(-2.0, ok_scale, ok_rot); 3];
    rows.extend([(3.0, ok_scale, [0.0; 4]); 2]);
    rows.push((3.0, [100.0, 100.0, 0.0], ok_rot));
    rows.push((3.0, [-200.0, -200.0, -200.0], ok_rot));
    let e = err_of("dropped.ply", gaussian_ascii(&rows).as_bytes());
    for part in [
        format!("3 {}", gaussians::FAINT),
        format!("2 {}", gaussians::NO_ROTATION),
        format!("1 {}", gaussians::HUGE),
        format!("1 {}", gaussians::NO_RADIUS),
    ] {
        assert!(e.contains(&part), "{part}\nin: {e}");
    }
    assert!(!e.contains("no vertices"), "{e}");
}

/// Degenerate clouds say what is wrong with them, not that faces are degenerate.
#[test]
fn degenerate_clouds_say_why() {
    let same = "1 2 3\n".repeat(50);
    let path = tmp("same.xyz", same.as_bytes());
    let e = model::to_splats(&model::load(&path).unwrap(), &path).unwrap_err();
    let e = e.to_string();
    assert!(e.contains("all 50 points are the one point"), "{e}");
    assert!(!e.contains("every face"), "{e}");
    let far: String = common::fibonacci_sphere(50)
        .iter()
        .map(|p| format!("{} {} {}\n", p.x * 1e30, p.y * 1e30, p.z * 1e30))
        .collect();
    let path = tmp("far.xyz", far.as_bytes());
    let e = model::to_splats(&model::load(&path).unwrap(), &path).unwrap_err();
    assert!(e.to_string().contains("too far for f32"), "{e}");
}

/// A count past 2^64 is too large, not "not a number"; a double of 1e300 is out of f32's range,
/// not infinite; an OBJ's too.
#[test]
fn numbers_out_of_range_say_so() {
    let big = "ply\nformat ascii 1.0\nelement vertex 18446744073709551616\nproperty float x\n\
               end_header\n";
    let e = err_of("big.ply", big.as_bytes());
    assert!(e.contains("line 3") && e.contains("is too large"), "{e}");
    let word = big.replace("18446744073709551616", "many");
    assert!(err_of("word.ply", word.as_bytes()).contains("is not a whole number"));
    let negative = big.replace("18446744073709551616", "-5");
    assert!(err_of("negative.ply", negative.as_bytes()).contains("`-5` is negative"));
    let mut double = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\n\
                       property double y\nproperty double z\nend_header\n"
        .to_vec();
    for v in [1e300, 0.0, 0.0f64] {
        double.extend(v.to_le_bytes());
    }
    let e = model::load_with(&tmp("double.ply", &double), &strict()).unwrap_err();
    let e = e.to_string();
    assert!(e.contains("1e300 is out of f32's range"), "{e}");
    assert!(!e.contains("inf"), "{e}");
    let e = err_of("far.obj", b"v 0 0 0\nv 1e300 0 0\n");
    assert!(
        e.contains("line 2") && e.contains("out of f32's range"),
        "{e}"
    );
}

/// A PLY with CR line ends alone (old Mac tools), ASCII and binary, reads as with LF.
#[test]
fn cr_line_ends_are_read() {
    let lf = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let want = model::load(&tmp("lf.ply", lf.as_bytes())).unwrap();
    for (name, text) in [
        ("cr.ply", lf.replace('\n', "\r")),
        ("crlf.ply", lf.replace('\n', "\r\n")),
    ] {
        let got = model::load(&tmp(name, text.as_bytes())).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(got.positions, want.positions, "{name}");
    }
    let mut binary = b"ply\rformat binary_little_endian 1.0\relement vertex 1\rproperty float x\r\
                       property float y\rproperty float z\rend_header\r"
        .to_vec();
    // The data's first byte is a line feed (10 = 0x0A): it belongs to the data.
    for v in [f32::from_le_bytes([10, 0, 128, 63]), 2.0, 3.0] {
        binary.extend(v.to_le_bytes());
    }
    let got = model::load(&tmp("cr_binary.ply", &binary)).unwrap();
    assert_eq!(got.positions[0].y, 2.0);
}

/// A LAS file whose point data would start or end past its last byte says where and how big
/// the file is, not "failed to fill whole buffer".
#[test]
fn las_offsets_past_the_end_give_the_size() {
    let good = common::write_las(&common::fibonacci_sphere(50), None, false);
    let mut moved = good.clone();
    let past = (good.len() as u32 + 1000).to_le_bytes();
    moved[96..100].copy_from_slice(&past);
    let e = err_of("moved.las", &moved);
    assert!(
        e.contains("past the file's end at byte") && e.contains(&good.len().to_string()),
        "{e}"
    );
    assert!(!e.contains("failed to fill"), "{e}");
}

/// A cloud that announces more points than the budget holds is refused before any is read.
#[test]
fn announced_points_past_the_budget_are_refused() {
    let budget = lobelight::budget::Budget {
        bytes: 1 << 20,
        source: lobelight::budget::Source::Flag,
    };
    let reading = Reading::within(budget);
    let text = sphere_xyz(0, "");
    let e = model::load_with(&tmp("big.xyz", text.repeat(40).as_bytes()), &reading);
    let e = e.unwrap_err().to_string();
    assert!(
        e.contains("past the budget") && e.contains("subsample"),
        "{e}"
    );
    let las = common::write_las(&common::fibonacci_sphere(5000), None, false);
    let e = model::load_with(&tmp("big.las", &las), &reading).unwrap_err();
    assert!(e.to_string().contains("past the budget"), "{e}");
}
