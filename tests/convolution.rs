//! The reference quadrature of the convolution study (`src/convolution.rs`): the lobe's
//! normalisation, the sharp-lobe limit, a brute-force check where both lobes are broad, and
//! convergence as the sample grids are refined. The study's benchmark and its better formula
//! build on these.

use glam::DVec3;
use lobelight::convolution::{Case, Formula, Quality, Reference, case_error, lobe_shape, ward};
use lobelight::shared::lobes::ward_kappa;
use std::f64::consts::PI;

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// Brute force over the hemisphere: a midpoint grid in (cos θ, φ), for broad integrands.
fn hemisphere(n: usize, f: impl Fn(DVec3) -> f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let z = (i as f64 + 0.5) / n as f64;
        for j in 0..2 * n {
            let phi = PI * (j as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            sum += f(DVec3::new(s * phi.cos(), s * phi.sin(), z));
        }
    }
    sum * (2.0 * PI) / (2 * n * n) as f64
}

/// The lobe's integral is about cos θL · κ(β²) (DESIGN.md §6), the approximation the EM
/// normalises by; the quadrature agrees where that approximation is meant to hold (it
/// ignores the horizon, which cuts a broad lobe at a steep angle: 1.2 % at 60° and β² = 0.04).
#[test]
fn lobe_norm_matches_the_design_approximation() {
    let cases: [(f64, f64); 5] = [
        (0.0, 0.04),
        (30.0, 0.04),
        (60.0, 0.01),
        (60.0, 1e-4),
        (80.0, 1e-4),
    ];
    for (angle, beta2) in cases {
        let case = Case {
            alpha: 0.1,
            beta2,
            angle: angle.to_radians(),
        };
        let norm = Reference::new(case, 64).norm;
        let approx = angle.to_radians().cos() * ward_kappa(beta2 as f32) as f64;
        assert!(
            (norm / approx - 1.0).abs() < 0.01,
            "angle {angle} β² {beta2}: {norm} vs {approx}"
        );
    }
}

/// A very narrow lobe is a single direction: I(ωo) = f_s(L, ωo).
#[test]
fn a_sharp_lobe_reflects_like_a_single_direction() {
    let case = Case {
        alpha: 0.1,
        beta2: 1e-9,
        angle: 40f64.to_radians(),
    };
    let r = Reference::new(case, 32);
    for wo in [dir(40.0, 180.0), dir(45.0, 175.0), dir(20.0, 90.0)] {
        let exact = ward(case.axis(), wo, case.alpha);
        let got = r.radiance(wo);
        assert!((got / exact - 1.0).abs() < 1e-3, "{wo}: {got} vs {exact}");
    }
}

/// Where both lobes are broad a plain hemisphere grid converges: the two must agree.
#[test]
fn broad_lobes_match_brute_force() {
    let case = Case {
        alpha: 0.3,
        beta2: 0.25,
        angle: 30f64.to_radians(),
    };
    let r = Reference::new(case, 48);
    let norm = hemisphere(800, |w| lobe_shape(&case, w));
    assert!((r.norm / norm - 1.0).abs() < 1e-3, "{} vs {norm}", r.norm);
    for wo in [dir(30.0, 180.0), dir(10.0, 0.0), dir(60.0, 120.0)] {
        let brute = hemisphere(800, |w| ward(w, wo, case.alpha) * lobe_shape(&case, w)) / norm;
        let got = r.radiance(wo);
        assert!((got / brute - 1.0).abs() < 2e-3, "{wo}: {got} vs {brute}");
    }
}

/// Refining both the sample maps and the view grid changes a case's errors by far less than
/// the accuracy the study asks of a formula (2 % median).
#[test]
fn errors_converge_with_the_grids() {
    let thesis = [Formula::Thesis { scale: 1.0 }];
    for case in [
        Case {
            alpha: 0.02,
            beta2: 1e-4,
            angle: 50f64.to_radians(),
        },
        Case {
            alpha: 0.15,
            beta2: 0.3,
            angle: 70f64.to_radians(),
        },
    ] {
        let coarse = case_error(&case, &thesis, Quality::default())[0];
        let fine = case_error(
            &case,
            &thesis,
            Quality {
                inner: 64,
                radial: 96,
                around: 64,
            },
        )[0];
        eprintln!("{case:?}: {coarse:?} {fine:?}");
        assert!(
            (coarse.l2_60 - fine.l2_60).abs() < 2e-3,
            "{coarse:?} {fine:?}"
        );
        assert!(
            (coarse.energy - fine.energy).abs() < 2e-3,
            "{coarse:?} {fine:?}"
        );
    }
}
