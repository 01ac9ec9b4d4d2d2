//! Every input the fuzz targets (`fuzz/`) found a crash with, kept in `fuzz/crashes/<target>/`,
//! read again by its loader: each is now a clear error naming the file, or a sane model.

use std::path::Path;

use lobelight::scene::model;

/// Each crash file, read as a model by the loader its folder names.
#[test]
fn every_crash_the_fuzzers_found_is_an_error_or_a_sane_model() {
    let mut seen = 0;
    for target in ["ply", "obj", "text", "las", "e57"] {
        let Ok(files) = std::fs::read_dir(Path::new("fuzz/crashes").join(target)) else {
            continue;
        };
        for file in files {
            let path = file.unwrap().path();
            seen += 1;
            match model::load(&path) {
                Err(e) => {
                    let name = path.file_name().unwrap().to_string_lossy().into_owned();
                    assert!(e.to_string().contains(&name), "{}: {e}", path.display());
                }
                Ok(mesh) => {
                    if let Ok(set) = model::to_splats(&mesh, &path) {
                        assert!(
                            set.disks
                                .iter()
                                .all(|d| d.radius > 0.0 && d.center.is_finite())
                        );
                    }
                }
            }
        }
    }
    assert!(seen >= 2, "the crash files are missing ({seen} found)");
}

/// The crashes by name: a PLY mesh whose flipped bit put a face's index past the vertices, and
/// a PLY of two vertex elements whose normals then missed the first's points (the harness's
/// checks were stricter than the loader's, which refused both: the first crash was the
/// harness's; the second now says what is wrong); a LAZ file whose description lists no item
/// (the LAZ reader panicked taking the first: now checked before it), and one whose decoder
/// indexed past an empty table (a decoder's panic is now an error, `reading::guarded`).
#[test]
fn the_crashes_found_say_what_is_wrong() {
    let e = model::load(Path::new("fuzz/crashes/ply/face-index.ply")).unwrap_err();
    assert!(e.to_string().contains("vertex index out of range"), "{e}");
    let e = model::load(Path::new("fuzz/crashes/las/no-laz-items.laz")).unwrap_err();
    assert!(e.to_string().contains("lists no compressed item"), "{e}");
    let e = model::load(Path::new("fuzz/crashes/las/decoder-index.laz")).unwrap_err();
    assert!(
        e.to_string().contains("the decoder failed on this file"),
        "{e}"
    );
    let e = model::load(Path::new("fuzz/crashes/ply/two-vertex-elements.ply")).unwrap_err();
    assert!(e.to_string().contains("a second `element vertex`"), "{e}");
}
