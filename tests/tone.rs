//! Tone mapping (docs/design.md §9): the GPU's log-average against an f64 sum and the CPU mirror,
//! NaN/Inf pixels, and the operator's defining property.

mod common;

use glam::{Vec2, Vec3};
use lobelight::cpu;
use lobelight::gpu::Gpu;
use lobelight::gpu::tone::tone_map;
use lobelight::shared::tone::{luminance, srgb_byte};
use lobelight::tone::{LOG_EPSILON, ToneConfig, ToneMode, log_average};

use common::Rng;

fn on_gpu(gpu: &Gpu, cfg: &ToneConfig, hdr: &[[f32; 4]]) -> (Vec<u32>, [f32; 2]) {
    let buf = gpu.storage("hdr", hdr).unwrap();
    let mut encoder = gpu.encoder("tone");
    let toned = tone_map(gpu, &mut encoder, &buf, hdr.len() as u32, cfg).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let rgba = gpu.read::<u32>(&toned.rgba, hdr.len()).unwrap();
    let sum = gpu.read::<[f32; 2]>(&toned.log_sum, 1).unwrap()[0];
    (rgba, sum)
}

/// An HDR image over six decades of luminance, coloured.
fn random_image(rng: &mut Rng, pixels: usize) -> Vec<[f32; 4]> {
    (0..pixels)
        .map(|_| {
            let y = 10f32.powf(rng.range(-4.0, 2.0));
            [y * rng.f32(), y * rng.f32(), y * rng.f32(), 1.0]
        })
        .collect()
}

/// The f64 log-average over the finite pixels.
fn reference_log_average(hdr: &[[f32; 4]]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for c in hdr {
        let c = Vec3::new(c[0], c[1], c[2]);
        if c.is_finite() {
            sum += (LOG_EPSILON as f64 + luminance(c.max(Vec3::ZERO)) as f64).ln();
            n += 1;
        }
    }
    (sum / n.max(1) as f64).exp()
}

fn assert_bytes_close(a: &[u32], b: &[u32], what: &str) {
    let mut worst = 0i32;
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        for k in 0..4 {
            let d = ((x >> (8 * k)) & 255) as i32 - ((y >> (8 * k)) & 255) as i32;
            assert!(d.abs() <= 1, "{what}: pixel {i}: {x:08x} vs {y:08x}");
            worst = worst.max(d.abs());
        }
    }
    eprintln!("{what}: largest byte difference {worst}");
}

/// The log-average within 1e-4 relative of an f64 sum, on one level (small image) and on
/// several (2 M pixels); the mirror's bytes within one step of the GPU's.
#[test]
fn log_average_matches_f64_and_mirror() {
    let gpu = common::gpu();
    let mut rng = Rng(3);
    let cfg = ToneConfig::default();
    for pixels in [1000, 512 * 384, 2_000_000] {
        let hdr = random_image(&mut rng, pixels);
        let (g_rgba, g_sum) = on_gpu(&gpu, &cfg, &hdr);
        let (c_rgba, c_sum) = cpu::tone_map(&cfg, &hdr).unwrap();
        assert_eq!(g_sum[1] as usize, pixels, "count");
        let reference = reference_log_average(&hdr);
        for (who, sum) in [("GPU", g_sum), ("CPU", c_sum)] {
            let rel = (log_average(sum) as f64 - reference).abs() / reference;
            eprintln!("{pixels} pixels, {who}: log-average {rel:.2e} from f64");
            assert!(rel <= 1e-4, "{who}: {} vs {reference}", log_average(sum));
        }
        assert_bytes_close(&g_rgba, &c_rgba, &format!("{pixels} pixels"));
    }
}

/// NaN and ±Inf pixels count for nothing in the average and come out black; an all-black
/// image and a single hot pixel give finite, sensible output.
#[test]
fn non_finite_and_extreme_images() {
    let gpu = common::gpu();
    let cfg = ToneConfig::default();
    let mut rng = Rng(9);
    let clean = random_image(&mut rng, 5000);
    let mut dirty = clean.clone();
    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    for (k, i) in (0..dirty.len()).step_by(97).enumerate() {
        dirty[i][k % 3] = bad[k % 3];
    }
    let poisoned = dirty.len().div_ceil(97);
    let finite: Vec<[f32; 4]> = dirty
        .iter()
        .copied()
        .filter(|c| c.iter().all(|x| x.is_finite()))
        .collect();
    let (rgba, sum) = on_gpu(&gpu, &cfg, &dirty);
    assert_eq!(sum[1] as usize, dirty.len() - poisoned);
    let expected = reference_log_average(&finite);
    let rel = (log_average(sum) as f64 - expected).abs() / expected;
    assert!(rel <= 1e-4, "average with NaN/Inf: {rel:.2e} off");
    for i in (0..dirty.len()).step_by(97) {
        assert_eq!(rgba[i], 0xff00_0000, "poisoned pixel {i} is black");
    }

    let black = vec![[0.0f32; 4]; 4096];
    let (rgba, sum) = on_gpu(&gpu, &cfg, &black);
    assert!((log_average(sum) - LOG_EPSILON).abs() <= 1e-9, "{sum:?}");
    assert!(rgba.iter().all(|&p| p == 0xff00_0000));

    let mut hot = vec![[0.01f32, 0.01, 0.01, 1.0]; 4096];
    hot[1234] = [1e30, 1e30, 1e30, 1.0];
    let (rgba, sum) = on_gpu(&gpu, &cfg, &hot);
    assert!(log_average(sum).is_finite());
    assert_eq!(rgba[1234] & 0xff, 255, "the hot pixel saturates");
    let (c_rgba, _) = cpu::tone_map(&cfg, &hot).unwrap();
    assert_bytes_close(&rgba, &c_rgba, "hot pixel");
}

/// A pixel at the log-average luminance maps to a display luminance of a / (1 + a) (photopic,
/// no exposure); `--tonemap none` is the radiance times 2^EV.
#[test]
fn operator_maps_the_average_to_the_key() {
    let cfg = ToneConfig {
        luminance_scale: 1e6,
        ..Default::default()
    };
    let grey = 0.37f32;
    let pixel = Vec3::splat(grey);
    let sum = Vec2::new((LOG_EPSILON + grey).ln() * 10.0, 10.0);
    let params = cfg.params(1, 0);
    let out = lobelight::shared::tone::tone_map(pixel, sum, &params);
    let a = cfg.key * grey / (LOG_EPSILON + grey);
    let expected = a / (1.0 + a);
    assert!(
        (luminance(out) - expected).abs() < 1e-6,
        "{out} vs {expected}"
    );

    let gpu = common::gpu();
    let linear = ToneConfig {
        mode: ToneMode::None,
        exposure: 1.0,
        ..Default::default()
    };
    let hdr = vec![[0.1f32, 0.2, 0.4, 1.0], [0.6, 2.0, 0.0, 1.0]];
    let (rgba, _) = on_gpu(&gpu, &linear, &hdr);
    for (p, c) in rgba.iter().zip(&hdr) {
        for (k, v) in c.iter().take(3).enumerate() {
            let expected = srgb_byte(v * 2.0) as i32;
            let got = ((p >> (8 * k)) & 255) as i32;
            assert!((got - expected).abs() <= 1, "{got} vs {expected}");
        }
    }
}
