//! The image metrics of `lobelight compare` on images with known answers.

use lobelight::cli::compare::{Values, difference, difference_of, flip};

const W: u32 = 32;
const H: u32 = 24;

fn constant(v: f32) -> Vec<[f32; 4]> {
    vec![[v, v, v, 1.0]; (W * H) as usize]
}

/// A smooth ramp with some structure, so FLIP's filters have something to see.
fn ramp() -> Vec<[f32; 4]> {
    (0..W * H)
        .map(|i| {
            let (x, y) = ((i % W) as f32 / W as f32, (i / W) as f32 / H as f32);
            [0.2 + x, 0.3 + 0.5 * y, 0.1 + x * y, 1.0]
        })
        .collect()
}

#[test]
fn identical_images_have_no_error() {
    let b = ramp();
    let d = difference_of(&b, &b, W, H, Values::Radiance).unwrap();
    assert_eq!(d.rel_mse, 0.0);
    assert_eq!(d.smape, 0.0);
    assert_eq!(d.psnr, f64::INFINITY);
    assert_eq!(d.flip, Some(0.0));
    assert_eq!(d.non_finite, 0);
}

/// A uniform gain k on a constant image of value 1: relMSE = k²/(1 + ε) with ε = 0.1², SMAPE
/// = k/(2 + k + 0.01), PSNR = −20 log10 k, energy = k.
#[test]
fn a_uniform_gain_gives_the_closed_forms() {
    let k = 0.1;
    let (a, b) = (constant(1.0 + k as f32), constant(1.0));
    let d = difference(&a, &b).unwrap();
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * y.abs().max(1.0);
    assert!(close(d.rel_mse, k * k / 1.01), "{d:?}");
    assert!(close(d.smape, k / (2.0 + k + 0.01)), "{d:?}");
    assert!(close(d.psnr, -20.0 * k.log10()), "{d:?}");
    assert!(close(d.energy, k), "{d:?}");
}

/// relMSE is relative: the same relative error in a dark and a bright half counts alike.
#[test]
fn rel_mse_does_not_depend_on_the_units() {
    let b = ramp();
    let a: Vec<[f32; 4]> = b
        .iter()
        .map(|p| [p[0] * 1.05, p[1], p[2] * 0.97, 1.0])
        .collect();
    let scale = |img: &[[f32; 4]], s: f32| -> Vec<[f32; 4]> {
        img.iter()
            .map(|p| [p[0] * s, p[1] * s, p[2] * s, 1.0])
            .collect()
    };
    let d1 = difference(&a, &b).unwrap();
    let d2 = difference(&scale(&a, 1e3), &scale(&b, 1e3)).unwrap();
    assert!(
        (d1.rel_mse / d2.rel_mse - 1.0).abs() < 1e-4,
        "{d1:?} {d2:?}"
    );
    assert!((d1.smape / d2.smape - 1.0).abs() < 1e-4, "{d1:?} {d2:?}");
    assert!((d1.psnr - d2.psnr).abs() < 1e-3, "{d1:?} {d2:?}");
}

/// FLIP grows with the difference and stays within [0, 1]; HDR pairs are tone-mapped with
/// the reference's average, so a brighter copy differs.
#[test]
fn flip_grows_with_the_difference() {
    let b = ramp();
    let gain = |s: f32| -> Vec<[f32; 4]> {
        b.iter()
            .map(|p| [p[0] * s, p[1] * s, p[2] * s, 1.0])
            .collect()
    };
    let f = |a: &[[f32; 4]]| flip(a, &b, W, H, Values::Radiance).unwrap();
    let (small, large) = (f(&gain(1.05)), f(&gain(2.0)));
    assert!(
        small > 0.0 && small < large && large <= 1.0,
        "{small} {large}"
    );
    // Too small an image for FLIP's filters: no figure rather than a wrong one.
    assert_eq!(flip(&b[..16], &b[..16], 4, 4, Values::Radiance), None);
}

#[test]
fn non_finite_pixels_are_counted_and_left_out() {
    let b = constant(1.0);
    let mut a = constant(1.0);
    a[3] = [f32::NAN, 1.0, 1.0, 1.0];
    a[7] = [1.0, f32::INFINITY, 1.0, 1.0];
    let d = difference(&a, &b).unwrap();
    assert_eq!(d.non_finite, 2);
    assert_eq!(d.rel_mse, 0.0);
    assert_eq!(d.smape, 0.0);
}

#[test]
fn images_of_different_sizes_are_an_error() {
    let e = difference(&constant(1.0), &constant(1.0)[..10]).unwrap_err();
    assert!(e.to_string().contains("differ in size"), "{e}");
}

/// Per-object figures: an image brighter by 10 % on one object's pixels only shows that
/// object's bias as +10 % and the others' as none; edge and empty pixels count for no object.
#[test]
fn per_object_figures_see_one_object_alone() {
    use lobelight::cli::compare::per_object;
    use lobelight::objects::{MIXED, NONE, id_of};
    let b = ramp();
    // Left half surface 0, right half surface 1, the first column empty, the last mixed.
    let ids: Vec<u16> = (0..W * H)
        .map(|i| match i % W {
            0 => NONE,
            x if x == W - 1 => MIXED,
            x if x < W / 2 => id_of(0),
            _ => id_of(1),
        })
        .collect();
    let a: Vec<[f32; 4]> = b
        .iter()
        .zip(&ids)
        .map(|(p, &id)| {
            let k = if id == id_of(1) || id == MIXED {
                1.1
            } else {
                1.0
            };
            [p[0] * k, p[1] * k, p[2] * k, 1.0]
        })
        .collect();
    let names = vec!["left".to_string(), "right".to_string()];
    let objects = per_object(&a, &b, &ids, &names).unwrap();
    assert_eq!(objects.len(), 2);
    assert_eq!(objects[0].name, "left");
    assert_eq!(objects[0].pixels as u32, (W / 2 - 1) * H);
    assert_eq!(objects[1].pixels as u32, (W / 2 - 1) * H);
    assert_eq!(objects[0].bias, 0.0);
    assert_eq!(objects[0].rel_mse, 0.0);
    assert!((objects[1].bias - 0.1).abs() < 1e-6, "{}", objects[1].bias);
    assert!(objects[1].rel_mse > 0.0);
    assert!(per_object(&a, &b, &ids[1..], &names).is_err());
}
