//! The merge tree's normal spread (docs/design.md §8): the Ward roughness a glossy merged disk
//! is widened by, against the slopes it stands for and the geometry of a sphere and a plane.

mod common;

use glam::Vec3;
use lobelight::lod::{merge_tree, normal_spread};
use lobelight::shared::splat::{lod_normal, lod_roughness, lod_word};
use lobelight::types::{LodSpread, Splat};

/// The spread `spread` holds at `level` (1–5), as `lod_roughness` widens a lobe of roughness 0.
fn spread_at(spread: &LodSpread, level: u32) -> f32 {
    lod_roughness(0.0, lod_word(spread, level))
}

/// Normals whose slopes along each axis are Gaussian of deviation σ, as Ward's lobe of
/// roughness α has them for σ = α / √2: their mean's length gives back α (Toksvig's relation),
/// within 0.5 % plus α² / 2 (a small-slope relation: 0.04 % at 0.05, 3.8 % low at 0.3).
#[test]
fn the_spread_of_gaussian_slopes_is_their_ward_roughness() {
    let mut rng = common::Rng(7);
    let mut gauss = || {
        // Box–Muller from two uniforms in (0, 1].
        let (u, v) = (1.0 - rng.f32(), rng.f32());
        (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
    };
    for alpha in [0.05f32, 0.1, 0.2, 0.3] {
        let sigma = alpha / 2f32.sqrt();
        let n = 200_000;
        // In f64: the mean's length differs from 1 by σ², under f32's rounding of the sum.
        let mut sum = glam::DVec3::ZERO;
        for _ in 0..n {
            sum += Vec3::new(sigma * gauss(), sigma * gauss(), 1.0)
                .normalize()
                .as_dvec3();
        }
        let got = normal_spread((sum.length() / n as f64) as f32);
        let err = (got - alpha).abs() / alpha;
        eprintln!("alpha {alpha}: spread {got:.4} ({:.2} %)", 100.0 * err);
        assert!(
            err < 0.005 + 0.5 * alpha * alpha,
            "alpha {alpha}: spread {got}"
        );
    }
    assert_eq!(normal_spread(1.0), 0.0);
}

/// Splats on a flat square spread nothing at any level; splats on a sphere of radius R spread
/// at every merged level where the disk took others in, by more than nothing and by no more
/// than normals turned by the merged extent's angle e / R each would (2 % for the small-angle
/// relation, one step of the byte), their mean within that angle of the kept splat's normal;
/// and coarser levels, whose disks are larger, spread more.
#[test]
fn a_merged_disk_spreads_as_its_surface_curves() {
    let radius = 0.01;
    let disk = |c: Vec3, n: Vec3| Splat {
        center: c.to_array(),
        normal: n.to_array(),
        radius,
        ..Default::default()
    };
    let side = 60;
    let flat: Vec<Splat> = (0..side * side)
        .map(|k| {
            let (x, y) = ((k % side) as f32, (k / side) as f32);
            disk(Vec3::new(x * 0.015, y * 0.015, 0.0), Vec3::Z)
        })
        .collect();
    let (lods, spreads) = merge_tree(&flat, true);
    let merged = lods.iter().filter(|l| l.top > 0).count();
    assert!(merged > 100, "{merged} merged");
    for s in &spreads {
        assert!(s.iter().all(|w| w & 0xff == 0), "{s:?}");
    }

    let sphere_radius = 0.5;
    let sphere: Vec<Splat> = common::fibonacci_sphere(6000)
        .into_iter()
        .map(|n| disk(n * sphere_radius, n))
        .collect();
    let (lods, spreads) = merge_tree(&sphere, true);
    let mut means = Vec::new();
    for level in 1..=3u32 {
        let at: Vec<(f32, f32)> = lods
            .iter()
            .zip(&spreads)
            .zip(&sphere)
            .filter(|((l, _), _)| l.top >= level)
            .map(|((l, s), splat)| {
                let extent = l.extent[level as usize - 1];
                // The members' mean normal: within the disk's angle of the kept splat's own.
                let own = Vec3::from(splat.normal);
                let mean = lod_normal(lod_word(s, level), own);
                let angle = mean.dot(own).min(1.0).acos();
                assert!(
                    angle <= extent / sphere_radius,
                    "level {level}: {angle} rad"
                );
                (spread_at(s, level), extent)
            })
            .collect();
        assert!(at.len() > 50, "level {level}: {} disks", at.len());
        for &(spread, extent) in &at {
            let bound = 1.02 * extent / sphere_radius + 1.0 / 255.0;
            assert!(spread <= bound, "level {level}: {spread} > {bound}");
            // A kept splat that took none of its neighbours keeps its own disk and normal.
            assert!(
                spread > 0.0 || extent == radius,
                "level {level}: extent {extent}"
            );
        }
        means.push(at.iter().map(|a| a.0).sum::<f32>() / at.len() as f32);
    }
    eprintln!("mean spread at levels 1–3: {means:?}");
    assert!(means.windows(2).all(|w| w[1] > w[0]), "{means:?}");
}
