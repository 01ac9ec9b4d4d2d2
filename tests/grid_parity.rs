//! The GPU grid build gives exactly the CPU mirror's cell lists, and those lists are right.

mod common;

use glam::Vec3;
use lobelight::cpu;
use lobelight::gpu::grid::build_grid;
use lobelight::grid::{
    CONE_STEPS, DIST_CAP, DIST_MASK, GridConfig, SplatGrid, cell_index, cone_axis, cone_faces_away,
    disk_cell_range, floor_cell, grid_params,
};
use lobelight::types::Splat;

fn gpu_grid(
    gpu: &lobelight::gpu::Gpu,
    splats: &[Splat],
    cfg: &GridConfig,
) -> (SplatGrid, SplatGrid) {
    let params = grid_params(splats, cfg).unwrap();
    let buf = gpu.storage("splats", splats).unwrap();
    let on_gpu = build_grid(gpu, &params, &buf)
        .unwrap()
        .download(gpu)
        .unwrap();
    let on_cpu = cpu::build_grid(&params, splats).unwrap();
    (on_gpu, on_cpu)
}

/// Compares two grids and names the first difference (the vectors are too long to print).
fn assert_same(a: &SplatGrid, b: &SplatGrid, what: &str) {
    assert_eq!(a.params, b.params, "{what}: params");
    let first_diff = |x: &[u32], y: &[u32]| {
        x.iter()
            .zip(y)
            .position(|(p, q)| p != q)
            .or((x.len() != y.len()).then_some(x.len().min(y.len())))
    };
    if let Some(i) = first_diff(&a.cell_start, &b.cell_start) {
        panic!(
            "{what}: cell_start differs first at cell {i}: {:?} vs {:?}",
            a.cell_start.get(i),
            b.cell_start.get(i)
        );
    }
    if let Some(i) = first_diff(&a.cell_dist, &b.cell_dist) {
        panic!(
            "{what}: cell_dist differs first at cell {i}: {:?} vs {:?}",
            a.cell_dist.get(i),
            b.cell_dist.get(i)
        );
    }
    if let Some(i) = first_diff(&a.cell_splats, &b.cell_splats) {
        let lo = i.saturating_sub(3);
        panic!(
            "{what}: cell_splats differs first at entry {i}: {:?} vs {:?}",
            &a.cell_splats[lo..(i + 3).min(a.cell_splats.len())],
            &b.cell_splats[lo..(i + 3).min(b.cell_splats.len())]
        );
    }
}

/// Independent check of a grid: each splat is listed exactly in the cells of its box,
/// lists are strictly increasing.
fn check_grid(grid: &SplatGrid, splats: &[Splat]) {
    let g = &grid.params;
    let mut expected = vec![Vec::new(); g.cell_count as usize];
    for (i, s) in splats.iter().enumerate() {
        let (lo, hi) = disk_cell_range(s, g);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    expected[cell_index(glam::UVec3::new(x, y, z), g) as usize].push(i as u32);
                }
            }
        }
    }
    for (c, list) in expected.iter().enumerate() {
        assert_eq!(grid.cell(c as u32), &list[..], "cell {c}");
    }
    check_distance(grid);
    check_cones(grid, splats);
}

/// Independent check of the facing cones: an empty cell has none, and where a listed cell's
/// cone turns a direction away, every disk it lists faces away from that direction (tried with
/// the cone's axis and directions around it), the disks' normals within the cone's angle.
fn check_cones(grid: &SplatGrid, splats: &[Splat]) {
    let mut cones = 0;
    for c in 0..grid.params.cell_count {
        let word = grid.cell_dist[c as usize];
        let list = grid.cell(c);
        if list.is_empty() {
            assert_eq!(word >> 8, 0, "empty cell {c} has a cone");
            continue;
        }
        let open = word >> 24;
        if open == 0 {
            continue;
        }
        cones += 1;
        let axis = cone_axis(word);
        let sin_bound = 1.0 - open as f32 / CONE_STEPS;
        let cos_bound = (1.0 - sin_bound * sin_bound).max(0.0).sqrt();
        let tilt = |v: Vec3| (axis + v).normalize();
        let tries = [
            axis,
            tilt(Vec3::X * 0.3),
            tilt(Vec3::Y * -0.5),
            tilt(Vec3::Z * 0.8),
        ];
        for &i in list {
            let n = Vec3::from(splats[i as usize].normal);
            assert!(
                axis.dot(n) >= cos_bound - 1e-5,
                "cell {c}: splat {i}'s normal lies outside the cone"
            );
            for d in tries.iter().filter(|&&d| cone_faces_away(word, d)) {
                assert!(n.dot(*d) > 0.0, "cell {c} turns {d:?} away from splat {i}");
            }
        }
    }
    assert!(
        grid.params.cell_count < 64 || cones > 0,
        "no listed cell has a facing cone"
    );
}

/// Independent check of the distance field: for each cell, the Chebyshev distance to the
/// nearest non-empty cell, capped, by brute force over the cube of radius DIST_CAP.
fn check_distance(grid: &SplatGrid) {
    let g = &grid.params;
    let [dx, dy, dz] = g.dims.map(|d| d as i32);
    let cap = DIST_CAP as i32;
    let occupied = |x: i32, y: i32, z: i32| {
        let inside = (0..dx).contains(&x) && (0..dy).contains(&y) && (0..dz).contains(&z);
        inside && !grid.cell((x + dx * (y + dy * z)) as u32).is_empty()
    };
    // Every 7th cell keeps the brute force affordable on the larger grids.
    for c in (0..g.cell_count as i32).step_by(7) {
        let (x, y, z) = (c % dx, (c / dx) % dy, c / (dx * dy));
        let mut best = cap;
        for oz in -cap..=cap {
            for oy in -cap..=cap {
                for ox in -cap..=cap {
                    let d = ox.abs().max(oy.abs()).max(oz.abs());
                    if d < best && occupied(x + ox, y + oy, z + oz) {
                        best = d;
                    }
                }
            }
        }
        assert_eq!(
            grid.cell_dist[c as usize] & DIST_MASK,
            best as u32,
            "distance of cell {c}"
        );
    }
}

#[test]
fn gpu_grid_equals_cpu_grid() {
    let gpu = common::gpu();
    // Several shapes: small disks, big disks spanning many cells, and a multi-level scan
    // (cell counts well above one scan block of 1024).
    let mixture = || {
        // Many tiny disks and a few huge ones that span hundreds of cells each.
        let mut s = common::random_splats(20_000, 0.001, 0.003, 11);
        s.extend(common::random_splats(60, 0.3, 0.6, 12));
        s
    };
    let cases = [
        common::random_splats(5_000, 0.001, 0.02, 1),
        common::random_splats(20_000, 0.01, 0.2, 2),
        mixture(),
    ];
    for (i, splats) in cases.into_iter().enumerate() {
        let (on_gpu, on_cpu) = gpu_grid(&gpu, &splats, &GridConfig::default());
        eprintln!(
            "case {i}: dims {:?}, {} cells, {} entries, max {} per cell",
            on_cpu.params.dims,
            on_cpu.params.cell_count,
            on_cpu.cell_splats.len(),
            on_cpu.max_cell_len()
        );
        assert!(
            on_cpu.params.cell_count > 1024 * 4,
            "case {i} should need a multi-level scan"
        );
        check_grid(&on_cpu, &splats);
        assert_same(&on_gpu, &on_cpu, &format!("case {i}"));
    }
}

#[test]
fn all_splats_in_one_cell() {
    let gpu = common::gpu();
    // Identical tiny disks at one point: the grid degenerates to very few cells that list
    // everything; the sort must still order them.
    let splats: Vec<Splat> = (0..3000)
        .map(|_| Splat {
            center: [0.25, 0.5, -0.75],
            radius: 1e-3,
            normal: [0.0, 0.0, 1.0],
            ..Default::default()
        })
        .collect();
    let (on_gpu, on_cpu) = gpu_grid(&gpu, &splats, &GridConfig::default());
    check_grid(&on_cpu, &splats);
    assert_same(&on_gpu, &on_cpu, "one cell");
    assert_eq!(on_cpu.max_cell_len(), 3000);
}

#[test]
fn scan_matches_cpu_for_many_lengths() {
    let gpu = common::gpu();
    let mut rng = common::Rng(7);
    for len in [1u32, 2, 1023, 1024, 1025, 4096, 1024 * 1024 + 17, 3_000_001] {
        let values: Vec<u32> = (0..len).map(|_| (rng.next_u64() % 7) as u32).collect();
        let mut expected = values.clone();
        cpu::exclusive_scan(&mut expected).unwrap();
        // Plain sequential exclusive scan as the independent reference.
        let mut acc = 0u32;
        for (i, v) in values.iter().enumerate() {
            assert_eq!(expected[i], acc, "cpu scan at {i} of {len}");
            acc += v;
        }
        let buf = gpu.storage("scan", &values).unwrap();
        let mut encoder = gpu.encoder("scan test");
        lobelight::gpu::scan::exclusive_scan(&gpu, &mut encoder, &buf, len).unwrap();
        gpu.submit_and_wait(encoder).unwrap();
        let got: Vec<u32> = gpu.read(&buf, len as usize).unwrap();
        assert_eq!(got, expected, "gpu scan of length {len}");
    }
}

#[test]
fn too_many_coincident_splats_is_a_clear_error() {
    let gpu = common::gpu();
    let splats: Vec<Splat> = (0..lobelight::grid::MAX_CELL_LEN + 1)
        .map(|_| Splat {
            center: [0.0; 3],
            radius: 1e-3,
            normal: [0.0, 1.0, 0.0],
            ..Default::default()
        })
        .collect();
    let params = grid_params(&splats, &GridConfig::default()).unwrap();
    let cpu_err = cpu::build_grid(&params, &splats).unwrap_err().to_string();
    let buf = gpu.storage("splats", &splats).unwrap();
    let gpu_err = build_grid(&gpu, &params, &buf)
        .err()
        .expect("GPU build should refuse")
        .to_string();
    for msg in [cpu_err, gpu_err] {
        assert!(msg.contains("4097 splats overlap one grid cell"), "{msg}");
    }
}

/// `floor_cell`, the mirror's cell of a point without `floorf`, is `floor` then the saturating
/// cast for every kind of value: integers and their neighbours, both zeros, halves, NaN, the
/// infinities, the edges of i32, and a sweep of ordinary coordinates.
#[test]
fn floor_cell_is_floor_for_every_kind_of_value() {
    let mut values = vec![
        0.0f32,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        f32::MIN,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        2147483648.0,
        -2147483648.0,
        2147483520.0,
        -2147483904.0,
        16777217.0,
    ];
    for k in -2000..2000 {
        let x = k as f32 * 0.37;
        values.extend([
            x,
            x.next_up(),
            x.next_down(),
            x.round(),
            x.round().next_down(),
        ]);
    }
    for x in values {
        let v = glam::Vec3::new(x, -x, x * 0.5);
        assert_eq!(floor_cell(v), v.floor().as_ivec3(), "{x}");
    }
}
