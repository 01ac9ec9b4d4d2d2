//! The moving frames' temporal pass (docs/design.md §8, "Moving frames"): parity with its
//! mirror, reprojection that finds where a surface was, history kept on an edge the jitter
//! crosses, and no trail beyond the neighbourhood clamp after a fast pan (history rejected
//! where the motion uncovered another surface).

mod common;

use glam::{Vec2, Vec3};
use lobelight::camera::View;
use lobelight::cpu::exec::CpuExecutor;
use lobelight::cpu::temporal::frame_exposure;
use lobelight::frame::temporal_params;
use lobelight::gpu::Gpu;
use lobelight::gpu::exec::GpuExecutor;
use lobelight::scene::file::CameraDesc;
use lobelight::sequence::{Executor, TemporalHistory, temporal};
use lobelight::shared::splat::pixel_ray;
use lobelight::shared::tone::{log_luminance, luminance};
use lobelight::shared::trace::FAR;
use lobelight::tone::LOG_EPSILON;
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

/// An image and its surfaces, read.
type Images<'a> = (&'a [[f32; 4]], &'a [[f32; 4]]);
/// The pass on one executor: this frame and the history in, the resolved image and the
/// surfaces kept out (`on_mirror`, `on_gpu`).
type Resolver<'a> = dyn FnMut(&Camera, &Camera, &TemporalParams, Images, Images) -> (Vec<[f32; 4]>, Vec<[f32; 4]>)
    + 'a;

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

/// The pass on the mirror and the device, named, after a history of 15 frames of `last` (its
/// image and surfaces): the resolved images.
fn after_long_history(
    gpu: &Gpu,
    cam: &Camera,
    prev: &Camera,
    now: &(Vec<[f32; 4]>, Vec<[f32; 4]>),
    last: &(Vec<[f32; 4]>, Vec<[f32; 4]>),
) -> [(&'static str, Vec<[f32; 4]>); 2] {
    let history = as_history(&last.0, 15.0);
    let params = temporal_params(SIZE, SIZE, false);
    let (now, last) = ((&now.0[..], &now.1[..]), (&history[..], &last.1[..]));
    [
        ("mirror", on_mirror(cam, prev, &params, now, last).0),
        ("device", on_gpu(gpu, cam, prev, &params, now, last).0),
    ]
}

/// The exposure the pass weighs `hdr`'s colours by: the tone map's default key over its
/// log-average luminance.
fn display_exposure(hdr: &[[f32; 4]]) -> f32 {
    let sum = hdr.iter().fold(Vec2::ZERO, |s, c| {
        s + log_luminance(Vec3::from_slice(&c[..3]), LOG_EPSILON)
    });
    frame_exposure(sum.to_array())
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
        // Within 1e-4 of the largest value of the pixel's neighbourhood in this frame. Where the
        // history's taps straddle an edge (the neighbours' surfaces keep both sides), the colour
        // moves with the reprojected position times the edge's contrast, and a position near
        // pixel 64 is rounded at 7.6e-6 pixel: the device's fused multiply-adds (llvmpipe's
        // too) put it up to a few of those apart, 2e-5 of the contrast measured on llvmpipe.
        let tolerance = 1e-4;
        let s = SIZE as usize;
        let scale = |i: usize, k: usize| {
            let (x, y) = (i % s, i / s);
            let around = [(x, y), (x.saturating_sub(1), y), ((x + 1).min(s - 1), y)]
                .into_iter()
                .chain([(x, y.saturating_sub(1)), (x, (y + 1).min(s - 1))]);
            around
                .map(|(x, y)| now.0[y * s + x][k].abs())
                .fold(1e-3, f32::max)
        };
        let mut worst = 0.0f32;
        for (i, (a, b)) in g.0.iter().zip(&c.0).enumerate() {
            for k in 0..4 {
                let d = (a[k] - b[k]).abs() / b[k].abs().max(scale(i, k));
                assert!(
                    d <= tolerance,
                    "reset {reset}, value {i}: {a:?} against {b:?}"
                );
                worst = worst.max(d);
            }
        }
        // The surfaces kept are the frame's own, copied.
        assert_eq!(g.1, c.1, "reset {reset}: surfaces kept");
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

/// A still camera whose jitter moves each sample by 0.8 pixel: the pixels on the squares'
/// edges now show the other side of the edge than they did. Their history shows a surface
/// that an edge neighbour shows now, within the pixel's footprint, so it is kept (held to the
/// pixel's own surface, it was dropped, and such edges showed this frame's sample alone: the
/// orbit's error spikes): 16 frames, and this frame blended with the clamped history. Run on
/// the device and the mirror.
#[test]
fn an_edge_the_jitter_crosses_keeps_its_history() {
    let gpu = common::gpu();
    let eye = Vec3::new(0.0, 0.1, 3.0);
    let prev = camera(eye, Vec3::ZERO, [-0.4, -0.4]);
    let cam = camera(eye, Vec3::ZERO, [0.4, 0.4]);
    let (now, last) = (frame(&cam), frame(&prev));
    let resolved = after_long_history(&gpu, &cam, &prev, &now, &last);
    let s = SIZE as i32;
    let at = |x: i32, y: i32| (y.clamp(0, s - 1) * s + x.clamp(0, s - 1)) as usize;
    // The pass weighs colours as displayed: their luminance times the frame's exposure.
    let exposure = display_exposure(&now.0);
    let weight = |c: Vec3| 1.0 / (1.0 + exposure * luminance(c).max(0.0));
    for (what, resolved) in &resolved {
        let mut crossed = 0;
        for y in 0..s {
            for x in 0..s {
                let i = at(x, y);
                // Near square, far square or nothing.
                let class = |t: f32| (t >= 2.7) as u8 + (t >= FAR) as u8;
                let was = class(last.1[i][3]);
                let cross =
                    [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)].map(|(dx, dy)| at(x + dx, y + dy));
                // Where the sample crossed an edge and an edge neighbour shows the other side
                // (at a corner none may: the diagonal one does).
                let beside = cross.iter().any(|&j| class(now.1[j][3]) == was);
                if class(now.1[i][3]) == was || !beside {
                    continue;
                }
                crossed += 1;
                let around = cross.map(|j| Vec3::from_slice(&now.0[j][..3]));
                let lo = around.iter().copied().fold(Vec3::MAX, Vec3::min);
                let hi = around.iter().copied().fold(Vec3::MIN, Vec3::max);
                let current = around[0];
                let kept = Vec3::from_slice(&last.0[i][..3]).clamp(lo, hi);
                let (wc, wh) = (weight(current) / 16.0, weight(kept) * 15.0 / 16.0);
                let expected = (wc * current + wh * kept) / (wc + wh);
                let got = Vec3::from_slice(&resolved[i][..3]);
                assert_eq!(resolved[i][3], 16.0, "{what}: ({x}, {y}) lost its history");
                assert!(
                    (got - expected).abs().max_element() <= 1e-4 * hi.max_element(),
                    "{what}: ({x}, {y}) {got} against {expected}"
                );
            }
        }
        eprintln!("{what}: {crossed} pixels whose sample crossed an edge");
        assert!(
            crossed > 40,
            "the jitter crosses too few edges to test: {crossed}"
        );
    }
}

/// A pan (the near square moves about 9 pixels, the far one about 7; this frame's jitter puts
/// the samples near the pixels' right edges): beside the near square's edge a pixel may show
/// the far square while an edge neighbour shows the near one, and its history the near one.
/// That history is kept only where what it showed lies within the pixel's footprint now; so a
/// pixel whose whole footprint shows the far square (16 samples across it) holds none of the
/// near square's colour (red above 1.3; the far square's is at most 0.9). Run on the device
/// and the mirror.
#[test]
fn a_pan_keeps_no_history_of_what_left_the_pixel() {
    let gpu = common::gpu();
    let prev = camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, [0.1, -0.2]);
    let cam = camera(
        Vec3::new(-0.25, 0.0, 3.0),
        Vec3::new(-0.25, 0.0, 0.0),
        [0.45, 0.15],
    );
    let (now, last) = (frame(&cam), frame(&prev));
    let resolved = after_long_history(&gpu, &cam, &prev, &now, &last);
    // Per pixel, whether 4 × 4 samples across its footprint all show the far square.
    let near = |t: f32| t < 2.7;
    let mut all_far = vec![true; (SIZE * SIZE) as usize];
    for k in 0..16 {
        let offset = [(k % 4) as f32 * 0.25 - 0.375, (k / 4) as f32 * 0.25 - 0.375];
        let (_, surface) = frame(&Camera {
            jitter: offset,
            ..cam
        });
        for (far, s) in all_far.iter_mut().zip(&surface) {
            *far &= !near(s[3]) && s[3] < FAR;
        }
    }
    let s = SIZE as i32;
    let at = |x: i32, y: i32| (y.clamp(0, s - 1) * s + x.clamp(0, s - 1)) as usize;
    for (what, resolved) in &resolved {
        let mut beside = 0;
        for y in 0..s {
            for x in 0..s {
                let i = at(x, y);
                let steps = [(1, 0), (-1, 0), (0, 1), (0, -1)];
                if !all_far[i]
                    || !steps
                        .iter()
                        .any(|(dx, dy)| near(now.1[at(x + dx, y + dy)][3]))
                {
                    continue;
                }
                beside += 1;
                assert!(
                    resolved[i][0] <= 0.9 + 1e-5,
                    "{what}: ({x}, {y}) {:?}",
                    resolved[i]
                );
            }
        }
        eprintln!("{what}: {beside} far pixels beside the near square");
        assert!(
            beside > 20,
            "too few pixels beside the near square: {beside}"
        );
    }
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
    let resolved = after_long_history(&gpu, &cam, &prev, &now, &last);
    let s = SIZE as i32;
    let at = |x: i32, y: i32| (y.clamp(0, s - 1) * s + x.clamp(0, s - 1)) as usize;
    for (what, resolved) in &resolved {
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

/// The pass weighs colours as they are displayed, their luminance times the frame's exposure
/// (the tone map's key over its log-average): a frame and its history k times as bright
/// resolve to k times the image, whatever the lights' power. Weighed by their luminance alone,
/// a dim scene's colours (the bunny's, well below 1) were blended nearly unweighted and a
/// bright one's weighed down: 10 times as bright, this image's edge pixels moved by up to 46 %.
/// Run on the device and the mirror.
#[test]
fn the_weights_follow_the_exposure_not_the_lights_power() {
    let gpu = common::gpu();
    let (cam, prev) = motion();
    // A sky where the squares are not: the log-average's ε (the tone map's) weighs black
    // pixels alike at any brightness.
    let with_sky = |(hdr, surface): (Vec<[f32; 4]>, Vec<[f32; 4]>)| {
        let hdr: Vec<[f32; 4]> = hdr
            .iter()
            .zip(&surface)
            .map(|(c, s)| {
                if s[3] >= FAR {
                    [0.05, 0.06, 0.08, c[3]]
                } else {
                    *c
                }
            })
            .collect();
        (hdr, surface)
    };
    let (now, last) = (with_sky(frame(&cam)), with_sky(frame(&prev)));
    let scaled = |img: &[[f32; 4]], k: f32| -> Vec<[f32; 4]> {
        img.iter()
            .map(|c| [k * c[0], k * c[1], k * c[2], c[3]])
            .collect()
    };
    let k = 10.0;
    let bright = (scaled(&now.0, k), now.1.clone());
    let bright_last = (scaled(&last.0, k), last.1.clone());
    let plain = after_long_history(&gpu, &cam, &prev, &now, &last);
    let brighter = after_long_history(&gpu, &cam, &prev, &bright, &bright_last);
    for ((what, a), (_, b)) in plain.iter().zip(&brighter) {
        let mut worst = 0.0f32;
        for (p, q) in a.iter().zip(b) {
            for c in 0..3 {
                worst = worst.max((k * p[c] - q[c]).abs() / (k * p[c]).abs().max(1e-3));
            }
        }
        eprintln!("{what}: largest relative difference {worst}");
        assert!(worst < 1e-3, "{what}: {worst}");
    }
}

/// An orbit (the camera turned 1° a frame about the squares' centre), each frame jittered as
/// the viewer's are, resolved in turn for 40 frames: a pixel on the far square's outline
/// against nothing holds what its footprint shows of the square (16 samples across it), as the
/// still image does. Such a pixel's sample shows nothing in some frames; its history moves
/// with the neighbour's surface there. Followed by its view direction, it fetched pixels that
/// showed nothing and went back to black with every sample that missed. Run on the device and
/// the mirror.
#[test]
fn an_outline_keeps_its_coverage() {
    use lobelight::frame::temporal_jitter;
    let gpu = common::gpu();
    const FRAMES: u32 = 40;
    let at = |k: u32, jitter: [f32; 2]| {
        let turn = (1.0f32 * k as f32).to_radians();
        let eye = Vec3::new(3.0 * turn.sin(), 0.1, 3.0 * turn.cos());
        camera(eye, Vec3::ZERO, jitter)
    };
    // Per pixel of the last frame's view, 4 × 4 samples across its footprint.
    let last_cam = at(FRAMES - 1, [0.0; 2]);
    // The blend weighs colours by 1 / (1 + luminance as displayed): where the jittered
    // samples show the square in some frames and nothing in others, it converges to their
    // mean weighed so (which leans to black), not to their plain mean.
    let exposure = display_exposure(&frame(&last_cam).0);
    let weight = |c: &[f32; 4]| 1.0 / (1.0 + exposure * luminance(Vec3::from_slice(&c[..3])));
    let n = (SIZE * SIZE) as usize;
    let (mut sum, mut weights) = (vec![0.0f32; n], vec![0.0f32; n]);
    let (mut far, mut none) = (vec![0; n], vec![0; n]);
    for k in 0..16 {
        let offset = [(k % 4) as f32 * 0.25 - 0.375, (k / 4) as f32 * 0.25 - 0.375];
        let (hdr, surface) = frame(&Camera {
            jitter: offset,
            ..last_cam
        });
        for i in 0..n {
            sum[i] += weight(&hdr[i]) * hdr[i][1];
            weights[i] += weight(&hdr[i]);
            far[i] += (surface[i][3] >= 2.7 && surface[i][3] < FAR) as u32;
            none[i] += (surface[i][3] >= FAR) as u32;
        }
    }
    let run = |on: &mut Resolver| {
        let params = temporal_params(SIZE, SIZE, false);
        let mut prev = at(0, temporal_jitter(0));
        let (mut history, mut kept) = frame(&prev);
        for k in 1..FRAMES {
            let cam = at(k, temporal_jitter(k));
            let now = frame(&cam);
            (history, kept) = on(&cam, &prev, &params, (&now.0, &now.1), (&history, &kept));
            prev = cam;
        }
        history
    };
    let mirror = run(&mut |c, p, params, now, last| on_mirror(c, p, params, now, last));
    let device = run(&mut |c, p, params, now, last| on_gpu(&gpu, c, p, params, now, last));
    for (what, resolved) in [("mirror", mirror), ("device", device)] {
        // The outline: pixels whose 16 samples show the far square and nothing, 2 to 14 of
        // them the square.
        let (mut held, mut truth, mut pixels) = (0.0, 0.0, 0);
        for i in 0..n {
            if far[i] + none[i] < 16 || !(2..=14).contains(&far[i]) {
                continue;
            }
            held += resolved[i][1];
            truth += sum[i] / weights[i];
            pixels += 1;
        }
        let ratio = held / truth;
        eprintln!("{what}: {pixels} outline pixels hold {ratio:.3} of their coverage");
        assert!(pixels > 40, "{what}: too few outline pixels: {pixels}");
        // 1.16 on both (the history's lag and resampling blur as the outline moves); 0.38
        // when the history followed the view direction.
        assert!((0.8..1.25).contains(&ratio), "{what}: {ratio}");
    }
}
