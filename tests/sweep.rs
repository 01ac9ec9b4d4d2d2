//! `bench sweep` on a small plan: every setting gives a row with finite figures, the files
//! are written, and thinning keeps the splats' area.

mod common;

use std::path::Path;

use lobelight::cli::sweep::{SweepPlan, sweep, thin};
use lobelight::em::LobeFamily;
use lobelight::renderer::Engine;
use lobelight::scene;

fn small_plan() -> SweepPlan {
    SweepPlan {
        size: 32,
        base_photons: 60_000,
        reference_photons: 200_000,
        reference_spp: 64,
        path_spp: vec![4],
        photons: vec![30_000, 200_000],
        iterations: vec![2, 10],
        radius_scales: vec![1.0, 2.0],
        lobes: vec![1, 3],
        splat_fractions: vec![0.5],
        families: vec![LobeFamily::Vmf],
        prune: vec![false],
        shares: vec![0.0],
        smooths: vec![0.0],
        frames: 1,
    }
}

#[test]
fn a_small_sweep_writes_its_tables_and_charts() {
    let engine = Engine::Device(std::sync::Arc::new(common::gpu()));
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let dir = std::env::temp_dir().join(format!("lobelight-sweep-{}", std::process::id()));
    let plan = small_plan();
    let r = sweep(&[("cornell".into(), scene)], &engine, &plan, &dir).unwrap();
    assert_eq!(r.rows.len(), 14);
    let share = r.rows.iter().find(|row| row.knob == "share").unwrap();
    assert_eq!(share.value, "0R");
    let smooth = r.rows.iter().find(|row| row.knob == "smooth").unwrap();
    assert_eq!(smooth.value, "0R");
    let path = r.rows.iter().find(|row| row.knob == "path").unwrap();
    assert_eq!(path.value, "4 spp");
    assert_eq!(r.references[0].spp, 64);
    // Per object: the Cornell box's five walls and two blocks, in every row.
    assert!(
        r.rows.iter().all(|row| row.objects.len() == 7),
        "{:?}",
        path.objects
    );
    for row in &r.rows {
        assert!(row.rel_mse.is_finite() && row.rel_mse > 0.0, "{row:?}");
        assert!(row.smape > 0.0 && row.smape < 1.0, "{row:?}");
        assert!(row.bake_ms > 0.0 && row.frame_ms > 0.0, "{row:?}");
    }
    // More photons, less error against the path-traced reference.
    let by = |knob: &str, value: &str| {
        r.rows
            .iter()
            .find(|row| row.knob == knob && row.value == value)
            .unwrap()
            .rel_mse
    };
    assert!(by("photons", "200k") < by("photons", "30k"), "{:?}", r.rows);
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert!(csv.starts_with("scene,knob,value,photons"));
    assert_eq!(csv.lines().count(), 15);
    assert!(csv.lines().next().unwrap().ends_with(",prune,lobes_kept"));
    let md = std::fs::read_to_string(dir.join("sweep.md")).unwrap();
    assert!(md.contains("| iterations | 10 |"), "{md}");
    let chart = image::open(dir.join("sweep_cornell.png")).unwrap();
    assert!(chart.width() > 600);
    assert!(dir.join("reference_cornell.exr").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn thinning_keeps_the_area() {
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let area = |s: &lobelight::scene::Scene| -> f64 {
        s.splats.iter().map(|p| (p.radius as f64).powi(2)).sum()
    };
    for fraction in [0.25f32, 0.5] {
        let thinned = thin(&scene, fraction);
        let kept = thinned.splats.len() as f64 / scene.splats.len() as f64;
        assert!((kept - fraction as f64).abs() < 0.02, "{kept}");
        let ratio = area(&thinned) / area(&scene);
        assert!((ratio - 1.0).abs() < 0.03, "{fraction}: {ratio}");
    }
}

/// `bench sweep --knobs` keeps only the named knobs and refuses unknown ones.
#[test]
fn a_sweep_turns_only_the_knobs_named() {
    let plan = SweepPlan::default()
        .only(&["prune".into(), "lobes".into()])
        .unwrap();
    assert_eq!(plan.prune, vec![true, false]);
    assert_eq!(plan.lobes, SweepPlan::default().lobes);
    assert!(plan.photons.is_empty() && plan.iterations.is_empty());
    assert!(plan.radius_scales.is_empty() && plan.splat_fractions.is_empty());
    assert!(plan.families.is_empty());
    let e = SweepPlan::default().only(&["colour".into()]).unwrap_err();
    assert!(
        e.to_string().contains("unknown sweep knob \"colour\""),
        "{e}"
    );
}
