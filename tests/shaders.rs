//! Every WGSL file is registered, resolves its imports and passes naga's validation; the
//! resolver's errors name the file and line. No GPU needed.

use lobelight::shaders::{self, SHARED, STAGES, Stage};

fn names_in(dir: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("wgsl directory")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn every_wgsl_file_is_registered() {
    let mut stages: Vec<String> = STAGES.iter().map(|s| s.name.to_owned()).collect();
    stages.sort();
    assert_eq!(names_in("wgsl"), stages, "wgsl/*.wgsl vs shaders::STAGES");
    let mut shared: Vec<String> = SHARED.iter().map(|s| s.name.to_owned()).collect();
    shared.sort();
    assert_eq!(
        names_in("wgsl/shared"),
        shared,
        "wgsl/shared/*.wgsl vs shaders::SHARED"
    );
}

#[test]
fn every_stage_validates_with_naga() {
    for &stage in Stage::ALL {
        let source = shaders::resolve_stage(stage).unwrap();
        let module = shaders::validate(stage.name(), &source).unwrap_or_else(|e| panic!("{e}"));
        let has = |name: &str| module.entry_points.iter().any(|e| e.name == name);
        assert!(
            has("main") || (has("vs_main") && has("fs_main")),
            "{} has neither `main` nor `vs_main` and `fs_main`",
            stage.name()
        );
    }
}

/// The sky's map, which `lights.wgsl` reads and each importer declares where its groups have
/// room (`trace.wgsl` in the geometry group, the splat stages after their own bindings): a
/// module that reads it and declares none validates with this stand-in.
const SKY_STAND_IN: &str = "@group(3) @binding(0) var<storage, read> sky: array<vec4<f32>>;\n";

#[test]
fn every_shared_module_validates_alone() {
    for module in SHARED {
        let path = format!("wgsl/shared/{}.wgsl", module.name);
        let mut source = shaders::resolve(&path, module.text, &|m| {
            SHARED.iter().find(|s| s.name == m).map(|s| s.text)
        })
        .unwrap();
        if source.contains("sky[") && !source.contains("var<storage, read> sky:") {
            source.push_str(SKY_STAND_IN);
        }
        shaders::validate(module.name, &source).unwrap_or_else(|e| panic!("{e}"));
    }
}

fn lookup(name: &str) -> Option<&'static str> {
    match name {
        "a" => Some("// #import b\nconst A: u32 = B;\n"),
        "b" => Some("const B: u32 = 1u;\n"),
        "loop1" => Some("// #import loop2\n"),
        "loop2" => Some("// #import loop1\n"),
        _ => None,
    }
}

#[test]
fn imports_are_spliced_once() {
    let out = shaders::resolve(
        "x.wgsl",
        "// #import a\n// #import b\n// #import a\nfn f() {}\n",
        &lookup,
    )
    .unwrap();
    assert_eq!(out.matches("const B").count(), 1);
    assert_eq!(out.matches("const A").count(), 1);
    // b is spliced before a's body, which uses it.
    assert!(out.find("const B").unwrap() < out.find("const A").unwrap());
}

#[test]
fn unknown_import_names_file_and_line() {
    let err =
        shaders::resolve("wgsl/x.wgsl", "fn f() {}\n  // #import nope\n", &lookup).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("wgsl/x.wgsl: line 2"), "{msg}");
    assert!(msg.contains("nope"), "{msg}");
}

#[test]
fn import_cycle_is_an_error() {
    let err = shaders::resolve("wgsl/x.wgsl", "// #import loop1\n", &lookup).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("cycle") && msg.contains("wgsl/shared/loop2.wgsl: line 1"),
        "{msg}"
    );
}

#[test]
fn malformed_import_is_an_error() {
    let err = shaders::resolve("wgsl/x.wgsl", "// #import a b\n", &lookup).unwrap_err();
    assert!(err.to_string().contains("line 1"), "{err}");
}

#[test]
fn every_subgroup_variant_validates_with_naga() {
    let mut variants = 0;
    for &stage in Stage::ALL
        .iter()
        .filter(|s| s.file().text.contains("// #ifdef subgroups"))
    {
        let source = shaders::resolve_stage_with(stage, &["subgroups"]).unwrap();
        shaders::validate_subgroups(stage.name(), &source).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            source.contains("subgroup"),
            "{}: variant not taken",
            stage.name()
        );
        variants += 1;
    }
    assert!(variants >= 1, "em_fit has a subgroup variant");
}

#[test]
fn ifdef_keeps_the_defined_branch() {
    let text = "a\n// #ifdef x\nb\n// #else\nc\n// #endif\nd\n";
    let none = shaders::resolve_with("wgsl/x.wgsl", text, &lookup, &[]).unwrap();
    assert_eq!(none, "a\nc\nd\n");
    let x = shaders::resolve_with("wgsl/x.wgsl", text, &lookup, &["x"]).unwrap();
    assert_eq!(x, "a\nb\nd\n");
}

#[test]
fn unbalanced_ifdef_names_file_and_line() {
    let err = shaders::resolve("wgsl/x.wgsl", "a\n// #ifdef x\nb\n", &lookup).unwrap_err();
    assert!(err.to_string().contains("wgsl/x.wgsl: line 2"), "{err}");
    let err = shaders::resolve("wgsl/x.wgsl", "a\n// #endif\n", &lookup).unwrap_err();
    assert!(err.to_string().contains("wgsl/x.wgsl: line 2"), "{err}");
}

/// The device host takes every stage's workgroup size (and items per invocation) from the
/// WGSL, read with naga; the CPU mirrors write theirs for their loops, in their rows of the
/// mirrors' table (`cpu::MIRRORS`). The two must agree, and every compute entry point of a
/// stage has one row (a stage that draws triangles, one row for its `main`).
#[test]
fn mirror_workgroup_shapes_match_the_wgsl() {
    use lobelight::cpu::{mirror_rows, tonemap_reduce};
    use lobelight::shaders::{stage_entries, stage_shape};
    // Every stage has its rows in its mirror's file, whose shape is the WGSL's: `em_fit`'s
    // workgroup size is a pipeline constant (`em::workgroup_size`), and the splat raster
    // passes, the reference gather and present draw triangles, so none of them has one.
    let mut passes = 0;
    for &stage in Stage::ALL {
        let mut rows: Vec<&str> = mirror_rows()
            .filter(|r| r.stage == stage)
            .map(|r| r.entry)
            .collect();
        let mut entries = stage_entries(stage).unwrap();
        if entries.is_empty() {
            entries.push("main".into());
        }
        rows.sort();
        entries.sort();
        assert_eq!(rows, entries, "{stage}: rows in the mirrors' table");
        passes += entries.len();
        let shape = stage_shape(stage).unwrap();
        for row in mirror_rows().filter(|r| r.stage == stage) {
            assert_eq!(
                row.workgroup_size, shape.workgroup_size,
                "{stage}: workgroup size"
            );
            if let Some(wg) = row.workgroup_size {
                assert_eq!(shape.items, row.items, "{stage}: items per invocation");
                assert_eq!(shape.per_group(stage).unwrap(), wg * row.items, "{stage}");
            }
        }
    }
    assert_eq!(mirror_rows().count(), passes);
    // Three stages run a second pass over coverage groups' members, and the direct bake one
    // over a sky's neighbours (`share`).
    assert_eq!(passes, Stage::ALL.len() + 4);
    assert_eq!(
        tonemap_reduce::BLOCK,
        tonemap_reduce::WG * tonemap_reduce::ITEMS
    );
    assert_eq!(stage_shape(Stage::EmFit).unwrap().workgroup_size, None);
    assert!(mirror_rows().filter(|r| r.workgroup_size.is_some()).count() > 30);
}

/// What the host and the mirrors bind is read from the WGSL too: each compute stage's
/// bindings are numbered from 0 without gaps in each group (so "binding order" is the order a
/// dispatch lists its buffers, as the CPU executor checks), and only the tracing stages use
/// group 1, the scene's geometry buffers (`GEOMETRY_BINDINGS`), as their mirrors say.
#[test]
fn stage_bindings_are_read_from_the_wgsl() {
    use lobelight::cpu::Mirror;
    use lobelight::shaders::{resolve_stage, stage_shape};
    let mut traced = 0;
    for &stage in Stage::ALL {
        let shape = stage_shape(stage).unwrap();
        let module = naga::front::wgsl::parse_str(&resolve_stage(stage).unwrap()).unwrap();
        for group in 0..2u32 {
            let mut numbers: Vec<u32> = module
                .global_variables
                .iter()
                .filter_map(|(_, v)| v.binding.as_ref())
                .filter(|b| b.group == group)
                .map(|b| b.binding)
                .collect();
            numbers.sort();
            let expected: Vec<u32> = (0..shape.bindings[group as usize]).collect();
            assert_eq!(numbers, expected, "{} group {group}", stage.name());
        }
        // A stage traces rays where its WGSL binds the geometry group, whole; its mirror, where
        // the executor runs one, takes the geometry then and only then.
        let traces = shape.bindings[1] > 0;
        if traces {
            assert_eq!(
                shape.bindings[1] as usize,
                lobelight::gpu::exec::GEOMETRY_BINDINGS,
                "{}: the geometry group",
                stage.name()
            );
            traced += 1;
        }
        for row in lobelight::cpu::mirror_rows().filter(|r| r.stage == stage) {
            let pass = stage.entry(row.entry);
            match row.run {
                Some(Mirror::Traced(_)) => assert!(traces, "{pass}: a traced mirror"),
                Some(Mirror::Plain(_)) => assert!(!traces, "{pass}: a mirror without geometry"),
                None => {}
            }
        }
        assert!(shape.bindings[0] > 0, "{}", stage.name());
    }
    // The photon pass, the direct bake, coverage, final gathering, the path tracer, the
    // photon view, shading, the reference gather and the ray-trace test stage.
    assert_eq!(traced, 9);
}

/// Every stage validates with each of its paged arrays split into three pages, and declares
/// the pages where the host binds them.
#[test]
fn every_paged_variant_validates_with_naga() {
    use lobelight::shaders::{PAGE_BINDING_STEP, PagedArray, Paging, paged_bindings};
    let mut paged_stages = 0;
    for &stage in Stage::ALL {
        let paged = paged_bindings(stage).unwrap();
        if paged.is_empty() {
            continue;
        }
        paged_stages += 1;
        let paging = Paging {
            arrays: paged
                .iter()
                .map(|p| PagedArray {
                    name: p.name.clone(),
                    pages: 3,
                    shift: 10,
                })
                .collect(),
        };
        let source = shaders::resolve_stage_paged(stage, &[], &paging).unwrap();
        let module = shaders::validate(stage.name(), &source).unwrap_or_else(|e| panic!("{e}"));
        for p in &paged {
            for k in 0..3 {
                let binding = p.binding + k * PAGE_BINDING_STEP;
                let declared = module.global_variables.iter().any(|(_, v)| {
                    v.binding
                        .as_ref()
                        .is_some_and(|b| b.group == p.group && b.binding == binding)
                });
                assert!(
                    declared,
                    "{}: page {k} of {} is not at {binding}",
                    stage.name(),
                    p.name
                );
            }
        }
    }
    // The splats alone are paged in every stage that reads them.
    assert!(
        paged_stages >= 15,
        "only {paged_stages} stages have paged arrays"
    );
}

#[test]
fn paged_needs_a_storage_array_declaration() {
    let err = shaders::resolve("wgsl/x.wgsl", "// #paged\nconst A: u32 = 1u;\n", &lookup)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("wgsl/x.wgsl") && err.contains("line 2"),
        "{err}"
    );
}

/// The value of `const NAME: u32 = Nu;` in a WGSL source.
fn wgsl_const_u32(source: &str, name: &str) -> u32 {
    let decl = format!("const {name}: u32 = ");
    let line = source
        .lines()
        .find_map(|l| l.trim().strip_prefix(decl.as_str()))
        .unwrap_or_else(|| panic!("no `{decl}` in the WGSL"));
    let digits = line.trim_end_matches(';').trim_end_matches('u');
    match digits.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16).unwrap(),
        None => digits.parse().unwrap(),
    }
}

/// The walk down the chunks' nodes finds a node's parent by position: the host's and the
/// stages' fan-out must be one number.
#[test]
fn node_fanout_matches_the_wgsl() {
    for stage in [Stage::SplatNodes, Stage::SplatSelect] {
        let source = shaders::resolve_stage(stage).unwrap();
        let fanout = wgsl_const_u32(&source, "NODE_FANOUT") as usize;
        assert_eq!(fanout, lobelight::lod::NODE_FANOUT, "{stage}");
    }
}

/// The host draws the splats' triangles by instances of several splats, and the vertex
/// shaders take a vertex's splat and corner from its vertex and instance index: both sides
/// must split a draw alike, or splats are drawn twice or not at all.
#[test]
fn splat_draw_constants_match_the_wgsl() {
    use lobelight::shared::splat::{SPLAT_CORNERS, SPLATS_PER_INSTANCE, instances};
    for stage in [Stage::SplatVisibility, Stage::SplatAttributes] {
        let source = shaders::resolve_stage(stage).unwrap();
        assert_eq!(wgsl_const_u32(&source, "SPLAT_CORNERS"), SPLAT_CORNERS);
        assert_eq!(
            wgsl_const_u32(&source, "SPLATS_PER_INSTANCE"),
            SPLATS_PER_INSTANCE
        );
    }
    assert_eq!(instances(0), 0);
    assert_eq!(instances(1), 1);
    assert_eq!(instances(SPLATS_PER_INSTANCE), 1);
    assert_eq!(instances(SPLATS_PER_INSTANCE + 1), 2);
}

/// Lights' kinds and flags are one set of numbers in Rust and WGSL: a light that reflects on
/// the host must reflect in every stage.
#[test]
fn light_constants_match_the_wgsl() {
    use lobelight::types::{light_flags, light_kind};
    let source = shaders::resolve_stage(Stage::Shade).unwrap();
    for (name, value) in [
        ("LIGHT_POINT", light_kind::POINT),
        ("LIGHT_SPOT", light_kind::SPOT),
        ("LIGHT_AREA", light_kind::AREA),
        ("LIGHT_DIRECTIONAL", light_kind::DIRECTIONAL),
        ("LIGHT_ENVIRONMENT", light_kind::ENVIRONMENT),
        ("LIGHT_SUN", light_kind::SUN),
        ("LIGHT_REFLECTS", light_flags::REFLECTS),
    ] {
        assert_eq!(wgsl_const_u32(&source, name), value, "{name}");
    }
}

/// The shade pass and its mirror let a reflecting light stand the same distance in front of
/// its own surface.
#[test]
fn reflecting_light_slack_matches_the_wgsl() {
    let source = shaders::resolve_stage(Stage::Shade).unwrap();
    let decl = "const REFLECTING_LIGHT_SLACK: f32 = ";
    let value: f32 = source
        .lines()
        .find_map(|l| l.trim().strip_prefix(decl))
        .and_then(|v| v.trim_end_matches(';').parse().ok())
        .expect("REFLECTING_LIGHT_SLACK in shade.wgsl");
    assert_eq!(value, lobelight::cpu::shade::REFLECTING_LIGHT_SLACK);
}

/// The lobe fit's flags and words are one set of numbers in Rust and WGSL: a flag the host
/// sets must select the same pass in every stage and its mirror.
#[test]
fn em_flags_match_the_wgsl() {
    use lobelight::shared::lobes::*;
    let source = shaders::resolve_stage(Stage::EstimateCoverage).unwrap();
    for (name, value) in [
        ("EM_SPARSE", EM_SPARSE),
        ("EM_PRIORS", EM_PRIORS),
        ("EM_FIT_ALL", EM_FIT_ALL),
        ("EM_SUBGROUP_REDUCE", EM_SUBGROUP_REDUCE),
        ("EM_DEFER_FIT", EM_DEFER_FIT),
        ("EM_SHARE", EM_SHARE),
        ("EM_GROUPS", EM_GROUPS),
        ("FOLLOWER_BIT", FOLLOWER_BIT),
    ] {
        assert_eq!(wgsl_const_u32(&source, name), value, "{name}");
    }
}

/// `estimate_smooth` and its mirror choose alike only with the same thresholds.
#[test]
fn smoothing_constants_match_the_wgsl() {
    use lobelight::shared::lobes::*;
    let source = shaders::resolve_stage(Stage::EstimateSmooth).unwrap();
    for (name, value) in [
        ("SMOOTH_PHOTONS_ENOUGH", SMOOTH_PHOTONS_ENOUGH),
        ("SMOOTH_BUDGET", SMOOTH_BUDGET),
        ("SMOOTH_SPAN", SMOOTH_SPAN),
    ] {
        assert_eq!(wgsl_const_u32(&source, name), value, "{name}");
    }
    for (name, value) in [
        ("SMOOTH_COS_MIN", SMOOTH_COS_MIN),
        ("SMOOTH_CONFIDENCE", SMOOTH_CONFIDENCE),
        ("SMOOTH_DET_MIN", SMOOTH_DET_MIN),
    ] {
        let decl = format!("const {name}: f32 = ");
        let wgsl: f32 = source
            .lines()
            .find_map(|l| l.trim().strip_prefix(decl.as_str()))
            .and_then(|v| v.trim_end_matches(';').parse().ok())
            .unwrap_or_else(|| panic!("no `{decl}` in estimate_smooth.wgsl"));
        assert_eq!(wgsl, value, "{name}");
    }
}
