//! Splat grid build, GPU against the CPU mirror, on the shipped scenes (and the model scenes
//! when scenes/models/fetch.sh has run). `cargo bench --bench grid`.
//! Throughput is reported in splats per second.

use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use lobelight::gpu::{BackendChoice, Gpu, grid::build_grid};
use lobelight::{cpu, grid::grid_params, scene};

fn bench(c: &mut Criterion) {
    let gpu = match Gpu::new(BackendChoice::Auto) {
        Ok(g) => g,
        Err(e) => panic!("the grid benchmark needs a GPU adapter: {e}"),
    };
    eprintln!("device: {} ({})", gpu.info.name, gpu.backend_name());
    let mut group = c.benchmark_group("grid_build");
    group.sample_size(10);
    for name in ["cornell", "bunny", "dragon", "dragon_full"] {
        let path = format!("scenes/{name}.toml");
        let Ok(scene) = scene::load(Path::new(&path)) else {
            eprintln!("skipping {name}: run scenes/models/fetch.sh for the model scenes");
            continue;
        };
        let params = grid_params(&scene.splats, &scene.grid).expect("grid params");
        let splats = gpu.storage("splats", &scene.splats).expect("upload");
        group.throughput(Throughput::Elements(scene.splats.len() as u64));
        group.bench_function(format!("{name}/gpu"), |b| {
            b.iter(|| build_grid(&gpu, &params, &splats).expect("gpu grid"))
        });
        group.bench_function(format!("{name}/cpu"), |b| {
            b.iter(|| cpu::build_grid(&params, &scene.splats).expect("cpu grid"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
