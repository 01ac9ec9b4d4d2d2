//! Ray traversal through the splat grid: the DDA with empty-space skipping finds exactly the
//! nearest hit a brute-force loop over all disks finds; the GPU stage `trace_rays` agrees with
//! its CPU mirror; and the documented hit policy holds (back faces, parallel and grazing rays,
//! coplanar overlapping disks, the skipped disk, t_max, the iteration budget).

mod common;

use glam::Vec3;
use lobelight::cpu::{self, groups_for, trace_rays};
use lobelight::gpu::Gpu;
use lobelight::gpu::grid::build_grid;
use lobelight::gpu::scene::device_clips;
use lobelight::grid::{
    DIST_MASK, GridConfig, SplatGrid, cell_index, cone_faces_away, grid_params, point_cell,
};
use lobelight::photons::ITERATION_BUDGET;
use lobelight::shaders::Stage;
use lobelight::shared::trace::{Geometry, intersect_disk, trace_ray};
use lobelight::types::{Hit, NO_SPLAT, Ray, Splat, SurfaceClip, TraceParams};

fn cpu_grid(splats: &[Splat]) -> SplatGrid {
    cpu::build_grid(
        &grid_params(splats, &GridConfig::default()).unwrap(),
        splats,
    )
    .unwrap()
}

fn params(rays: usize, budget: u32) -> TraceParams {
    TraceParams {
        path_count: rays as u32,
        iteration_budget: budget,
        ..Default::default()
    }
}

fn cpu_trace(splats: &[Splat], clips: &[SurfaceClip], rays: &[Ray], budget: u32) -> Vec<Hit> {
    let grid = cpu_grid(splats);
    let geo = Geometry {
        grid: &grid,
        splats,
        clips,
        sky: &[[0.0; 4]],
    };
    let mut hits = vec![Hit::default(); rays.len()];
    let groups = groups_for(rays.len() as u32, trace_rays::WG);
    trace_rays::trace_rays(&params(rays.len(), budget), rays, &mut hits, &geo, groups);
    hits
}

fn gpu_trace(
    gpu: &Gpu,
    splats: &[Splat],
    clips: &[SurfaceClip],
    rays: &[Ray],
    budget: u32,
) -> Vec<Hit> {
    let p = grid_params(splats, &GridConfig::default()).unwrap();
    let splat_buf = gpu.storage("splats", splats).unwrap();
    let clip_buf = gpu
        .storage("surface clips", &device_clips(clips, splats))
        .unwrap();
    let grid = build_grid(gpu, &p, &splat_buf).unwrap();
    let sky_buf = gpu.storage("sky", &[[0.0f32; 4]]).unwrap();
    let params_buf = gpu.uniform("trace params", &params(rays.len(), budget));
    let ray_buf = gpu.storage("rays", rays).unwrap();
    let hit_buf = gpu
        .storage_zeroed("hits", (rays.len() * std::mem::size_of::<Hit>()) as u64)
        .unwrap();
    let mut encoder = gpu.encoder("trace test");
    gpu.dispatch_groups(
        &mut encoder,
        Stage::TraceRays,
        &[
            &[&params_buf, &ray_buf, &hit_buf],
            &[
                &grid.params_buf,
                &splat_buf,
                &grid.cell_start,
                &grid.cell_splats,
                &grid.cell_dist,
                &clip_buf,
                &sky_buf,
            ],
        ],
        groups_for(rays.len() as u32, trace_rays::WG),
    )
    .unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    gpu.read(&hit_buf, rays.len()).unwrap()
}

/// The nearest front-facing hit over all disks, by the same disk test.
fn brute_force(splats: &[Splat], r: &Ray) -> (f32, u32) {
    brute_force_clipped(splats, &[], r)
}

/// `brute_force` where the surfaces' clips keep the hit.
fn brute_force_clipped(splats: &[Splat], clips: &[SurfaceClip], r: &Ray) -> (f32, u32) {
    let (o, d) = (Vec3::from(r.origin), Vec3::from(r.direction));
    let mut best = (r.t_max, NO_SPLAT);
    for (i, s) in splats.iter().enumerate() {
        if i as u32 == r.skip {
            continue;
        }
        let t = intersect_disk(s, o, d);
        let kept = |p: Vec3| clips.get(s.object as usize).is_none_or(|c| c.keeps(p));
        let t = if t > 0.0 && kept(o + t * d) { t } else { -1.0 };
        if t > 0.0 && t < best.0 {
            best = (t, i as u32);
        }
    }
    best
}

/// Rays from random points inside and outside the splats' box, some aimed at disk centres.
fn random_rays(splats: &[Splat], n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = common::Rng(seed);
    (0..n)
        .map(|k| {
            let origin = [
                rng.range(-1.6, 1.6),
                rng.range(-1.6, 1.6),
                rng.range(-1.6, 1.6),
            ];
            let direction = if k % 3 == 0 {
                let target =
                    Vec3::from(splats[(rng.next_u64() % splats.len() as u64) as usize].center);
                (target - Vec3::from(origin)).normalize().to_array()
            } else {
                rng.unit_vector()
            };
            Ray {
                origin,
                t_max: if k % 5 == 0 {
                    rng.range(0.1, 2.0)
                } else {
                    1e30
                },
                direction,
                skip: if k % 7 == 0 {
                    (rng.next_u64() % splats.len() as u64) as u32
                } else {
                    NO_SPLAT
                },
            }
        })
        .collect()
}

fn scenes() -> Vec<(&'static str, Vec<Splat>)> {
    let mut mixture = common::random_splats(20_000, 0.002, 0.01, 21);
    mixture.extend(common::random_splats(40, 0.3, 0.7, 22));
    vec![
        (
            "sparse small disks",
            common::random_splats(3_000, 0.01, 0.05, 23),
        ),
        (
            "dense mixed radii",
            common::random_splats(20_000, 0.005, 0.1, 24),
        ),
        ("tiny disks and huge ones", mixture),
    ]
}

#[test]
fn traversal_finds_the_nearest_hit_of_brute_force() {
    for (name, splats) in scenes() {
        let rays = random_rays(&splats, 4_000, 31);
        let hits = cpu_trace(&splats, &[], &rays, ITERATION_BUDGET);
        let mut hit_count = 0;
        for (k, (r, h)) in rays.iter().zip(&hits).enumerate() {
            assert_eq!(h.aborted, 0, "{name}: ray {k} aborted");
            let (t, s) = brute_force(&splats, r);
            if s != NO_SPLAT {
                hit_count += 1;
            }
            // Ties between disks at the same t may pick either; the distance must agree.
            let same = h.splat == s
                || (h.splat != NO_SPLAT && s != NO_SPLAT && (h.t - t).abs() <= 1e-5 * t.max(1.0));
            assert!(
                same,
                "{name}: ray {k}: traversal ({}, {}) vs brute force ({s}, {t})",
                h.splat, h.t
            );
        }
        eprintln!("{name}: {hit_count} of {} rays hit", rays.len());
        assert!(
            hit_count > rays.len() / 10,
            "{name}: too few hits to test anything"
        );
    }
}

/// How far apart two devices' f32 distances to one disk may lie: t = n·(c − o) / n·d, whose
/// denominator keeps a relative precision of about ε / |cos| at incidence cos = n·d, so that a
/// grazing ray's t moves with a device's rounding (an H100 measured 3.4e-5 relatively at
/// cos 4e-4, where lavapipe agrees with the mirror bit for bit); 1e-5 elsewhere.
fn t_tolerance(t: f32, cos: f32) -> f32 {
    1e-5 * t.abs().max(1.0) + 4.0 * f32::EPSILON * t.abs() / cos.abs().max(1e-6)
}

#[test]
fn gpu_trace_rays_equals_cpu_mirror() {
    let gpu = common::gpu();
    for (name, splats) in scenes() {
        let rays = random_rays(&splats, 20_000, 41);
        let on_cpu = cpu_trace(&splats, &[], &rays, ITERATION_BUDGET);
        let on_gpu = gpu_trace(&gpu, &splats, &[], &rays, ITERATION_BUDGET);
        let mut differ = 0;
        for (k, (a, b)) in on_gpu.iter().zip(&on_cpu).enumerate() {
            let cos = splats.get(b.splat as usize).map_or(1.0, |s| {
                Vec3::from(s.normal).dot(Vec3::from(rays[k].direction))
            });
            let near = (a.t - b.t).abs() <= t_tolerance(b.t, cos);
            // Two disks crossing at the hit point: either is the nearest.
            let tie = a.splat != NO_SPLAT && b.splat != NO_SPLAT && near;
            let same = (a.splat == b.splat || tie) && a.aborted == b.aborted && near;
            if !same {
                differ += 1;
                eprintln!("{name}: ray {k}: GPU {a:?} vs CPU {b:?}; cos {cos:.4}");
            }
        }
        // Float rounding may differ (a device may fuse multiply-adds), so a hit at a disk's
        // rim can flip.
        assert!(
            differ * 10_000 <= rays.len(),
            "{name}: {differ} of {} rays differ",
            rays.len()
        );
    }
}

fn disk(center: [f32; 3], radius: f32, normal: [f32; 3]) -> Splat {
    Splat {
        center,
        radius,
        normal,
        ..Default::default()
    }
}

fn ray(origin: [f32; 3], direction: [f32; 3], skip: u32) -> Ray {
    Ray {
        origin,
        t_max: 1e30,
        direction: Vec3::from(direction).normalize().to_array(),
        skip,
    }
}

/// The documented policy, on a small hand-made scene, on the CPU and on the GPU.
#[test]
fn hit_policy_is_as_documented() {
    let splats = vec![
        // 0, 1: coplanar overlapping disks in z = 0 facing +z (0 has the lower index).
        disk([0.0, 0.0, 0.0], 0.3, [0.0, 0.0, 1.0]),
        disk([0.1, 0.0, 0.0], 0.3, [0.0, 0.0, 1.0]),
        // 2: a disk at z = -1 facing +z, behind the first two.
        disk([0.0, 0.0, -1.0], 0.5, [0.0, 0.0, 1.0]),
        // 3: a disk at z = 1 facing +z: seen from below it is a back face.
        disk([0.0, 0.0, 1.0], 0.5, [0.0, 0.0, 1.0]),
        // 4: a lone disk in the plane x = 2 facing +x, for parallel and grazing rays.
        disk([2.0, 0.0, 0.0], 0.5, [1.0, 0.0, 0.0]),
        // 5: padding far away so the grid has some extent.
        disk([-2.0, -2.0, -2.0], 0.1, [0.0, 1.0, 0.0]),
    ];
    let cases: Vec<(&str, Ray, u32)> = vec![
        (
            "coplanar overlap: lowest index wins",
            ray([0.05, 0.0, 0.5], [0.0, 0.0, -1.0], NO_SPLAT),
            0,
        ),
        (
            "back face is transparent",
            ray([0.0, 0.0, 0.5], [0.0, 0.0, 1.0], NO_SPLAT),
            NO_SPLAT,
        ),
        (
            "from below: back of 3 passes, front of nothing",
            ray([0.0, 0.0, -0.5], [0.0, 0.0, 1.0], NO_SPLAT),
            NO_SPLAT,
        ),
        (
            "leaving disk 0: its coplanar neighbour is behind",
            ray([0.05, 0.0, 0.0], [0.3, 0.0, 1.0], 0),
            NO_SPLAT,
        ),
        (
            "skipped disk is ignored, the next one counts",
            ray([0.05, 0.0, 0.5], [0.0, 0.0, -1.0], 0),
            1,
        ),
        (
            "skipping both coplanar disks reaches the one behind",
            ray([-0.25, 0.0, 0.5], [0.0, 0.0, -1.0], 0),
            2,
        ),
        (
            "parallel to a disk's plane misses it",
            ray([2.0, -1.0, 0.0], [0.0, 1.0, 0.0], NO_SPLAT),
            NO_SPLAT,
        ),
        (
            "grazing (1e-3 rad) from the front hits",
            ray([2.0005, -0.4, 0.0], [-1e-3, 1.0, 0.0], NO_SPLAT),
            4,
        ),
        (
            "grazing from the back misses",
            ray([1.9995, -0.4, 0.0], [1e-3, 1.0, 0.0], NO_SPLAT),
            NO_SPLAT,
        ),
    ];
    let rays: Vec<Ray> = cases.iter().map(|c| c.1).collect();
    let gpu = common::gpu();
    let on_cpu = cpu_trace(&splats, &[], &rays, ITERATION_BUDGET);
    let on_gpu = gpu_trace(&gpu, &splats, &[], &rays, ITERATION_BUDGET);
    for (k, (what, r, expected)) in cases.iter().enumerate() {
        assert_eq!(on_cpu[k].splat, *expected, "CPU: {what}");
        assert_eq!(on_gpu[k].splat, *expected, "GPU: {what}");
        assert_eq!(brute_force(&splats, r).1, *expected, "brute force: {what}");
    }
    // t_max: the disk at t = 1.5 is beyond a limit of 1.
    let mut limited = ray([0.0, 0.0, 0.5], [0.0, 0.0, -1.0], 0);
    limited.skip = 0;
    limited.t_max = 1.0;
    let skip_both = Ray { skip: 1, ..limited };
    let h = cpu_trace(&splats, &[], &[limited, skip_both], ITERATION_BUDGET);
    assert_eq!(
        h[0].splat, 1,
        "t_max: the coplanar neighbour at t = 0.5 is within"
    );
    let far = Ray {
        t_max: 1.0,
        ..ray([-0.35, 0.0, 0.5], [0.0, 0.0, -1.0], NO_SPLAT)
    };
    let h = cpu_trace(&splats, &[], &[far], ITERATION_BUDGET);
    assert_eq!(h[0].splat, NO_SPLAT, "t_max: disk 2 at t = 1.5 is beyond 1");
}

#[test]
fn budget_stops_a_ray_and_says_so() {
    let gpu = common::gpu();
    let splats = common::random_splats(20_000, 0.005, 0.05, 51);
    // A ray through the whole cloud needs far more than 3 steps.
    let rays = vec![ray([-1.5, -1.5, -1.5], [1.0, 1.0, 1.0], NO_SPLAT)];
    for hits in [
        cpu_trace(&splats, &[], &rays, 3),
        gpu_trace(&gpu, &splats, &[], &rays, 3),
    ] {
        assert_eq!(hits[0].aborted, 1);
        assert_eq!(hits[0].splat, NO_SPLAT);
    }
    let full = cpu_trace(&splats, &[], &rays, ITERATION_BUDGET);
    assert_eq!(full[0].aborted, 0);
    assert_ne!(full[0].splat, NO_SPLAT);
}

/// A grid of a real scene (the Cornell box) with a whole direct-light pass's worth of rays:
/// the trace must agree with brute force there too, where long empty stretches are skipped.
#[test]
fn traversal_on_the_cornell_box() {
    let scene = lobelight::scene::load(std::path::Path::new("scenes/cornell.toml")).unwrap();
    let splats = &scene.splats;
    let grid = cpu_grid(splats);
    let geo = scene.geometry(&grid);
    let rays = random_rays(splats, 2_000, 61);
    for (k, r) in rays.iter().enumerate() {
        let mut budget = ITERATION_BUDGET;
        let h = trace_ray(
            &geo,
            Vec3::from(r.origin),
            Vec3::from(r.direction),
            r.skip,
            r.t_max,
            &mut budget,
        );
        let (t, s) = brute_force_clipped(splats, &scene.clips, r);
        let same = h.splat == s
            || (h.splat != NO_SPLAT && s != NO_SPLAT && (h.t - t).abs() <= 1e-5 * t.max(1.0));
        assert!(
            same,
            "ray {k}: traversal ({}, {}) vs brute force ({s}, {t})",
            h.splat, h.t
        );
    }
}

/// A box's disks end at its edges (`SurfaceClip`): a ray falling past the box's side, through
/// where the top face's disks overhang it, meets nothing, on the device and the mirror, while a
/// ray just inside the edge, or on it, still meets the top face. Unclipped, the overhang would
/// stop the first ray though a ray from the side face below passes it from behind.
#[test]
fn box_disks_end_at_the_box_edges() {
    let scene = common::lit_box("", [0.0, 2.0, 0.0], 1.0);
    // The top face's disks on the row z = 0.0125 reach x = 0.2875 + 0.0186 past the side x = 0.3.
    let overhang = scene
        .splats
        .iter()
        .filter(|s| s.normal[1] > 0.5)
        .map(|s| s.center[0] + s.radius)
        .fold(f32::MIN, f32::max);
    assert!(
        overhang > 0.305,
        "the top face's disks reach x = {overhang}"
    );
    let down = |x: f32| ray([x, 1.0, 0.0125], [0.0, -1.0, 0.0], NO_SPLAT);
    let rays = [down(0.303), down(0.297), down(0.3)];
    let top = |h: &Hit| h.splat != NO_SPLAT && scene.splats[h.splat as usize].normal[1] > 0.5;
    let gpu = common::gpu();
    let on_gpu = gpu_trace(&gpu, &scene.splats, &scene.clips, &rays, ITERATION_BUDGET);
    let on_cpu = cpu_trace(&scene.splats, &scene.clips, &rays, ITERATION_BUDGET);
    for (name, hits) in [("GPU", &on_gpu), ("CPU", &on_cpu)] {
        assert_eq!(
            hits[0].splat, NO_SPLAT,
            "{name}: the ray past the side hit a disk"
        );
        assert!(
            top(&hits[1]),
            "{name}: the ray inside the edge missed the top face"
        );
        assert!(
            top(&hits[2]),
            "{name}: the ray on the edge missed the top face"
        );
        assert!(
            (hits[1].t - 0.7).abs() < 1e-4,
            "{name}: top face at t = {}",
            hits[1].t
        );
    }
    // Without the clips the overhang stops the first ray.
    let unclipped = cpu_trace(&scene.splats, &[], &rays[..1], ITERATION_BUDGET);
    assert!(top(&unclipped[0]), "the overhang did not reach the ray");
}

/// Rays leaving surfaces, the rays the facing cones are for: from each of `count` disks of
/// `splats`, just off its centre, into the hemisphere its normal faces (a shadow ray or a
/// bounce), skipping the disk it leaves.
fn leaving_rays(splats: &[Splat], count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = common::Rng(seed);
    (0..count)
        .map(|_| {
            let i = (rng.next_u64() % splats.len() as u64) as u32;
            let s = &splats[i as usize];
            let n = Vec3::from(s.normal);
            let d = Vec3::from(rng.unit_vector());
            let d = if d.dot(n) < 0.0 { -d } else { d };
            Ray {
                origin: (Vec3::from(s.center) + 0.5 * s.radius * n).to_array(),
                t_max: 1e30,
                direction: d.to_array(),
                skip: i,
            }
        })
        .collect()
}

/// The facing cones change no ray: on the Cornell box and on a sphere of disks, rays leaving
/// the surfaces meet the same disk at the same distance, with the same budget left and the
/// same aborted flag, as through the same grid with its cones taken out, also with a budget
/// that runs out; many of them start in a cell whose cone turns them away; and the device
/// (whose grid build makes its own cones) agrees with the mirror.
#[test]
fn facing_cones_change_no_ray() {
    let gpu = common::gpu();
    let cornell = lobelight::scene::load(std::path::Path::new("scenes/cornell.toml")).unwrap();
    let sphere: Vec<Splat> = common::fibonacci_sphere(20_000)
        .into_iter()
        .map(|p| disk(p.to_array(), 0.025, p.to_array()))
        .collect();
    for (name, splats, clips) in [
        ("cornell", cornell.splats.clone(), cornell.clips.clone()),
        ("sphere", sphere, vec![]),
    ] {
        let grid = cpu_grid(&splats);
        let mut bare = grid.clone();
        bare.cell_dist.iter_mut().for_each(|w| *w &= DIST_MASK);
        let (with, without) = (
            Geometry {
                grid: &grid,
                splats: &splats,
                clips: &clips,
                sky: &[[0.0; 4]],
            },
            Geometry {
                grid: &bare,
                splats: &splats,
                clips: &clips,
                sky: &[[0.0; 4]],
            },
        );
        let rays = leaving_rays(&splats, 4_000, 71);
        let mut turned = 0;
        for (k, r) in rays.iter().enumerate() {
            let (o, d) = (Vec3::from(r.origin), Vec3::from(r.direction));
            let c = point_cell(o, &grid.params)
                .max(glam::IVec3::ZERO)
                .as_uvec3();
            turned +=
                cone_faces_away(grid.cell_dist[cell_index(c, &grid.params) as usize], d) as usize;
            for start_budget in [ITERATION_BUDGET, 40] {
                let (mut a, mut b) = (start_budget, start_budget);
                let ha = trace_ray(&with, o, d, r.skip, r.t_max, &mut a);
                let hb = trace_ray(&without, o, d, r.skip, r.t_max, &mut b);
                assert_eq!((ha, a), (hb, b), "{name}: ray {k}, budget {start_budget}");
            }
        }
        eprintln!(
            "{name}: {turned} of {} rays start in a cell that turns them away",
            rays.len()
        );
        assert!(turned * 4 > rays.len(), "{name}: too few rays meet a cone");
        let on_cpu = cpu_trace(&splats, &clips, &rays, ITERATION_BUDGET);
        let on_gpu = gpu_trace(&gpu, &splats, &clips, &rays, ITERATION_BUDGET);
        let differ = on_cpu
            .iter()
            .zip(&on_gpu)
            .filter(|(a, b)| {
                a.splat != b.splat
                    || a.aborted != b.aborted
                    || (a.t - b.t).abs() > t_tolerance(a.t, 1e-3)
            })
            .count();
        assert!(
            differ * 1_000 <= rays.len(),
            "{name}: {differ} rays differ on the device"
        );
    }
}
