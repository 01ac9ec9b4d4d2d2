//! Model loading: every PLY encoding reads the same mesh, malformed files give an error naming
//! the file and element (never a panic or a huge allocation), meshes and point clouds become
//! splats that close the surface. No GPU needed.

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use lobelight::scene::model::{self, Mesh};

fn tmp(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lobelight-models-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A unit-sphere mesh: a latitude/longitude grid, quads split into triangles.
fn uv_sphere(rings: u32, segments: u32) -> Mesh {
    let mut m = Mesh::default();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
            m.positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    for i in 0..rings {
        for j in 0..segments {
            let a = i * segments + j;
            let b = i * segments + (j + 1) % segments;
            let (c, d) = (a + segments, b + segments);
            // Counter-clockwise seen from outside.
            m.faces.push([a, b, d]);
            m.faces.push([a, d, c]);
        }
    }
    m
}

fn ply_header(format: &str, m: &Mesh, colors: bool) -> String {
    let mut h = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\n",
        m.positions.len()
    );
    h += "property float x\nproperty float y\nproperty float z\n";
    if colors {
        h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    }
    h += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.faces.len()
    );
    h
}

fn write_ply(format: &str, m: &Mesh, colors: Option<&[[u8; 3]]>) -> Vec<u8> {
    let mut out = ply_header(format, m, colors.is_some()).into_bytes();
    let big = format == "binary_big_endian";
    let f32b = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let i32b = |v: i32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for (k, p) in m.positions.iter().enumerate() {
        if format == "ascii" {
            write!(out, "{} {} {}", p.x, p.y, p.z).unwrap();
            if let Some(c) = colors {
                write!(out, " {} {} {}", c[k][0], c[k][1], c[k][2]).unwrap();
            }
            out.push(b'\n');
        } else {
            for v in p.to_array() {
                out.extend(f32b(v));
            }
            if let Some(c) = colors {
                out.extend(c[k]);
            }
        }
    }
    for f in &m.faces {
        if format == "ascii" {
            writeln!(out, "3 {} {} {}", f[0], f[1], f[2]).unwrap();
        } else {
            out.push(3);
            for i in f {
                out.extend(i32b(*i as i32));
            }
        }
    }
    out
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn err_of(name: &str, bytes: &[u8]) -> String {
    let p = tmp(name, bytes);
    model::load(&p).unwrap_err().to_string()
}

#[test]
fn every_ply_encoding_reads_the_same_mesh() {
    let m = uv_sphere(8, 12);
    let colors: Vec<[u8; 3]> = (0..m.positions.len())
        .map(|k| [k as u8, 255 - k as u8, 128])
        .collect();
    let mut loaded = Vec::new();
    for (name, bytes) in [
        ("a.ply", write_ply("ascii", &m, Some(&colors))),
        (
            "le.ply",
            write_ply("binary_little_endian", &m, Some(&colors)),
        ),
        ("be.ply", write_ply("binary_big_endian", &m, Some(&colors))),
        (
            "gz.ply.gz",
            gzip(&write_ply("binary_little_endian", &m, Some(&colors))),
        ),
    ] {
        loaded.push((name, model::load(&tmp(name, &bytes)).unwrap()));
    }
    for (name, got) in &loaded {
        assert_eq!(got.faces, m.faces, "{name}");
        assert_eq!(got.positions.len(), m.positions.len(), "{name}");
        for (a, b) in got.positions.iter().zip(&m.positions) {
            // ASCII goes through decimal text: shortest round-trip formatting is exact.
            assert_eq!(a, b, "{name}");
        }
        let c = got.colors.as_ref().expect("colours");
        assert_eq!(c[3], [3.0 / 255.0, 252.0 / 255.0, 128.0 / 255.0], "{name}");
    }
}

#[test]
fn truncated_ply_names_the_element() {
    let m = uv_sphere(4, 6);
    let bin = write_ply("binary_little_endian", &m, None);
    let msg = err_of("trunc.ply", &bin[..bin.len() - 7]);
    assert!(
        msg.contains("trunc.ply: element face #") && msg.contains("truncated"),
        "{msg}"
    );
    let ascii = write_ply("ascii", &m, None);
    let cut = String::from_utf8(ascii).unwrap();
    let cut = &cut[..cut.find("\n3 ").unwrap()]; // drop all faces
    let msg = err_of("trunc_ascii.ply", cut.as_bytes());
    assert!(
        msg.contains("element face #0") && msg.contains("truncated"),
        "{msg}"
    );
}

#[test]
fn lying_header_count_is_refused_before_allocating() {
    let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
    let msg = err_of("huge.ply", text.as_bytes());
    assert!(
        msg.contains("element vertex") && msg.contains("more than the 4 bytes"),
        "{msg}"
    );
}

#[test]
fn nan_coordinates_name_the_vertex() {
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 nan 0\n0 1 0\n";
    let path = tmp("nan.ply", text.as_bytes());
    let mesh = model::load(&path).unwrap();
    assert_eq!((mesh.positions.len(), mesh.left_out.skipped), (2, 1));
    let strict = model::Reading {
        strict: true,
        ..model::Reading::current()
    };
    let msg = model::load_with(&path, &strict).unwrap_err().to_string();
    for msg in [&msg, mesh.left_out.first_skipped.as_ref().unwrap()] {
        assert!(
            msg.contains("element vertex #1 (line 9)") && msg.contains("not a finite number"),
            "{msg}"
        );
    }
}

#[test]
fn malformed_ply_headers() {
    let cases: [(&str, &str); 5] = [
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
            "unknown property type `quad`",
        ),
        ("ply\nformat xml 1.0\nend_header\n", "unknown format `xml`"),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
            "before `end_header`",
        ),
        ("PLY file\n", "not a PLY file"),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3 4\n",
            "extra value",
        ),
    ];
    for (text, want) in cases {
        let msg = err_of("h.ply", text.as_bytes());
        assert!(msg.contains(want), "{want}: {msg}");
    }
}

#[test]
fn face_index_out_of_range() {
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    let msg = err_of("idx.ply", text.as_bytes());
    assert!(
        msg.contains("face #0") && msg.contains("out of range"),
        "{msg}"
    );
}

#[test]
fn garbage_obj_is_refused() {
    let msg = err_of("garbage.obj", b"hello world\nthis is not a model\n");
    assert!(
        msg.contains("garbage.obj: line 1: unknown statement `hello`"),
        "{msg}"
    );
    let msg = err_of("binary.obj", &[0x7f, b'E', b'L', b'F', 0xff, 0xfe, 0, 1, 2]);
    assert!(msg.contains("not a text file"), "{msg}");
    let msg = err_of("bad_number.obj", b"v 0 0 0\nv 1 x 0\n");
    assert!(
        msg.contains("line 2") && msg.contains("`x` is not a number"),
        "{msg}"
    );
    let msg = err_of("bad_face.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert!(
        msg.contains("line 4") && msg.contains("out of range"),
        "{msg}"
    );
    let msg = err_of("empty.obj", b"# nothing\n");
    assert!(msg.contains("no vertices"), "{msg}");
    let msg = err_of("model.stl", b"solid x\n");
    assert!(msg.contains("unknown model format"), "{msg}");
}

#[test]
fn obj_colours_quads_and_relative_indices() {
    let text = "# a quad\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nvn 0 0 1\nf -4//1 -3//1 -2//1 -1//1\n";
    let m = model::load(&tmp("quad.obj", text.as_bytes())).unwrap();
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.colors.as_ref().unwrap()[1], [0.0, 1.0, 0.0]);
    let s = model::to_splats(&m, Path::new("quad.obj")).unwrap();
    assert_eq!(s.disks.len(), 4);
    for d in &s.disks {
        assert!((d.normal - Vec3::Z).length() < 1e-6, "{:?}", d.normal);
    }
    // sRGB 1.0 stays 1.0 in linear; the file's colours become per-splat albedo.
    assert_eq!(s.colors.as_ref().unwrap()[3], [1.0, 1.0, 1.0]);
    assert!((model::srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
}

/// Whether `q` lies on some disk (within `slab` of its plane).
fn covered(q: Vec3, disks: &[lobelight::scene::shapes::Disk], slab: f32) -> bool {
    disks.iter().any(|d| {
        let v = q - d.center;
        let h = v.dot(d.normal);
        h.abs() <= slab && v.length_squared() - h * h <= d.radius * d.radius
    })
}

#[test]
fn mesh_splats_cover_every_triangle() {
    let m = uv_sphere(24, 36);
    let s = model::to_splats(&m, Path::new("sphere")).unwrap();
    assert_eq!(s.dropped, 0);
    let mut rng = common::Rng(3);
    for k in 0..4000 {
        let f = m.faces[k % m.faces.len()];
        let (mut a, mut b) = (rng.f32(), rng.f32());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let [p0, p1, p2] = f.map(|i| m.positions[i as usize]);
        let q = p0 + a * (p1 - p0) + b * (p2 - p0);
        // The three corner splats of the triangle must cover it (disks tilt with the surface:
        // allow the sagitta of the sphere's curvature across a triangle).
        let corners: Vec<_> = f.iter().map(|&i| s.disks[i as usize]).collect();
        assert!(
            covered(q, &corners, 0.02),
            "point {q} of face {f:?} is in a hole"
        );
    }
    // Outward normals: area-weighted normals of a CCW mesh point away from the centre.
    for d in &s.disks {
        assert!(d.normal.dot(d.center.normalize()) > 0.95);
    }
}

#[test]
fn procedural_shapes_have_no_holes() {
    use lobelight::scene::shapes;
    let m = glam::Affine3A::from_scale_rotation_translation(
        Vec3::new(0.7, 1.3, 0.4),
        glam::Quat::from_rotation_y(0.3) * glam::Quat::from_rotation_x(0.2),
        Vec3::new(0.1, 0.2, 0.3),
    );
    let mut rng = common::Rng(5);
    let mut disks = Vec::new();
    shapes::cube(&m, 0.05, &mut disks);
    for _ in 0..3000 {
        // A random point on a random face of the cube.
        let face = (rng.next_u64() % 6) as usize;
        let mut p = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        p[face / 2] = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
        let q = m.transform_point3(p.into());
        assert!(covered(q, &disks, 1e-4), "cube point {q} is in a hole");
    }
    let mut disks = Vec::new();
    let sphere = glam::Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.0));
    shapes::sphere(&sphere, 0.5, 0.03, &mut disks);
    for _ in 0..3000 {
        let q = Vec3::new(1.0, 0.0, 0.0) + 0.5 * Vec3::from(rng.unit_vector());
        assert!(covered(q, &disks, 0.01), "sphere point {q} is in a hole");
    }
}

#[test]
fn point_cloud_gets_oriented_pca_normals_and_closing_radii() {
    // A Fibonacci sphere of radius 2 as a bare point cloud (no faces, no normals).
    let n = 3000;
    let mut m = Mesh::default();
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    for k in 0..n {
        let z = 1.0 - (2.0 * k as f32 + 1.0) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * k as f32;
        m.positions
            .push(2.0 * Vec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    let s = model::to_splats(&m, Path::new("cloud")).unwrap();
    assert_eq!(s.disks.len(), n);
    let outward = s
        .disks
        .iter()
        .filter(|d| d.normal.dot(d.center.normalize()) > 0.95)
        .count();
    assert_eq!(
        outward, n,
        "every normal should point outwards, consistently oriented"
    );
    let mut rng = common::Rng(9);
    for _ in 0..2000 {
        let q = 2.0 * Vec3::from(rng.unit_vector());
        assert!(covered(q, &s.disks, 0.05), "cloud point {q} is in a hole");
    }
}

#[test]
fn degenerate_faces_drop_unused_vertices() {
    // Two triangles, one of zero area; the vertex only it uses is dropped, not NaN.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nf 4 4 4\n";
    let m = model::load(&tmp("degenerate.obj", text.as_bytes())).unwrap();
    let s = model::to_splats(&m, Path::new("degenerate.obj")).unwrap();
    assert_eq!((s.disks.len(), s.dropped), (3, 1));
    assert!(
        s.disks
            .iter()
            .all(|d| d.radius.is_finite() && d.normal.is_finite())
    );
}

/// Text point clouds: the same points read alike from `.xyz` with normals, `.xyz` with an 8-bit
/// colour, `.xyz` with both (commas and tabs), and a Leica `.pts` (count line, intensity, colour),
/// gzipped too; each becomes closed, sanely sized splats facing outwards.
#[test]
fn text_point_clouds_read_every_layout() {
    let pts = common::fibonacci_sphere(1200);
    let line = |p: &Vec3, rest: String| format!("{} {} {}{rest}\n", p.x, p.y, p.z);
    let mut normals = String::from("# x y z nx ny nz\n");
    let mut colours = String::new();
    let mut both = String::from("// x,y,z,r,g,b,nx,ny,nz\n");
    let mut leica = format!("{}\n", pts.len());
    for (k, p) in pts.iter().enumerate() {
        let c = [(k % 200) as u8 + 20, 100, 200];
        normals += &line(p, format!(" {} {} {}", p.x, p.y, p.z));
        colours += &line(p, format!(" {} {} {}", c[0], c[1], c[2]));
        both += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            p.x, p.y, p.z, c[0], c[1], c[2], p.x, p.y, p.z
        );
        leica += &format!(
            "{}\t{}\t{}\t-1200\t{}\t{}\t{}\n",
            p.x, p.y, p.z, c[0], c[1], c[2]
        );
    }
    let cases = [
        ("n.xyz", normals.into_bytes(), true, false),
        ("c.xyz", colours.into_bytes(), false, true),
        ("b.xyz", both.into_bytes(), true, true),
        ("l.pts", leica.clone().into_bytes(), false, true),
        ("l.pts.gz", gzip(leica.as_bytes()), false, true),
    ];
    for (name, bytes, has_normals, has_colours) in cases {
        let path = tmp(name, &bytes);
        let mesh = model::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.positions.len(), pts.len(), "{name}");
        assert!(mesh.faces.is_empty());
        assert_eq!(mesh.normals.is_some(), has_normals, "{name}");
        assert_eq!(mesh.colors.is_some(), has_colours, "{name}");
        if let Some(c) = &mesh.colors {
            assert_eq!(c[1], [21.0 / 255.0, 100.0 / 255.0, 200.0 / 255.0], "{name}");
        }
        let set = model::to_splats(&mesh, &path).unwrap();
        assert_eq!(set.disks.len(), pts.len(), "{name}");
        for d in &set.disks {
            // Outward within the PCA's orientation (towards the cloud's outside).
            assert!(d.normal.dot(d.center) > 0.9, "{name}: {d:?}");
            assert!(d.radius > 0.01 && d.radius < 0.3, "{name}: {d:?}");
        }
    }
}

/// Malformed text clouds: a bad line is skipped and counted, with the first named by its line;
/// read strictly (`--strict`) it is an error naming the file and line; a file with no good
/// point, or whose columns are neither a normal nor a colour, is an error either way.
#[test]
fn malformed_text_clouds_name_the_line() {
    let strict = model::Reading {
        strict: true,
        ..model::Reading::current()
    };
    for (name, text, expect) in [
        ("a.xyz", "0 0 0\n1 0 0\n0 1 zero\n", "line 3"),
        ("b.xyz", "0 0 0\n1 0 0\n1 0 0 5\n", "line 3"),
        ("f.pts", "2\n0 0 0\n1 0 0\nnan 0 0\n", "line 4"),
    ] {
        let path = tmp(name, text.as_bytes());
        let mesh = model::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            (mesh.positions.len(), mesh.left_out.skipped),
            (2, 1),
            "{name}"
        );
        let first = mesh.left_out.first_skipped.as_deref().unwrap_or_default();
        assert!(
            first.contains(name) && first.contains(expect),
            "{name}: {first}"
        );
        let err = model::load_with(&path, &strict).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains(expect), "{name}: {err}");
    }
    for (name, text, expect) in [
        ("c.xyz", "0 0 0 1 2\n", "5 numbers"),
        ("d.xyz", "# nothing\n\n", "no vertices or points"),
        ("e.xyz", "0 0 0 0 0 1 300 0 0\n", "columns 7–9 hold neither"),
        (
            "g.xyz",
            "nan 0 0\n0 zero 0\n",
            "2 could not be read (the first: ",
        ),
    ] {
        let err = err_of(name, text.as_bytes());
        assert!(err.contains(name) && err.contains(expect), "{name}: {err}");
    }
}

/// LAS and LAZ written by the `las` crate read back as the same cloud (to the file's 1 mm
/// resolution), with 16-bit colours, or 8-bit colours stored in 16 bits; their splats close
/// the sphere with outward PCA normals. A header announcing more points than the file holds,
/// a truncated file and garbage are errors naming the file.
#[test]
fn las_and_laz_read_back_what_the_las_crate_wrote() {
    let pts = common::fibonacci_sphere(1500);
    let wide = |k: usize| [(k * 40) as u16, 30000, 65535];
    let narrow = |k: usize| [(k % 256) as u16, 128, 255];
    // (file, colour of point k, LAZ, the colours' full scale)
    type Colour<'a> = Option<&'a dyn Fn(usize) -> [u16; 3]>;
    let cases: [(&str, Colour, bool, f32); 4] = [
        ("plain.las", None, false, 0.0),
        ("wide.las", Some(&wide), false, 65535.0),
        ("wide.laz", Some(&wide), true, 65535.0),
        ("narrow.laz", Some(&narrow), true, 255.0),
    ];
    for (name, colours, laz, full) in cases {
        let bytes = common::write_las(&pts, colours, laz);
        let path = tmp(name, &bytes);
        let mesh = model::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.positions.len(), pts.len(), "{name}");
        for (a, b) in mesh.positions.iter().zip(&pts) {
            assert!(
                (*a - *b).abs().max_element() <= 0.0006,
                "{name}: {a} vs {b}"
            );
        }
        match (colours, &mesh.colors) {
            (None, None) => {}
            (Some(c), Some(read)) => {
                for (k, got) in read.iter().enumerate().step_by(97) {
                    let want = c(k).map(|v| v as f32 / full);
                    assert_eq!(*got, want, "{name}: point {k}");
                }
            }
            (c, read) => panic!(
                "{name}: colours {} but read {}",
                c.is_some(),
                read.is_some()
            ),
        }
        let set = model::to_splats(&mesh, &path).unwrap();
        assert_eq!(set.disks.len(), pts.len(), "{name}");
        assert!(
            set.disks.iter().all(|d| d.normal.dot(d.center) > 0.9),
            "{name}"
        );
    }
    let good = common::write_las(&pts, None, false);
    let err = err_of("cut.las", &good[..good.len() / 2]);
    assert!(err.contains("cut.las"), "{err}");
    let mut lying = good.clone();
    // The legacy point count (LAS 1.2 header, offset 107) far past what the bytes hold.
    lying[107..111].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = err_of("lying.las", &lying);
    assert!(err.contains("lying.las"), "{err}");
    let err = err_of("garbage.laz", b"not a lidar file at all");
    assert!(err.contains("garbage.laz"), "{err}");
}

/// 3DGS and 2DGS captures: opaque Gaussians become splats at their means, facing out (the
/// capture's signless normals oriented), of radius 2σ = 0.1, coloured by their DC term; faint
/// ones are left out and counted.
#[test]
fn gaussian_splat_plys_become_splats() {
    let pts = common::fibonacci_sphere(1000);
    let colour = |k: usize| [0.2 + 0.6 * (k % 7) as f32 / 7.0, 0.5, 0.8];
    for two_d in [false, true] {
        let name = if two_d { "2dgs.ply" } else { "3dgs.ply" };
        let path = tmp(name, &common::gaussian_ply(&pts, two_d, &colour));
        let mesh = model::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.left_out.dropped(), 200, "{name}");
        let rules = &mesh.left_out.by_rule;
        assert_eq!(rules.len(), 1, "{name}: {rules:?}");
        assert_eq!(rules[0].rule, model::gaussians::FAINT, "{name}");
        assert_eq!(mesh.positions.len(), 800, "{name}");
        let set = model::to_splats(&mesh, &path).unwrap();
        assert_eq!(set.disks.len(), 800, "{name}");
        assert_eq!(set.dropped, 200, "{name}");
        let opaque: Vec<usize> = (0..pts.len()).filter(|k| k % 5 != 4).collect();
        let colours = set.colors.as_ref().unwrap();
        for ((d, &k), c) in set.disks.iter().zip(&opaque).zip(colours) {
            assert!((d.center - pts[k]).length() < 1e-6, "{name}");
            assert!(
                d.normal.dot(pts[k]) > 0.999,
                "{name}: point {k} faces {}",
                d.normal
            );
            assert!((d.radius - 0.1).abs() < 1e-4, "{name}: radius {}", d.radius);
            let want = colour(k).map(model::srgb_to_linear);
            assert!(
                (0..3).all(|i| (c[i] - want[i]).abs() < 1e-5),
                "{name}: {c:?} {want:?}"
            );
        }
    }
}

/// An E57 file of two scans written by the `e57` crate, each in its own frame with a pose:
/// read back as one cloud in the file's frame (poses applied), with its 8-bit colours, the
/// returns that did not come back left out and counted, and splats that close the sphere.
/// Damaged files are errors naming the file.
#[test]
fn e57_scans_read_back_in_one_frame() {
    let pts = common::fibonacci_sphere(1600);
    let (upper, lower): (Vec<Vec3>, Vec<Vec3>) = pts.iter().partition(|p| p.z >= 0.0);
    let shift = Vec3::new(0.0, 0.0, -3.0);
    let lower_local: Vec<Vec3> = lower.iter().map(|p| *p - shift).collect();
    let colour = |k: usize| [(k % 250) as u8, 128, 255];
    let bytes = common::write_e57(
        &[
            (upper.clone(), [0.0; 3]),
            (
                lower_local,
                [shift.x as f64, shift.y as f64, shift.z as f64],
            ),
        ],
        &colour,
    );
    let path = tmp("scan.e57", &bytes);
    let mesh = model::load(&path).unwrap();
    assert_eq!(mesh.positions.len(), pts.len());
    assert_eq!(mesh.left_out.dropped(), 2, "one invalid return a scan");
    for (got, want) in mesh.positions.iter().zip(upper.iter().chain(&lower)) {
        assert!((*got - *want).length() < 1e-5, "{got} vs {want}");
    }
    let colours = mesh.colors.as_ref().unwrap();
    assert_eq!(colours[3], [3.0 / 255.0, 128.0 / 255.0, 1.0]);
    let set = model::to_splats(&mesh, &path).unwrap();
    assert_eq!(set.disks.len(), pts.len());
    assert_eq!(set.dropped, 2);
    assert!(set.disks.iter().all(|d| d.normal.dot(d.center) > 0.9));
    let err = err_of("cut.e57", &bytes[..bytes.len() / 2]);
    assert!(err.contains("cut.e57"), "{err}");
    let err = err_of("garbage.e57", b"ASTM-E57 but not really");
    assert!(err.contains("garbage.e57"), "{err}");
}

/// A coarse mesh sampled at a spacing: a 10 × 4 quad of two triangles, and a sliver, become
/// splats of about that spacing (one per spacing² of area, give or take the sub-triangles'
/// shape) that cover every point of every triangle, facing the triangle's way, with
/// interpolated colours.
#[test]
fn coarse_meshes_are_sampled_without_holes() {
    use lobelight::scene::model::surface::sample_surface;
    let m = Mesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(10.0, 4.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(10.0, 0.0, 1.0),
            Vec3::new(5.0, 0.0, 1.05),
        ],
        colors: Some(vec![
            [0.0; 3], [1.0; 3], [1.0; 3], [0.0; 3], [0.5; 3], [0.5; 3], [0.5; 3],
        ]),
        faces: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]],
        ..Default::default()
    };
    let spacing = 0.25;
    let s = sample_surface(&m, spacing);
    let quad = s.disks.iter().filter(|d| d.normal.z > 0.99).count();
    let per_area = quad as f32 * spacing * spacing / 40.0;
    assert!(
        (0.8..=2.5).contains(&per_area),
        "{quad} splats on the quad ({per_area} a spacing²)"
    );
    assert!(
        s.disks.iter().all(|d| d.radius <= 1.5 * spacing),
        "a splat wider than 1.5 spacings"
    );
    let mut rng = common::Rng(8);
    for k in 0..6000 {
        let f = m.faces[k % 3];
        let (mut a, mut b) = (rng.f32(), rng.f32());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let [p0, p1, p2] = f.map(|i| m.positions[i as usize]);
        let q = p0 + a * (p1 - p0) + b * (p2 - p0);
        assert!(
            covered(q, &s.disks, 1e-4),
            "point {q} of face {f:?} is in a hole"
        );
    }
    // Colours: linear at the centroid, so the quad's left edge is dark and its right bright.
    let colours = s.colors.as_ref().unwrap();
    for (d, c) in s.disks.iter().zip(colours) {
        if d.normal.z > 0.99 && d.center.x < 0.3 {
            assert!(c[0] < 0.01, "{d:?} {c:?}");
        }
    }
}

/// An OBJ with an MTL library: a coarse model is sampled at the default spacing (1/80 of its
/// extent), its faces keep the materials the MTL defines (Kd the albedo, Ks and Ns a Ward
/// lobe), one surface each; a material the scene names instead overrides them; a material the
/// library does not define is an error naming it.
#[test]
fn obj_materials_become_ward_materials() {
    let obj = "mtllib room.mtl\nv 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 4\nv 4 0 4\n\
               usemtl paint\nf 1 2 3 4\nusemtl metal\nf 1 2 6 5\n";
    let mtl =
        "newmtl paint\nKd 0.2 0.4 0.6\nnewmtl metal\nKd 0.1 0.1 0.1\nKs 0.5 0.5 0.5\nNs 198\n";
    let obj_path = tmp("room.obj", obj.as_bytes());
    tmp("room.mtl", mtl.as_bytes());
    let dir = obj_path.parent().unwrap();
    let scene_text = |material: &str| {
        format!(
            "[[light]]\ntype = \"point\"\nposition = [2.0, 2.0, 2.0]\nintensity = 1.0\n\n\
             [[object]]\nshape = \"model\"\npath = \"room.obj\"\n{material}"
        )
    };
    let scene_path = dir.join("room.toml");
    std::fs::write(&scene_path, scene_text("")).unwrap();
    let scene = lobelight::scene::load(&scene_path).unwrap();
    assert_eq!(scene.surfaces, ["#1 model paint", "#1 model metal"]);
    let index = |name: &str| scene.material_names.iter().position(|n| n == name).unwrap();
    let (paint, metal) = (index("#1 model/paint"), index("#1 model/metal"));
    assert_eq!(scene.materials[paint].specular, [0.0; 3]);
    assert_eq!(scene.materials[metal].specular, [0.5; 3]);
    assert!((scene.materials[metal].roughness - 0.1).abs() < 1e-6);
    let on = |k: usize| scene.splats.iter().filter(move |s| s.material == k as u32);
    // 4 × 4 faces at 0.05 a splat: several thousand each, none as large as the face.
    assert!(on(paint).count() > 3000 && on(metal).count() > 3000);
    assert!(on(paint).all(|s| s.diffuse == [0.2, 0.4, 0.6] && s.radius < 0.1));
    // The scene names a material: the MTL's are not used.
    std::fs::write(
        &scene_path,
        format!(
            "[materials.grey]\ndiffuse = 0.5\n\n{}",
            scene_text("material = \"grey\"\n")
        ),
    )
    .unwrap();
    let named = lobelight::scene::load(&scene_path).unwrap();
    assert!(!named.material_names.iter().any(|n| n.contains("paint")));
    assert!(named.splats.iter().all(|s| s.diffuse == [0.5; 3]));
    tmp("room.mtl", b"newmtl paint\nKd 0.2 0.4 0.6\n");
    std::fs::write(&scene_path, scene_text("")).unwrap();
    let err = lobelight::scene::load(&scene_path).unwrap_err().to_string();
    assert!(err.contains("metal") && err.contains("room.mtl"), "{err}");
}

/// In an OBJ whose faces partly have MTL materials, the faces without one keep their vertex
/// colours (`v x y z r g b`), as in a model with no materials at all.
#[test]
fn obj_faces_without_a_material_keep_their_vertex_colours() {
    let obj = "mtllib mixed.mtl\nv 0 0 0 1 0 0\nv 4 0 0 1 0 0\nv 4 4 0 1 0 0\nv 0 4 0 1 0 0\n\
               v 0 0 4 0 0 1\nv 4 0 4 0 0 1\nf 1 2 6 5\nusemtl paint\nf 1 2 3 4\n";
    let obj_path = tmp("mixed.obj", obj.as_bytes());
    tmp("mixed.mtl", b"newmtl paint\nKd 0.2 0.4 0.6\n");
    let scene_path = obj_path.parent().unwrap().join("mixed.toml");
    std::fs::write(
        &scene_path,
        "[[light]]\ntype = \"point\"\nposition = [2.0, 2.0, 2.0]\nintensity = 1.0\n\n\
         [[object]]\nshape = \"model\"\npath = \"mixed.obj\"\n",
    )
    .unwrap();
    let scene = lobelight::scene::load(&scene_path).unwrap();
    let paint = scene
        .material_names
        .iter()
        .position(|n| n == "#1 model/paint")
        .unwrap();
    let (painted, plain): (Vec<&lobelight::types::Splat>, Vec<_>) = scene
        .splats
        .iter()
        .partition(|s| s.material == paint as u32);
    assert!(painted.len() > 1000 && plain.len() > 1000);
    // Where a face has both, its vertex colours are its albedo (its vertices here are red).
    assert!(painted.iter().all(|s| s.diffuse == [1.0, 0.0, 0.0]));
    // The plain face runs from red (its z = 0 edge) to blue (z = 4): coloured, not the default
    // material's grey, and both ends are seen.
    let red = plain
        .iter()
        .filter(|s| s.diffuse[0] > 0.9 && s.diffuse[2] < 0.1)
        .count();
    let blue = plain
        .iter()
        .filter(|s| s.diffuse[2] > 0.9 && s.diffuse[0] < 0.1)
        .count();
    assert!(
        red > 10 && blue > 10,
        "{red} red, {blue} blue splats of {}",
        plain.len()
    );
}
