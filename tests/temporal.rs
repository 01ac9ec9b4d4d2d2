//! The moving frames' temporal pass (docs/design.md §8, "Moving frames"): parity with its
//! mirror, reprojection that finds where a surface was, and no trail beyond the neighbourhood
//! clamp after a fast pan (history rejected where the motion uncovered another surface).

mod common;

use glam::{Vec2, Vec3};
use lobelight::camera::View;
use lobelight::cpu::exec::CpuExecutor;
use lobelight::frame::temporal_params;
use lobelight::gpu::Gpu;
use lobelight::gpu::exec::GpuExecutor;
use lobelight::scene::file::CameraDesc;
use lobelight::sequence::{Executor, TemporalHistory, temporal};
use lobelight::shared::splat::pixel_ray;
use lobelight::shared::trace::FAR;
use lobelight::types::{Camera, TemporalParams};

const SIZE: u32 = 64;

/// The camera uniform of a pinhole at `eye` looking at `target`, jittered by `jitter` pixels.
fn camera(eye: Vec3, target: Vec3, jitter: [f32; 2]) -> Camera {
    let desc = CameraDesc {
        eye: eye.to_array(),
        target: target.to_array(),
        up: [0.0, 1.0, 0.0],
        fov: 40.0,
        ..CameraDesc::default()
    };
    let view = View::new(&desc, SIZE, SIZE);
    Camera {
        eye: view.eye.to_array(),
        near: 1e-3,
        forward: view.forward.to_array(),
        depth_tolerance: 1.0,
        right: view.right.to_array(),
        tan_x: view.tan_half.x,
        up: view.up.to_array(),
        tan_y: view.tan_half.y,
        size: [SIZE as f32; 2],
        jitter,
        ..Camera::default()
    }
}

/// A scene of two squares facing +z: a far one (z = 0, side 2) and a near one in front of
/// its left half (z = 0.6, side 0.6), each with a smooth colour ramp; outside them, nothing.
/// Returns each pixel's radiance and surface (normal, distance) as `shade` writes them.
fn frame(cam: &Camera) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let eye = Vec3::from(cam.eye);
    let mut hdr = Vec::new();
    let mut surface = Vec::new();
    for i in 0..SIZE * SIZE {
        let px = Vec2::new((i % SIZE) as f32, (i / SIZE) as f32);
        let d = pixel_ray(cam, px + 0.5);
        let hit = |z: f32, centre: Vec2, half: f32| {
            let t = (z - eye.z) / d.z;
            let p = eye + t * d;
            let inside = (p.truncate() - centre).abs().max_element() <= half;
            (t > 0.0 && inside).then_some((t, p))
        };
        let near = hit(0.6, Vec2::new(-0.4, 0.0), 0.3);
        let far = hit(0.0, Vec2::ZERO, 1.0);
        let (c, s) = match (near, far) {
            (Some((t, p)), _) => ([2.0 + p.x, 1.0 + 0.5 * p.y, 0.5, 1.0], [0.0, 0.0, 1.0, t]),
            (None, Some((t, p))) => (
                [
                    0.5 + 0.4 * (8.0 * p.x).sin(),
                    0.4,
                    0.6 + 0.3 * (6.0 * p.y).cos(),
                    1.0,
                ],
                [0.0, 0.0, 1.0, t],
            ),
            _ => ([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, FAR]),
        };
        hdr.push(c);
        surface.push(s);
    }
    (hdr, surface)
}

/// The temporal pass of `hdr`/`surface` after `history` on executor `ex`: the resolved image
/// and the surfaces kept.
#[allow(clippy::too_many_arguments)]
fn resolve<E: Executor>(
    ex: &mut E,
    cam: &Camera,
    prev: &Camera,
    params: &TemporalParams,
    (hdr, surface): (&[[f32; 4]], &[[f32; 4]]),
    (history, history_surface): (&[[f32; 4]], &[[f32; 4]]),
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let n = hdr.len();
    let up = |ex: &mut E, data: &[[f32; 4]]| ex.upload("image", data).unwrap();
    let (hdr_b, surface_b) = (up(ex, hdr), up(ex, surface));
    let (history_b, history_surface_b) = (up(ex, history), up(ex, history_surface));
    let (next_b, next_surface_b) = (
        ex.zeroed("next", n as u64 * 16).unwrap(),
        ex.zeroed("next", n as u64 * 16).unwrap(),
    );
    let last = TemporalHistory {
        image: &history_b,
        surface: &history_surface_b,
    };
    let next = TemporalHistory {
        image: &next_b,
        surface: &next_surface_b,
    };
    temporal(ex, cam, prev, params, &hdr_b, &surface_b, last, next).unwrap();
    let resolved = ex.read::<[f32; 4]>(&hdr_b, n).unwrap();
    let kept = ex.read::<[f32; 4]>(&next_surface_b, n).unwrap();
    (resolved, kept)
}

fn on_mirror(
    cam: &Camera,
    prev: &Camera,
    params: &TemporalParams,
    now: (&[[f32; 4]], &[[f32; 4]]),
    last: (&[[f32; 4]], &[[f32; 4]]),
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    resolve(&mut CpuExecutor::default(), cam, prev, params, now, last)
}

fn on_gpu(
    gpu: &Gpu,
    cam: &Camera,
    prev: &Camera,
    params: &TemporalParams,
    now: (&[[f32; 4]], &[[f32; 4]]),
    last: (&[[f32; 4]], &[[f32; 4]]),
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let mut encoder = gpu.encoder("temporal");
    let mut ex = GpuExecutor::new(gpu, &mut encoder);
    resolve(&mut ex, cam, prev, params, now, last)
}

/// The last frame's camera and this one's: moved sideways and turned a little, jittered.
fn motion() -> (Camera, Camera) {
    let prev = camera(Vec3::new(0.0, 0.1, 3.0), Vec3::ZERO, [0.25, -0.125]);
    let cam = camera(
        Vec3::new(0.12, 0.05, 2.95),
        Vec3::new(0.02, 0.0, 0.0),
        [-0.375, 0.2],
    );
    (cam, prev)
}

/// A resolved history of `frames` frames: the frame's own image, count in w.
fn as_history(hdr: &[[f32; 4]], frames: f32) -> Vec<[f32; 4]> {
    hdr.iter().map(|c| [c[0], c[1], c[2], frames]).collect()
}

#[test]
fn the_temporal_pass_matches_its_mirror() {
    let gpu = common::gpu();
    let (cam, prev) = motion();
    let now = frame(&cam);
    let last = frame(&prev);
    let history = as_history(&last.0, 5.0);
    for reset in [false, true] {
        let params = temporal_params(SIZE, SIZE, reset);
        let g = on_gpu(
            &gpu,
            &cam,
            &prev,
            &params,
            (&now.0, &now.1),
            (&history, &last.1),
        );
        let c = on_mirror(&cam, &prev, &params, (&now.0, &now.1), (&history, &last.1));
        // Within 1e-5 relative where the device rounds as the mirror does (llvmpipe fuses the
        // bilinear sums' multiply-adds: 0.4 came back 0.39999998), else 1e-4 (a GPU's fused
        // multiply-adds also move a reprojected position by ~1e-6 pixel).
        let tolerance = if common::rounds_like_the_mirror(&gpu) {
            1e-5
        } else {
            1e-4
        };
        let mut worst = 0.0f32;
        for (i, (a, b)) in g.0.iter().zip(&c.0).chain(g.1.iter().zip(&c.1)).enumerate() {
            for k in 0..4 {
                let d = (a[k] - b[k]).abs() / b[k].abs().max(1e-3);
                assert!(
                    d <= tolerance,
                    "reset {reset}, value {i}: {a:?} against {b:?}"
                );
                worst = worst.max(d);
            }
        }
        eprintln!("reset {reset}: largest relative difference {worst:e}");
    }
}

/// With the last frame's exact image as a long history, the resolved image of a pixel inside
/// one surface is this frame's within the error of bilinear resampling: the pass looked where
/// the surface was. (Looked where the pixel was, it would lag by the motion, ~3 pixels here.)
#[test]
fn reprojection_finds_where_the_surface_was() {
    let (cam, prev) = motion();
    let now = frame(&cam);
    // A resolved history holds each pixel's centre (the mean of its jittered samples).
    let centred = |c: &Camera| {
        frame(&Camera {
            jitter: [0.0; 2],
            ..*c
        })
    };
    let last = centred(&prev);
    let truth = centred(&cam);
    let history = as_history(&last.0, 15.0);
    let params = temporal_params(SIZE, SIZE, false);
    let (resolved, _) = on_mirror(&cam, &prev, &params, (&now.0, &now.1), (&history, &last.1));
    let s = SIZE as i32;
    let mut checked = 0;
    let mut worst = 0.0f32;
    for y in 3..s - 3 {
        for x in 3..s - 3 {
            // Inside one surface: the same distance class over a 7×7 neighbourhood.
            let class = |x: i32, y: i32| now.1[(y * s + x) as usize][3] < 2.7;
            let same = (-3..=3).all(|dy| (-3..=3).all(|dx| class(x + dx, y + dy) == class(x, y)));
            let i = (y * s + x) as usize;
            if !same || now.1[i][3] >= FAR {
                continue;
            }
            let frames = resolved[i][3];
            assert!(
                frames > 15.99,
                "pixel ({x}, {y}) lost its history: {frames}"
            );
            // About the history's 15/16 at the pixel's centre, this frame's 1/16 at its sample
            // (the blend weighs them by luminance too).
            for (k, v) in resolved[i][..3].iter().enumerate() {
                let expected = (15.0 * truth.0[i][k] + now.0[i][k]) / 16.0;
                worst = worst.max((v - expected).abs());
            }
            checked += 1;
        }
    }
    eprintln!("{checked} pixels: largest difference {worst}");
    assert!(checked > 1000, "{checked}");
    assert!(worst < 0.02, "{worst}");
}

/// A fast pan (the near square moves 12 pixels across the far one) after a long history: the
/// near square's bright colour (red above 1.6) leaves no trail where the far one now shows
/// (red at most 0.9): each resolved pixel lies within its neighbourhood's range in this frame
/// (the clamp's bound), and where that neighbourhood is all far square, within 5 % of this
/// frame's light (its colour ramp varies by about that over 3 pixels). Run on the device and
/// the mirror.
#[test]
fn a_fast_pan_leaves_no_trail() {
    let gpu = common::gpu();
    let prev = camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, [0.0; 2]);
    let cam = camera(
        Vec3::new(-0.5, 0.0, 3.0),
        Vec3::new(-0.5, 0.0, 0.0),
        [0.25, 0.25],
    );
    let now = frame(&cam);
    let last = frame(&prev);
    let history = as_history(&last.0, 15.0);
    let params = temporal_params(SIZE, SIZE, false);
    let on_cpu = on_mirror(&cam, &prev, &params, (&now.0, &now.1), (&history, &last.1));
    let on_device = on_gpu(
        &gpu,
        &cam,
        &prev,
        &params,
        (&now.0, &now.1),
        (&history, &last.1),
    );
    let s = SIZE as i32;
    let at = |x: i32, y: i32| (y.clamp(0, s - 1) * s + x.clamp(0, s - 1)) as usize;
    for (what, (resolved, _)) in [("mirror", &on_cpu), ("device", &on_device)] {
        let mut trail = 0;
        for y in 0..s {
            for x in 0..s {
                let i = at(x, y);
                // The clamp's neighbourhood: the pixel and its four edge neighbours.
                let steps = [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)];
                let around: Vec<usize> = steps.iter().map(|(dx, dy)| at(x + dx, y + dy)).collect();
                for (k, &v) in resolved[i][..3].iter().enumerate() {
                    let lo = around.iter().map(|&j| now.0[j][k]).fold(f32::MAX, f32::min);
                    let hi = around.iter().map(|&j| now.0[j][k]).fold(f32::MIN, f32::max);
                    assert!(
                        v >= lo - 1e-5 && v <= hi + 1e-5,
                        "{what}: pixel ({x}, {y}) channel {k}: {v} outside {lo}..{hi}"
                    );
                }
                let far = |j: usize| now.1[j][3] > 2.7 && now.1[j][3] < FAR;
                let was_near = last.0[i][0] > 1.6;
                if around.iter().all(|&j| far(j)) && was_near {
                    trail += 1;
                    assert!(resolved[i][0] <= 0.9 + 1e-5, "{what}: ({x}, {y}) trails");
                    let l = |c: &[f32; 4]| c[0] + c[1] + c[2];
                    let rel = (l(&resolved[i]) - l(&now.0[i])).abs() / l(&now.0[i]);
                    assert!(rel <= 0.05, "{what}: ({x}, {y}) {rel}");
                }
            }
        }
        eprintln!("{what}: {trail} pixels where the near square was and the far one shows");
        assert!(trail > 50, "the pan uncovers too little to test: {trail}");
    }
}
