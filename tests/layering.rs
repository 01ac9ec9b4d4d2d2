//! The library's modules depend on each other one way (docs/architecture.md §2), at every
//! depth: no import cycle between the modules of one parent (`gpu::exec` → `gpu::scene` →
//! `gpu::grid` → `gpu::exec` is one, as `bake` → `cpu` → `bake` is at the top), and nothing
//! below the application imports `cli`. Read from the `crate::`, `super::` and `self::` paths
//! in the sources, so a new cycle fails here rather than in review.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module's path below the crate: `["gpu", "exec"]` for `src/gpu/exec.rs`.
type ModPath = Vec<String>;

/// Every `.rs` file under `root` with the module it defines (`mod.rs` its folder's).
fn module_files(root: &Path) -> Vec<(PathBuf, ModPath)> {
    let mut files = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("source directory") {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(root).expect("under the root");
            let mut module: ModPath = rel
                .components()
                .map(|c| {
                    c.as_os_str()
                        .to_string_lossy()
                        .trim_end_matches(".rs")
                        .to_owned()
                })
                .collect();
            if matches!(
                module.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                module.pop();
            }
            files.push((path, module));
        }
    }
    files.sort();
    files
}

/// The identifiers of a path that starts at `text`: `a::b::c`, or each branch's first
/// identifiers of a `{a::b, c}` group (one level deep, as the sources write them).
fn paths_at(text: &str) -> Vec<Vec<String>> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut head = Vec::new();
    let mut rest = text;
    loop {
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            return group[..end]
                .split(',')
                .map(|branch| {
                    let mut p = head.clone();
                    p.extend(
                        branch
                            .trim()
                            .split("::")
                            .map(ident)
                            .take_while(|s| !s.is_empty()),
                    );
                    p
                })
                .collect();
        }
        let name = ident(rest);
        if name.is_empty() {
            return vec![head];
        }
        rest = &rest[name.len()..];
        head.push(name);
        match rest.strip_prefix("::") {
            Some(r) => rest = r,
            None => return vec![head],
        }
    }
}

/// Module → the modules of the same parent that its files (and its submodules' files) name:
/// an edge `gpu::exec` → `gpu::scene` for a `use super::scene::…` in `src/gpu/exec.rs`, and
/// `bake` → `cpu` for a `crate::cpu::…` anywhere under `src/bake`.
fn sibling_graph(root: &Path) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let files = module_files(root);
    let modules: BTreeSet<ModPath> = files.iter().map(|(_, m)| m.clone()).collect();
    let mut graph: BTreeMap<ModPath, BTreeSet<ModPath>> = BTreeMap::new();
    for (path, module) in &files {
        let text = std::fs::read_to_string(path).expect("readable source");
        let mut named = Vec::new();
        for (prefix, base) in [
            ("crate::", Vec::new()),
            ("super::", module[..module.len().saturating_sub(1)].to_vec()),
            ("self::", module.clone()),
        ] {
            for (i, _) in text.match_indices(prefix) {
                // `super::` inside `crate::a::super_x` or an identifier ending in `self`.
                let before = text[..i].chars().next_back();
                if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
                    continue;
                }
                for tail in paths_at(&text[i + prefix.len()..]) {
                    let mut target = base.clone();
                    // `super::super::x`: one parent up for each.
                    let ups = tail.iter().take_while(|s| *s == "super").count();
                    target.truncate(target.len().saturating_sub(ups));
                    target.extend(tail.into_iter().skip(ups));
                    named.push(target);
                }
            }
        }
        for mut target in named {
            // The module the path ends in: its longest prefix that is a module.
            while !target.is_empty() && !modules.contains(&target) {
                target.pop();
            }
            let common = module
                .iter()
                .zip(&target)
                .take_while(|(a, b)| a == b)
                .count();
            // A module's own parts, or its ancestors, are not a sibling's.
            if common == module.len() || common == target.len() {
                continue;
            }
            let from = module[..=common].to_vec();
            let to = target[..=common].to_vec();
            graph.entry(from).or_default().insert(to);
        }
    }
    graph
}

/// The first import cycle of `graph`, as `a -> b -> a`.
fn first_cycle(graph: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Option<String> {
    // Depth-first search; a module met again while still on the path closes a cycle.
    fn visit(
        m: &ModPath,
        graph: &BTreeMap<ModPath, BTreeSet<ModPath>>,
        path: &mut Vec<ModPath>,
        done: &mut BTreeSet<ModPath>,
    ) -> Option<String> {
        if done.contains(m) {
            return None;
        }
        if let Some(i) = path.iter().position(|p| p == m) {
            let names: Vec<String> = path[i..].iter().chain([m]).map(|p| p.join("::")).collect();
            return Some(names.join(" -> "));
        }
        path.push(m.clone());
        for next in graph.get(m).into_iter().flatten() {
            if let Some(cycle) = visit(next, graph, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(m.clone());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|m| visit(m, graph, &mut Vec::new(), &mut done))
}

#[test]
fn no_import_cycle_among_modules_at_any_depth() {
    let graph = sibling_graph(Path::new("src"));
    let nested = graph.keys().filter(|m| m.len() > 1).count();
    assert!(
        graph.len() > 30 && nested > 10,
        "found only {:?}",
        graph.keys()
    );
    if let Some(cycle) = first_cycle(&graph) {
        panic!("import cycle: {cycle}");
    }
}

/// A cycle planted two levels down, through `super::` and `crate::` paths and a use group, is
/// found; the same tree without its closing import has none.
#[test]
fn a_planted_nested_cycle_is_found() {
    let root = std::env::temp_dir().join(format!("lobelight-layering-{}", std::process::id()));
    let write = |rel: &str, text: &str| {
        let path = root.join(rel);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("temp folder");
        std::fs::write(path, text).expect("temp file");
    };
    write("lib.rs", "pub mod outer;\n");
    write("outer/mod.rs", "pub mod inner;\n");
    write("outer/inner/mod.rs", "pub mod a;\npub mod b;\npub mod c;\n");
    write("outer/inner/a.rs", "use super::{b::Thing, c};\n");
    write("outer/inner/b.rs", "pub struct Thing;\n");
    write(
        "outer/inner/c.rs",
        "fn f() { crate::outer::inner::a::g(); }\n",
    );
    let graph = sibling_graph(&root);
    let cycle = first_cycle(&graph);
    assert_eq!(
        cycle.as_deref(),
        Some("outer::inner::a -> outer::inner::c -> outer::inner::a")
    );
    write(
        "outer/inner/c.rs",
        "fn f() { crate::outer::inner::b::Thing; }\n",
    );
    assert_eq!(first_cycle(&sibling_graph(&root)), None);
    std::fs::remove_dir_all(&root).expect("temp folder removed");
}

#[test]
fn the_library_does_not_import_the_application() {
    let cli = vec!["cli".to_owned()];
    for (module, uses) in sibling_graph(Path::new("src")) {
        if module.len() == 1 && module != cli {
            assert!(!uses.contains(&cli), "{} imports cli", module.join("::"));
        }
    }
}

/// The library's top-level modules from the bottom up: each uses only those before it
/// (docs/architecture.md §2 gives the same list in its layers). A module missing here fails
/// `every_module_has_its_place`.
const ORDER: &[&str] = &[
    // Records, errors and the WGSL with its Rust twins (the grid's cells, which the traversal
    // twin walks, among them).
    "error",
    "large_pages",
    "timing",
    "budget",
    "types",
    "grid",
    "shared",
    "shaders",
    // Each stage's settings, limits and host data; nothing of scene files.
    "photons",
    "em",
    "bins",
    "tone",
    "lobe_norms",
    "convolution",
    "fit_groups",
    "lod",
    // Scenes and views.
    "scene",
    "camera",
    // The dispatch sequences, what frames and bakes derive from a scene, and the two
    // engines that run them (neither reads the other).
    "sequence",
    "direct",
    "frame",
    "objects",
    "plan",
    "host",
    "cpu",
    "gpu",
    // The bake over either engine, its cache, and the renderer that picks the engine once.
    "bake",
    "cache",
    "renderer",
    // A sequence's frames as a video.
    "video",
    // The application.
    "cli",
];

/// Each `(module, import)` of `root`'s top level where the import is listed after the module
/// in `order`, or not listed at all.
fn upward_imports(root: &Path, order: &[&str]) -> Vec<String> {
    let place = |m: &str| order.iter().position(|o| *o == m);
    let mut found = Vec::new();
    for (module, uses) in sibling_graph(root) {
        if module.len() != 1 {
            continue;
        }
        for used in uses {
            match (place(&module[0]), place(&used[0])) {
                (Some(a), Some(b)) if b < a => {}
                _ => found.push(format!("{} imports {}", module[0], used[0])),
            }
        }
    }
    found
}

#[test]
fn every_module_uses_only_those_below_it() {
    let found = upward_imports(Path::new("src"), ORDER);
    assert!(found.is_empty(), "imports against the layers: {found:?}");
}

#[test]
fn every_module_has_its_place() {
    let lib = std::fs::read_to_string("src/lib.rs").expect("src/lib.rs");
    let declared: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    assert!(declared.len() > 20, "found only {declared:?}");
    for m in &declared {
        assert!(ORDER.contains(m), "`{m}` has no place in ORDER");
    }
    for m in ORDER {
        assert!(
            declared.contains(m),
            "ORDER lists `{m}`, which src/lib.rs does not"
        );
    }
}

/// An import planted from a low module to a higher one is found, through `crate::` and a use
/// group; the same tree without it has none.
#[test]
fn a_planted_upward_import_is_found() {
    let root = std::env::temp_dir().join(format!("lobelight-layers-{}", std::process::id()));
    let write = |rel: &str, text: &str| {
        let path = root.join(rel);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("temp folder");
        std::fs::write(path, text).expect("temp file");
    };
    let order = ["low", "mid", "high"];
    write("lib.rs", "pub mod low;\npub mod mid;\npub mod high;\n");
    write("low.rs", "pub struct Low;\n");
    write("mid/mod.rs", "pub mod part;\n");
    write("mid/part.rs", "use crate::{low::Low, high::High};\n");
    write("high.rs", "use crate::mid::part;\npub struct High;\n");
    assert_eq!(upward_imports(&root, &order), vec!["mid imports high"]);
    write("mid/part.rs", "use crate::low::Low;\n");
    assert!(upward_imports(&root, &order).is_empty());
    std::fs::remove_dir_all(&root).expect("temp folder removed");
}

/// The paths of `text` that name an engine: the mirrors (`cpu::`), the device (`gpu::`) or
/// its frame passes.
fn engine_paths(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for name in ["cpu::", "gpu::", "FrameRenderer"] {
        for (i, _) in text.match_indices(name) {
            let before = text[..i].chars().next_back();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
                continue;
            }
            let line = text[..i].lines().count();
            found.push(format!("{name} (line {line})"));
        }
    }
    found
}

/// No file of the application names an engine (`cpu::`, `gpu::`, the device's frame passes):
/// it draws through `renderer::Renderer`, which picks the engine once.
#[test]
fn the_application_picks_no_engine() {
    let files = module_files(Path::new("src/cli"));
    assert!(files.len() >= 5, "found only {files:?}");
    for (path, _) in files {
        let text = std::fs::read_to_string(&path).expect("readable source");
        let found = engine_paths(&text);
        assert!(
            found.is_empty(),
            "{} reaches an engine itself: {found:?}",
            path.display()
        );
    }
}

#[test]
fn engine_paths_are_found() {
    let text = "use crate::gpu::Gpu;\nfn f() { cpu::frames::cpu_frame(); my_gpu::x(); }\n";
    assert_eq!(engine_paths(text), vec!["cpu:: (line 2)", "gpu:: (line 1)"]);
}
