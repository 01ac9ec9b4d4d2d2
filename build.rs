//! Generates the stage table from `wgsl/`: one `Stage` variant a `wgsl/<stage>.wgsl` (its
//! name the file stem in camel case) and the shared modules of `wgsl/shared/`, so that a new
//! stage is registered by its file alone (`src/shaders.rs` includes `stages.rs`).

use std::path::Path;

/// The file stems of the `.wgsl` files directly in `dir`, sorted.
fn stems(dir: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

/// `splat_tile_count` → `SplatTileCount`.
fn camel(stem: &str) -> String {
    stem.split('_')
        .map(|part| {
            let mut chars = part.chars();
            chars.next().map_or_else(String::new, |c| {
                c.to_ascii_uppercase().to_string() + chars.as_str()
            })
        })
        .collect()
}

fn main() {
    println!("cargo:rerun-if-changed=wgsl");
    println!("cargo:rerun-if-changed=wgsl/shared");
    let mut out = String::from("stages! {\n");
    for stem in stems("wgsl") {
        out += &format!("    {} => \"{stem}\",\n", camel(&stem));
    }
    out += "}\n\nshared_modules! {\n";
    for stem in stems("wgsl/shared") {
        out += &format!("    \"{stem}\",\n");
    }
    out += "}\n";
    let dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    std::fs::write(Path::new(&dir).join("stages.rs"), out).expect("OUT_DIR is writable");
}
