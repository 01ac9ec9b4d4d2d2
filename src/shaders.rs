//! The WGSL sources, embedded at build time, and the `// #import name` resolver.
//!
//! A line `// #import name` splices in `wgsl/shared/name.wgsl` (recursively), each module at
//! most once per shader, so stages can import `types` and a shared module that also imports
//! it. `// #ifdef name`, `// #else` and `// #endif` keep or drop lines by the defines a
//! pipeline is built with (a variant that uses an optional device feature, such as
//! subgroups). `// #paged` before a storage array's declaration makes it a paged array (see
//! `Paging`): the stage reads it through `NAME_at(i)` and writes it through `NAME_put(i, v)`,
//! so that the host can bind an array larger than one storage binding as several. Errors name
//! the file and line.

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

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
            text: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/wgsl/",
                $name,
                ".wgsl"
            )),
        }
    };
}

macro_rules! shared {
    ($name:literal) => {
        WgslFile {
            name: $name,
            text: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/wgsl/shared/",
                $name,
                ".wgsl"
            )),
        }
    };
}

/// Declares `SHARED`, the modules a stage imports with `// #import name`.
macro_rules! shared_modules {
    ($($name:literal,)*) => {
        /// The shared modules of `wgsl/shared/`, by name.
        pub const SHARED: &[WgslFile] = &[$(shared!($name),)*];
    };
}

/// Declares the stage table: the `Stage` enum, one variant a stage, and `STAGES`, the stages'
/// WGSL files in the same order.
macro_rules! stages {
    ($($variant:ident => $name:literal,)*) => {
        /// A shader stage (`wgsl/<name>.wgsl`): entry point `main` for compute stages, `vs_main`
        /// and `fs_main` for the splat raster passes. The variant names what the host dispatches,
        /// checked by the compiler; `name` is its file's stem.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Stage {
            $($variant,)*
        }

        impl Stage {
            /// Every stage, in the stage table's order.
            pub const ALL: &[Stage] = &[$(Stage::$variant,)*];

            /// The stage's file stem: `wgsl/<name>.wgsl`, `src/cpu/<name>.rs`.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Stage::$variant => $name,)*
                }
            }
        }

        /// Every stage's WGSL file, in `Stage::ALL`'s order. The stage table.
        pub const STAGES: &[WgslFile] = &[$(stage!($name),)*];
    };
}

// One row a `wgsl/<stage>.wgsl` and one a `wgsl/shared/<module>.wgsl`, in file-name order,
// written by `build.rs`.
include!(concat!(env!("OUT_DIR"), "/stages.rs"));

impl Stage {
    /// The stage whose file stem is `name`.
    pub fn from_name(name: &str) -> Option<Stage> {
        Stage::ALL.iter().copied().find(|s| s.name() == name)
    }

    /// The stage's WGSL file.
    pub fn file(self) -> &'static WgslFile {
        &STAGES[self as usize]
    }
}

/// One compute entry point of a stage: `main`, or another of the stage's passes (its second,
/// say) that binds the same buffers. A stage converts to its `main`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Pass {
    pub stage: Stage,
    pub entry: &'static str,
}

impl From<Stage> for Pass {
    fn from(stage: Stage) -> Pass {
        Pass { stage, entry: MAIN }
    }
}

/// The entry point a stage's dispatch runs unless it names another.
pub const MAIN: &str = "main";

impl Stage {
    /// The stage's entry point `entry` (see `Pass`).
    pub const fn entry(self, entry: &'static str) -> Pass {
        Pass { stage: self, entry }
    }
}

impl std::fmt::Display for Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.entry {
            MAIN => write!(f, "{}", self.stage),
            entry => write!(f, "{}::{entry}", self.stage),
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the host reads from a stage's WGSL instead of writing it a second time: the shape of
/// its workgroups. The CPU mirrors state their own in their rows (their loops need them), and
/// a test checks those against this.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StageShape {
    /// `@workgroup_size` of the compute entry points (its x; y and z are 1; every entry point
    /// of a stage has the same), or `None` where a pipeline-overridable constant sets it
    /// (`em_fit`), the entry points differ or the stage draws triangles.
    pub workgroup_size: Option<u32>,
    /// The stage's `const ITEMS`, values per invocation; 1 where it has none.
    pub items: u32,
    /// Bindings the stage declares in bind groups 0 and 1 (one past the highest binding
    /// index): what a dispatch must bind, in binding order.
    pub bindings: [u32; 2],
}

impl StageShape {
    /// Values one workgroup covers: the unit a dispatch's group count is taken in.
    pub fn per_group(&self, stage: Stage) -> Result<u32> {
        self.workgroup_size
            .map(|wg| wg * self.items)
            .ok_or_else(|| {
                Error::Internal(format!(
                    "stage '{stage}' has no fixed workgroup size in its WGSL"
                ))
            })
    }
}

/// What the host reads of a stage's WGSL: its shape and its paged arrays.
#[derive(Clone, Debug)]
struct Reflected {
    shape: StageShape,
    paged: Vec<PagedBinding>,
    /// The names of its compute entry points.
    entries: Vec<String>,
}

/// A stage's WGSL read with naga, once per process.
fn reflect(stage: Stage) -> Result<Arc<Reflected>> {
    static REFLECTED: OnceLock<Mutex<HashMap<Stage, Arc<Reflected>>>> = OnceLock::new();
    let cache = REFLECTED.get_or_init(Default::default);
    if let Some(r) = cache.lock().ok().and_then(|m| m.get(&stage).cloned()) {
        return Ok(r);
    }
    let source = resolve_stage(stage)?;
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| {
        Error::parse(
            Path::new(&format!("wgsl/{stage}.wgsl")),
            "after import resolution",
            e.emit_to_string(&source),
        )
    })?;
    let reflected = Arc::new(Reflected {
        shape: read_shape(&module),
        paged: read_paged(&module),
        entries: compute_entries(&module).map(|e| e.name.clone()).collect(),
    });
    if let Ok(mut m) = cache.lock() {
        m.insert(stage, reflected.clone());
    }
    Ok(reflected)
}

/// The shape of a stage, read once per process from its WGSL with naga.
pub fn stage_shape(stage: Stage) -> Result<StageShape> {
    reflect(stage).map(|r| r.shape)
}

/// The names of `stage`'s compute entry points, in the order its WGSL declares them.
/// Whether `stage` walks the splat grid (it imports `trace`): its bind group 1 is the scene's
/// geometry (`wgsl/shared/trace.wgsl`).
pub fn traces(stage: Stage) -> bool {
    stage.file().text.contains("// #import trace\n")
}

pub fn stage_entries(stage: Stage) -> Result<Vec<String>> {
    reflect(stage).map(|r| r.entries.clone())
}

fn compute_entries(module: &naga::Module) -> impl Iterator<Item = &naga::EntryPoint> {
    module
        .entry_points
        .iter()
        .filter(|e| e.stage == naga::ShaderStage::Compute)
}

fn read_shape(module: &naga::Module) -> StageShape {
    let size = |e: &naga::EntryPoint| {
        Some(e)
            .filter(|e| e.workgroup_size_overrides.is_none())
            .filter(|e| e.workgroup_size[1] == 1 && e.workgroup_size[2] == 1)
            .map(|e| e.workgroup_size[0])
    };
    let sizes: Vec<Option<u32>> = compute_entries(module).map(size).collect();
    let workgroup_size = sizes
        .first()
        .copied()
        .flatten()
        .filter(|&first| sizes.iter().all(|&s| s == Some(first)));
    let items = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("ITEMS"))
        .and_then(|(_, c)| match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => Some(v),
            _ => None,
        })
        .unwrap_or(1);
    let mut bindings = [0u32; 2];
    for (_, var) in module.global_variables.iter() {
        if let Some(rb) = &var.binding
            && let Some(count) = bindings.get_mut(rb.group as usize)
        {
            *count = (*count).max(rb.binding + 1);
        }
    }
    StageShape {
        workgroup_size,
        items,
        bindings,
    }
}

/// The full source of a stage with its imports resolved, nothing defined.
pub fn resolve_stage(stage: Stage) -> Result<String> {
    resolve_stage_with(stage, &[])
}

/// The full source of a stage with its imports resolved and `defines` defined.
pub fn resolve_stage_with(stage: Stage, defines: &[&str]) -> Result<String> {
    resolve_stage_paged(stage, defines, &Paging::default())
}

/// Resolves `// #import` lines of `text` (named `path` in errors) using `lookup` for modules.
pub fn resolve(
    path: &str,
    text: &str,
    lookup: &dyn Fn(&str) -> Option<&'static str>,
) -> Result<String> {
    resolve_with(path, text, lookup, &[])
}

/// `resolve`, keeping the `// #ifdef` branches of `defines`.
pub fn resolve_with(
    path: &str,
    text: &str,
    lookup: &dyn Fn(&str) -> Option<&'static str>,
    defines: &[&str],
) -> Result<String> {
    resolve_paged(path, text, lookup, defines, &Paging::default())
}

/// `resolve_with`, with the paged arrays laid out as `paging` says.
pub fn resolve_paged(
    path: &str,
    text: &str,
    lookup: &dyn Fn(&str) -> Option<&'static str>,
    defines: &[&str],
    paging: &Paging,
) -> Result<String> {
    let mut out = String::with_capacity(text.len() * 2);
    let mut ctx = Splice {
        lookup,
        defines,
        paging,
        done: HashSet::new(),
        active: vec![path.to_owned()],
    };
    splice(path, text, &mut ctx, &mut out)?;
    Ok(out)
}

struct Splice<'a> {
    lookup: &'a dyn Fn(&str) -> Option<&'static str>,
    defines: &'a [&'a str],
    paging: &'a Paging,
    /// Modules already spliced.
    done: HashSet<String>,
    /// The chain of files being spliced (for cycles).
    active: Vec<String>,
}

/// A `// #` directive other than `#import`: its kind and argument.
fn directive(line: &str) -> Option<(&str, &str)> {
    let rest = line.trim_start().strip_prefix("// #")?;
    let (kind, arg) = rest.split_once(' ').unwrap_or((rest, ""));
    matches!(kind, "ifdef" | "else" | "endif" | "paged").then_some((kind, arg.trim()))
}

fn splice(path: &str, text: &str, ctx: &mut Splice, out: &mut String) -> Result<()> {
    // One entry per open `#ifdef`: whether its current branch is kept, and its line.
    let mut branches: Vec<(bool, usize)> = Vec::new();
    // Set by `// #paged`: the next line declares a paged array.
    let mut paged = false;
    for (n, line) in text.lines().enumerate() {
        let err = |msg: String| Error::at_line(Path::new(path), n + 1, msg);
        let kept = branches.iter().all(|b| b.0);
        if paged {
            paged = false;
            if kept {
                let decl = PagedDecl::parse(line).ok_or_else(|| {
                    err(format!(
                        "`// #paged` must precede `@group(G) @binding(B) var<storage, ..> NAME: array<T>;`, \
                         not '{}'",
                        line.trim()
                    ))
                })?;
                decl.write(ctx.paging, out);
                continue;
            }
        }
        if let Some((kind, arg)) = directive(line) {
            match (kind, branches.last_mut()) {
                ("paged", _) if arg.is_empty() => paged = true,
                ("ifdef", _) if !arg.is_empty() => {
                    branches.push((ctx.defines.contains(&arg), n + 1));
                }
                ("else", Some(top)) => top.0 = !top.0,
                ("endif", Some(_)) => {
                    branches.pop();
                }
                _ => return Err(err(format!("unmatched or malformed `{}`", line.trim()))),
            }
            continue;
        }
        if !kept {
            continue;
        }
        let Some(rest) = line.trim_start().strip_prefix("// #import") else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        let name = rest.trim();
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(err(format!(
                "malformed import '{}': expected `// #import name`",
                line.trim()
            )));
        }
        let module_path = format!("wgsl/shared/{name}.wgsl");
        if ctx.active.contains(&module_path) {
            return Err(err(format!(
                "import cycle: {} -> {module_path}",
                ctx.active.join(" -> ")
            )));
        }
        if !ctx.done.insert(name.to_owned()) {
            continue;
        }
        let module = (ctx.lookup)(name)
            .ok_or_else(|| err(format!("unknown import '{name}' (no {module_path})")))?;
        out.push_str(&format!("// ---- begin {module_path}\n"));
        ctx.active.push(module_path.clone());
        splice(&module_path, module, ctx, out)?;
        ctx.active.pop();
        out.push_str(&format!("// ---- end {module_path}\n"));
    }
    match branches.last() {
        Some(&(_, line)) => Err(Error::at_line(
            Path::new(path),
            line,
            "`// #ifdef` without `// #endif`",
        )),
        None => Ok(()),
    }
}

/// Parses and validates a resolved shader with naga, as wgpu would on a device without
/// optional features.
pub fn validate(name: &str, source: &str) -> Result<naga::Module> {
    validate_with(name, source, naga::valid::Capabilities::default())
}

/// `validate` on a device with subgroup operations in compute shaders.
pub fn validate_subgroups(name: &str, source: &str) -> Result<naga::Module> {
    validate_with(name, source, naga::valid::Capabilities::SUBGROUP)
}

fn validate_with(
    name: &str,
    source: &str,
    capabilities: naga::valid::Capabilities,
) -> Result<naga::Module> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        Error::parse(
            Path::new(&format!("wgsl/{name}.wgsl")),
            "after import resolution",
            e.emit_to_string(source),
        )
    })?;
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities);
    if capabilities.contains(naga::valid::Capabilities::SUBGROUP) {
        validator
            .subgroup_stages(naga::valid::ShaderStages::COMPUTE)
            .subgroup_operations(naga::valid::SubgroupOperationSet::all());
    }
    validator.validate(&module).map_err(|e| {
        Error::parse(
            Path::new(&format!("wgsl/{name}.wgsl")),
            "validation",
            e.emit_to_string(source),
        )
    })?;
    Ok(module)
}

/// Binding numbers of a paged array's pages: page k of the array declared at binding B is
/// bound at B + k × PAGE_BINDING_STEP (wgpu allows binding numbers below 1000).
pub const PAGE_BINDING_STEP: u32 = 100;

/// Most pages one paged array can be split into.
pub const MAX_PAGES: u32 = 9;

/// How a pipeline variant splits its paged arrays (`// #paged`) into bindings. An array that
/// fits one storage binding has one page and is read as before, so scenes that fit pay
/// nothing; a larger one is bound as `pages` windows of 2^shift elements of one buffer, and
/// its accessors pick the window by the index's high bits.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Paging {
    pub arrays: Vec<PagedArray>,
}

/// One paged array's layout in a `Paging`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PagedArray {
    /// The array's name in the WGSL.
    pub name: String,
    /// Bindings it takes, at least 2 (an array of one page is not listed).
    pub pages: u32,
    /// log2 of the elements in one page.
    pub shift: u32,
}

impl Paging {
    /// The layout of array `name`, if it has more than one page.
    pub fn of(&self, name: &str) -> Option<&PagedArray> {
        self.arrays.iter().find(|a| a.name == name)
    }

    /// A key for pipeline caches: empty when nothing is split.
    pub fn key(&self) -> String {
        self.arrays
            .iter()
            .map(|a| format!(" {}:{}x2^{}", a.name, a.pages, a.shift))
            .collect()
    }
}

/// A paged array's declaration, parsed from its line.
struct PagedDecl<'a> {
    group: u32,
    binding: u32,
    access: &'a str,
    name: &'a str,
    elem: &'a str,
}

impl<'a> PagedDecl<'a> {
    /// `@group(G) @binding(B) var<storage, ACCESS> NAME: array<T>;`
    fn parse(line: &'a str) -> Option<PagedDecl<'a>> {
        let number = |s: &str, tag: &str| -> Option<u32> {
            let rest = &s[s.find(tag)? + tag.len()..];
            rest[..rest.find(')')?].trim().parse().ok()
        };
        let (group, binding) = (number(line, "@group(")?, number(line, "@binding(")?);
        let rest = &line[line.find("var<storage,")? + "var<storage,".len()..];
        let (access, rest) = rest.split_once('>')?;
        let (name, ty) = rest.split_once(':')?;
        let ty = ty.trim().strip_suffix(';')?.trim();
        let elem = ty.strip_prefix("array<")?.strip_suffix('>')?.trim();
        let name = name.trim();
        let ok = !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        ok.then_some(PagedDecl {
            group,
            binding,
            access: access.trim(),
            name,
            elem,
        })
    }

    /// The declaration of every page, and the accessors: `NAME_at(i)`, `NAME_len()`, and
    /// `NAME_put(i, v)` where the array is writable.
    fn write(&self, paging: &Paging, out: &mut String) {
        let PagedDecl {
            group,
            binding,
            access,
            name,
            elem,
        } = *self;
        let layout = paging.of(name);
        let pages = layout.map_or(1, |l| l.pages);
        for k in 0..pages {
            let (b, page) = match k {
                0 => (binding, name.to_owned()),
                _ => (binding + k * PAGE_BINDING_STEP, format!("{name}_page{k}")),
            };
            out.push_str(&format!(
                "@group({group}) @binding({b}) var<storage, {access}> {page}: array<{elem}>;\n"
            ));
        }
        let writable = access == "read_write";
        let Some(layout) = layout else {
            out.push_str(&format!(
                "fn {name}_at(i: u32) -> {elem} {{ return {name}[i]; }}\n\
                 fn {name}_len() -> u32 {{ return arrayLength(&{name}); }}\n"
            ));
            if writable {
                out.push_str(&format!(
                    "fn {name}_put(i: u32, v: {elem}) {{ {name}[i] = v; }}\n"
                ));
            }
            return;
        };
        let (shift, mask) = (layout.shift, (1u64 << layout.shift) - 1);
        // Every page but the last is full (`Gpu::paging`).
        let last = pages - 1;
        out.push_str(&format!(
            "fn {name}_len() -> u32 {{ return arrayLength(&{name}_page{last}) + {}u; }}\n",
            (last as u64) << shift
        ));
        let cases = |body: &dyn Fn(&str) -> String| {
            let mut s = String::new();
            for k in 1..pages {
                s.push_str(&format!(
                    "        case {k}u: {{ {} }}\n",
                    body(&format!("{name}_page{k}"))
                ));
            }
            s.push_str(&format!("        default: {{ {} }}\n", body(name)));
            s
        };
        out.push_str(&format!(
            "fn {name}_at(i: u32) -> {elem} {{\n    let j = i & {mask}u;\n    \
             switch i >> {shift}u {{\n{}    }}\n}}\n",
            cases(&|page| format!("return {page}[j];"))
        ));
        if writable {
            out.push_str(&format!(
                "fn {name}_put(i: u32, v: {elem}) {{\n    let j = i & {mask}u;\n    \
                 switch i >> {shift}u {{\n{}    }}\n}}\n",
                cases(&|page| format!("{page}[j] = v;"))
            ));
        }
    }
}

/// A paged array a stage declares: where it is bound (page 0) and its element stride.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PagedBinding {
    pub name: String,
    pub group: u32,
    pub binding: u32,
    pub stride: u32,
}

/// The full source of a stage with `defines` and its paged arrays laid out as `paging` says.
pub fn resolve_stage_paged(stage: Stage, defines: &[&str], paging: &Paging) -> Result<String> {
    resolve_paged(
        &format!("wgsl/{stage}.wgsl"),
        stage.file().text,
        &|m| SHARED.iter().find(|s| s.name == m).map(|s| s.text),
        defines,
        paging,
    )
}

/// The paged arrays of a stage (those with a `NAME_at` accessor), read once per process.
pub fn paged_bindings(stage: Stage) -> Result<Vec<PagedBinding>> {
    reflect(stage).map(|r| r.paged.clone())
}

fn read_paged(module: &naga::Module) -> Vec<PagedBinding> {
    let accessor = |n: &str| {
        let at = format!("{n}_at");
        module
            .functions
            .iter()
            .any(|(_, f)| f.name.as_deref() == Some(at.as_str()))
    };
    let mut paged = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let (Some(rb), Some(var_name)) = (&var.binding, &var.name) else {
            continue;
        };
        if !accessor(var_name) {
            continue;
        }
        if let naga::TypeInner::Array { stride, .. } = module.types[var.ty].inner {
            paged.push(PagedBinding {
                name: var_name.clone(),
                group: rb.group,
                binding: rb.binding,
                stride,
            });
        }
    }
    paged
}
