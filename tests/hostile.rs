//! Hostile inputs: valid PLY (meshes, clouds, Gaussian splats), OBJ, text cloud, LAS/LAZ, E57
//! and scene files, truncated, with bytes overwritten or
//! inserted, with header counts and numbers replaced by huge, negative, NaN or infinite ones
//! (property tests). Whatever comes in, the loaders give a clear error or a sanitised result
//! (finite splats with positive radii and unit normals), never a panic, and what they build is
//! bounded by the file's size.

mod common;

use std::path::Path;

use lobelight::scene;
use lobelight::scene::model::{Mesh, Reading, lidar, obj, ply, scan, text, to_splats};
use proptest::prelude::*;

/// The default reading: a bad point is skipped and counted.
fn lenient() -> Reading {
    Reading {
        strict: false,
        ..Reading::current()
    }
}

/// Writes each starting file into its fuzz target's corpus folder under `dir`.
fn write_seeds(dir: &Path) {
    let colour = |k: usize| [0.1 * (k % 10) as f32, 0.5, 0.9];
    let sphere = common::fibonacci_sphere(30);
    let byte_colour = |k: usize| [k as u8, 20, 30];
    let seeds: Vec<(&str, &str, Vec<u8>)> = vec![
        ("ply", "ascii.ply", ply_file("ascii")),
        ("ply", "binary.ply", ply_file("binary_little_endian")),
        (
            "ply",
            "3dgs.ply",
            common::gaussian_ply(&sphere, false, &colour),
        ),
        (
            "ply",
            "2dgs.ply",
            common::gaussian_ply(&sphere, true, &colour),
        ),
        ("obj", "quad.obj", OBJ.into()),
        ("text", "leica.pts", PTS.into()),
        ("text", "normals.xyz", XYZ.into()),
        ("las", "sphere.las", common::write_las(&sphere, None, false)),
        ("las", "sphere.laz", common::write_las(&sphere, None, true)),
        (
            "e57",
            "sphere.e57",
            common::write_e57(&[(sphere.clone(), [0.0; 3])], &byte_colour),
        ),
        ("scene", "scene.toml", SCENE.into()),
        (
            "views",
            "orbit.toml",
            b"[orbit]\nframes = 4\ndegrees = 90\n".to_vec(),
        ),
        (
            "views",
            "views.toml",
            b"[[view]]\neye = [0, 1, 3]\n\n[[view]]\nfov = 30\n".to_vec(),
        ),
    ];
    for (target, name, bytes) in seeds {
        let folder = dir.join(target);
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join(name), bytes).unwrap();
    }
}

/// Values an attacker would try where a number goes.
const HOSTILE: [&str; 14] = [
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0",
    "1e-30",
    "1e30",
    "-1e30",
    "1e9",
    "4294967295",
    "18446744073709551616",
    "x",
    "",
];

/// A tetrahedron with colours, as PLY in `format`.
fn ply_file(format: &str) -> Vec<u8> {
    let v = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let f = [[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut out = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for (k, p) in v.iter().enumerate() {
        if format == "ascii" {
            out.extend(format!("{} {} {} 200 {} 30\n", p[0], p[1], p[2], 60 * k).bytes());
        } else {
            p.iter().for_each(|x| out.extend(x.to_le_bytes()));
            out.extend([200, 60 * k as u8, 30]);
        }
    }
    for t in f {
        if format == "ascii" {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        } else {
            out.push(3);
            t.iter().for_each(|i| out.extend((*i as i32).to_le_bytes()));
        }
    }
    out
}

const OBJ: &str = "# a quad and a triangle\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\n\
v 0 1 0 1 1 1\nv 0.5 0.5 1 0.5 0.5 0.5\nvn 0 0 1\nf 1 2 3 4\nf 1//1 2//1 5//1\nf -1 -2 -3\n";

/// A Leica `.pts` cloud: count line, then x y z intensity r g b.
const PTS: &str = "5\n0 0 0 -100 10 20 30\n1 0 0 -90 40 50 60\n0 1 0 -80 70 80 90\n\
1 1 0 -70 100 110 120\n0.5 0.5 0.1 -60 130 140 150\n";

/// An `.xyz` cloud with normals and colours, comma-separated.
const XYZ: &str = "# x,y,z,nx,ny,nz,r,g,b\n0,0,0,0,0,1,10,20,30\n1,0,0,0,0,1,40,50,60\n\
0,1,0,0,0,1,70,80,90\n1,1,0,0,0,1,100,110,120\n0.5,0.5,0.05,0,0,1,130,140,150\n";

const SCENE: &str = r#"[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0
resolution = [64, 48]

[materials.white]
diffuse = [0.8, 0.8, 0.8]

[materials.gloss]
diffuse = [0.2, 0.2, 0.2]
specular = [0.5, 0.5, 0.5]
roughness = 0.1

[[light]]
type = "point"
position = [0.0, 0.9, 0.0]
power = [10.0, 10.0, 10.0]

[bake]
photons = 1000

[[object]]
shape = "box"
material = "white"
scale = [1.0, 1.0, 1.0]
spacing = 0.2

[[object]]
shape = "sphere"
material = "gloss"
radius = 0.3
translate = [0.2, -0.5, 0.1]
spacing = 0.1
"#;

/// `cases` cases from a fixed seed (the same inputs every run, so CI is reproducible);
/// failures are reported, not written to a regressions file.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6c6f_6265),
        ..ProptestConfig::default()
    }
}

/// The unmutated files load: the properties below see the success path too. With
/// `LOBELIGHT_FUZZ_SEEDS=DIR` they are written as the fuzz targets' first corpus, one folder
/// a target (the kept corpus, `fuzz/corpus/*.tar.gz`, began with them).
#[test]
fn the_files_the_mutations_start_from_load() {
    if let Some(dir) = std::env::var_os("LOBELIGHT_FUZZ_SEEDS") {
        write_seeds(Path::new(&dir));
    }
    for format in ["ascii", "binary_little_endian"] {
        let mesh = ply::parse(Path::new("t.ply"), &ply_file(format), &lenient()).unwrap();
        assert_eq!(to_splats(&mesh, Path::new("t.ply")).unwrap().disks.len(), 4);
    }
    let mesh = obj::parse(Path::new("t.obj"), OBJ.as_bytes()).unwrap();
    assert!(to_splats(&mesh, Path::new("t.obj")).unwrap().disks.len() >= 4);
    for laz in [false, true] {
        let bytes = common::write_las(&common::fibonacci_sphere(40), None, laz);
        let mesh = lidar::parse(Path::new("t.las"), bytes, &lenient()).unwrap();
        assert_eq!(
            to_splats(&mesh, Path::new("t.las")).unwrap().disks.len(),
            40
        );
    }
    for (name, text) in [("t.pts", PTS), ("t.xyz", XYZ)] {
        let mesh = text::parse(Path::new(name), text.as_bytes(), &lenient()).unwrap();
        assert_eq!(to_splats(&mesh, Path::new(name)).unwrap().disks.len(), 5);
    }
    let s = scene::parse(Path::new("t.toml"), SCENE).unwrap();
    assert!(s.splats.len() > 100);
}

/// One change to a file's bytes.
#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    Overwrite(usize, u8),
    Insert(usize, Vec<u8>),
    /// Replace the k-th number-like token with one of `HOSTILE`.
    Number(usize, usize),
    /// Drop the k-th line.
    DropLine(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(at, b)| Mutation::Overwrite(at, b)),
        (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(at, b)| Mutation::Insert(at, b)),
        (any::<usize>(), 0..HOSTILE.len()).prop_map(|(k, h)| Mutation::Number(k, h)),
        any::<usize>().prop_map(Mutation::DropLine),
    ]
}

/// Where the number-like tokens of `bytes` are (runs of digits, signs, dots and exponents).
fn numbers(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &b) in bytes.iter().enumerate() {
        let numeric = b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.' | b'e');
        match (numeric, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    out
}

fn apply(bytes: &[u8], m: &Mutation) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if bytes.is_empty() {
        return out;
    }
    match m {
        Mutation::Truncate(at) => out.truncate(at % (bytes.len() + 1)),
        Mutation::Overwrite(at, b) => {
            let i = at % bytes.len();
            out[i] = *b;
        }
        Mutation::Insert(at, b) => {
            let i = at % (bytes.len() + 1);
            out.splice(i..i, b.iter().copied());
        }
        Mutation::Number(k, h) => {
            let tokens = numbers(bytes);
            if let Some(&(s, e)) = tokens.get(k % tokens.len().max(1)) {
                out.splice(s..e, HOSTILE[*h].bytes());
            }
        }
        Mutation::DropLine(k) => {
            let lines: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
            let k = k % lines.len();
            out = lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .flat_map(|(_, l)| l.iter().copied().chain([b'\n']))
                .collect();
        }
    }
    out
}

/// A parsed mesh is bounded by its file and its splats are sane.
fn check_mesh(mesh: &Mesh, size: usize) -> Result<(), TestCaseError> {
    prop_assert!(
        mesh.positions.len() <= size,
        "{} vertices",
        mesh.positions.len()
    );
    prop_assert!(mesh.faces.len() <= size, "{} faces", mesh.faces.len());
    if let Ok(set) = to_splats(mesh, Path::new("fuzz")) {
        for d in &set.disks {
            prop_assert!(d.center.is_finite(), "{d:?}");
            prop_assert!(d.radius.is_finite() && d.radius > 0.0, "{d:?}");
            prop_assert!((d.normal.length() - 1.0).abs() < 1e-3, "{d:?}");
        }
        if let Some(c) = &set.colors {
            prop_assert!(c.iter().flatten().all(|x| x.is_finite()));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(4096))]

    #[test]
    fn mutated_ply_is_an_error_or_a_sane_mesh(
        binary in any::<bool>(),
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let mut bytes = ply_file(if binary { "binary_little_endian" } else { "ascii" });
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = ply::parse(Path::new("fuzz.ply"), &bytes, &lenient()) {
            check_mesh(&mesh, bytes.len())?;
        }
    }

    #[test]
    fn mutated_obj_is_an_error_or_a_sane_mesh(
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let mut bytes = OBJ.as_bytes().to_vec();
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = obj::parse(Path::new("fuzz.obj"), &bytes) {
            check_mesh(&mesh, bytes.len())?;
        }
    }

    #[test]
    fn mutated_text_cloud_is_an_error_or_a_sane_mesh(
        pts in any::<bool>(),
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let (name, mut bytes) = if pts {
            ("fuzz.pts", PTS.as_bytes().to_vec())
        } else {
            ("fuzz.xyz", XYZ.as_bytes().to_vec())
        };
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = text::parse(Path::new(name), &bytes, &lenient()) {
            check_mesh(&mesh, bytes.len())?;
        }
    }

    #[test]
    fn mutated_gaussian_ply_is_an_error_or_a_sane_mesh(
        two_d in any::<bool>(),
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let colour = |k: usize| [0.1 * (k % 10) as f32, 0.5, 0.9];
        let mut bytes = common::gaussian_ply(&common::fibonacci_sphere(30), two_d, &colour);
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = ply::parse(Path::new("fuzz.ply"), &bytes, &lenient()) {
            check_mesh(&mesh, bytes.len())?;
        }
    }

    #[test]
    fn mutated_e57_is_an_error_or_a_sane_mesh(
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let colour = |k: usize| [k as u8, 20, 30];
        let mut bytes = common::write_e57(&[(common::fibonacci_sphere(30), [0.0; 3])], &colour);
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = scan::parse(Path::new("fuzz.e57"), bytes.clone(), &lenient()) {
            check_mesh(&mesh, bytes.len())?;
        }
    }

    #[test]
    fn mutated_las_is_an_error_or_a_sane_mesh(
        laz in any::<bool>(),
        changes in proptest::collection::vec(mutation(), 1..4),
    ) {
        let colour = |k: usize| [k as u16 * 1000, 2000, 3000];
        let pts = common::fibonacci_sphere(40);
        let mut bytes = common::write_las(&pts, Some(&colour), laz);
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        if let Ok(mesh) = lidar::parse(Path::new("fuzz.las"), bytes.clone(), &lenient()) {
            // A LAZ record may pack into a byte or two: bound by the file's size in points.
            check_mesh(&mesh, 8 * bytes.len())?;
        }
    }
}

proptest! {
    #![proptest_config(config(2048))]

    #[test]
    fn mutated_scene_is_an_error_or_a_sane_scene(
        changes in proptest::collection::vec(mutation(), 1..3),
    ) {
        let mut bytes = SCENE.as_bytes().to_vec();
        for m in &changes {
            bytes = apply(&bytes, m);
        }
        let Ok(text) = String::from_utf8(bytes) else {
            return Ok(()); // the loader reads text; invalid UTF-8 is refused when read
        };
        match scene::parse(Path::new("fuzz.toml"), &text) {
            Ok(s) => {
                prop_assert!(s.splats.len() as u64 <= 2 * scene::MAX_OBJECT_SPLATS);
                for p in &s.splats {
                    prop_assert!(p.center.iter().all(|x| x.is_finite()), "{p:?}");
                    prop_assert!(p.radius.is_finite() && p.radius > 0.0, "{p:?}");
                    let n = glam::Vec3::from(p.normal);
                    prop_assert!((n.length() - 1.0).abs() < 1e-3, "{p:?}");
                    prop_assert!(p.diffuse.iter().all(|x| x.is_finite() && *x >= 0.0), "{p:?}");
                    prop_assert!((p.material as usize) < s.materials.len());
                }
                for l in &s.lights {
                    prop_assert!(l.position.iter().chain(&l.power).all(|x| x.is_finite()));
                }
                for m in &s.materials {
                    prop_assert!(m.specular.iter().all(|x| x.is_finite() && *x >= 0.0));
                    prop_assert!(m.roughness.is_finite() && m.roughness > 0.0, "{m:?}");
                }
            }
            Err(e) => {
                // A clear error names the file.
                prop_assert!(e.to_string().contains("fuzz.toml"), "{e}");
            }
        }
    }
}
