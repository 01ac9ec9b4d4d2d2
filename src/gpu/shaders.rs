//! The WGSL sources, embedded at build time, and the `// #import name` resolver.
//!
//! A line `// #import name` splices in `wgsl/shared/name.wgsl` (recursively), each module at
//! most once per shader, so stages can import `types` and a shared module that also imports
//! it. Errors name the importing file and line.

use std::collections::HashSet;
use std::path::Path;

use crate::error::{Error, Result};

/// A WGSL file of the project: its name (file stem) and text.
#[derive(Clone, Copy, Debug)]
pub struct WgslFile {
    pub name: &'static str,
    pub text: &'static str,
}

macro_rules! stage {
    ($name:literal) => {
        WgslFile {
            name: $name,
            text: include_str!(concat!("../../wgsl/", $name, ".wgsl")),
        }
    };
}

macro_rules! shared {
    ($name:literal) => {
        WgslFile {
            name: $name,
            text: include_str!(concat!("../../wgsl/shared/", $name, ".wgsl")),
        }
    };
}

/// Every stage shader (`wgsl/<name>.wgsl`, entry point `main`). The stage table.
pub const STAGES: &[WgslFile] = &[
    stage!("grid_count"),
    stage!("grid_scatter"),
    stage!("grid_rank"),
    stage!("grid_distance"),
    stage!("trace_rays"),
    stage!("photon_trace"),
    stage!("bin_count"),
    stage!("bin_scatter"),
    stage!("bin_rank"),
    stage!("bin_place"),
    stage!("em_select"),
    stage!("em_fit"),
    stage!("scan_reduce"),
    stage!("scan_apply"),
];

/// Every shared module (`wgsl/shared/<name>.wgsl`), importable by name.
pub const SHARED: &[WgslFile] = &[
    shared!("types"),
    shared!("dispatch"),
    shared!("grid"),
    shared!("rng"),
    shared!("sampling"),
    shared!("ward"),
    shared!("trace"),
    shared!("bins"),
    shared!("octahedral"),
    shared!("lobes"),
];

pub fn stage(name: &str) -> Option<&'static WgslFile> {
    STAGES.iter().find(|s| s.name == name)
}

/// The full source of a stage with its imports resolved.
pub fn resolve_stage(name: &str) -> Result<String> {
    let file =
        stage(name).ok_or_else(|| Error::Invalid(format!("no shader stage named '{name}'")))?;
    resolve(&format!("wgsl/{name}.wgsl"), file.text, &|m| {
        SHARED.iter().find(|s| s.name == m).map(|s| s.text)
    })
}

/// Resolves `// #import` lines of `text` (named `path` in errors) using `lookup` for modules.
pub fn resolve(
    path: &str,
    text: &str,
    lookup: &dyn Fn(&str) -> Option<&'static str>,
) -> Result<String> {
    let mut out = String::with_capacity(text.len() * 2);
    let mut done = HashSet::new();
    let mut active = vec![path.to_owned()];
    splice(path, text, lookup, &mut done, &mut active, &mut out)?;
    Ok(out)
}

fn splice(
    path: &str,
    text: &str,
    lookup: &dyn Fn(&str) -> Option<&'static str>,
    done: &mut HashSet<String>,
    active: &mut Vec<String>,
    out: &mut String,
) -> Result<()> {
    for (n, line) in text.lines().enumerate() {
        let Some(rest) = line.trim_start().strip_prefix("// #import") else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        let err = |msg: String| Error::at_line(Path::new(path), n + 1, msg);
        let name = rest.trim();
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(err(format!(
                "malformed import '{}': expected `// #import name`",
                line.trim()
            )));
        }
        let module_path = format!("wgsl/shared/{name}.wgsl");
        if active.contains(&module_path) {
            return Err(err(format!(
                "import cycle: {} -> {module_path}",
                active.join(" -> ")
            )));
        }
        if !done.insert(name.to_owned()) {
            continue;
        }
        let module = lookup(name)
            .ok_or_else(|| err(format!("unknown import '{name}' (no {module_path})")))?;
        out.push_str(&format!("// ---- begin {module_path}\n"));
        active.push(module_path.clone());
        splice(&module_path, module, lookup, done, active, out)?;
        active.pop();
        out.push_str(&format!("// ---- end {module_path}\n"));
    }
    Ok(())
}

/// Parses and validates a resolved shader with naga, as wgpu would.
pub fn validate(name: &str, source: &str) -> Result<naga::Module> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        Error::parse(
            Path::new(&format!("wgsl/{name}.wgsl")),
            "after import resolution",
            e.emit_to_string(source),
        )
    })?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    );
    validator.validate(&module).map_err(|e| {
        Error::parse(
            Path::new(&format!("wgsl/{name}.wgsl")),
            "validation",
            e.emit_to_string(source),
        )
    })?;
    Ok(module)
}
