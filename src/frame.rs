//! One frame of the baked scene (docs/design.md §7–8): the camera uniform, the shading settings,
//! and the CPU mirror of the splat passes. `gpu::frame` records the same passes on a device.

use glam::{Vec2, Vec3};

use crate::bins::PhotonBins;
use crate::camera::View;
use crate::cpu;
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::scene::Scene;
use crate::shared::trace::Geometry;
use crate::types::{Camera, EmParams, ShadeParams, Splat};

/// Which light a frame shows: everything, or one part of it (the viewer's keys 1–5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Show {
    /// Direct and indirect, diffuse and specular.
    #[default]
    Full,
    /// Shadow-ray light alone.
    Direct,
    /// The bake's light alone: total irradiance and the lobes.
    Indirect,
    /// Diffuse reflection alone, direct and indirect.
    Diffuse,
    /// The lobes' specular reflection alone.
    Lobes,
}

impl Show {
    pub const ALL: [Show; 5] = [
        Show::Full,
        Show::Direct,
        Show::Indirect,
        Show::Diffuse,
        Show::Lobes,
    ];

    /// `ShadeParams::show` bits.
    pub fn mask(self) -> u32 {
        use crate::shared::splat::*;
        match self {
            Show::Full => SHOW_ALL,
            Show::Direct => SHOW_DIRECT_DIFFUSE | SHOW_DIRECT_SPECULAR,
            Show::Indirect => SHOW_INDIRECT_DIFFUSE | SHOW_INDIRECT_SPECULAR,
            Show::Diffuse => SHOW_DIRECT_DIFFUSE | SHOW_INDIRECT_DIFFUSE,
            Show::Lobes => SHOW_INDIRECT_SPECULAR,
        }
    }
}

/// Settings of the splat passes.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameConfig {
    /// Area lights are sampled on an `area_samples`² jittered grid per pixel.
    pub area_samples: u32,
    /// Splats within this many of their radii behind the visible surface blend into a pixel.
    pub depth_tolerance: f32,
    /// Seed of the area-light jitter.
    pub seed: u32,
    /// Which light terms to show (`shared::splat::SHOW_*` bits).
    pub show: u32,
}

impl Default for FrameConfig {
    fn default() -> Self {
        FrameConfig {
            area_samples: 4,
            depth_tolerance: 1.0,
            seed: 1,
            show: crate::shared::splat::SHOW_ALL,
        }
    }
}

impl FrameConfig {
    pub fn validate(&self) -> Result<()> {
        if !(1..=16).contains(&self.area_samples) {
            return Err(Error::Invalid(format!(
                "area light samples per axis must be within 1..=16, got {}",
                self.area_samples
            )));
        }
        if !(self.depth_tolerance >= 0.0 && self.depth_tolerance.is_finite()) {
            return Err(Error::Invalid(format!(
                "the depth tolerance must be a non-negative number of splat radii, got {}",
                self.depth_tolerance
            )));
        }
        Ok(())
    }
}

/// The camera uniform of `view`. The near plane sits at 1e-4 of the scene's size: with
/// reversed depth that costs no precision further away.
pub fn camera_uniform(view: &View, bounds: (Vec3, Vec3), cfg: &FrameConfig) -> Camera {
    let size = (bounds.1 - bounds.0).length().max(1e-6);
    Camera {
        eye: view.eye.to_array(),
        near: 1e-4 * size,
        forward: view.forward.to_array(),
        depth_tolerance: cfg.depth_tolerance,
        right: view.right.to_array(),
        tan_x: view.tan_half.x,
        up: view.up.to_array(),
        tan_y: view.tan_half.y,
        size: Vec2::new(view.width as f32, view.height as f32).to_array(),
        ..Default::default()
    }
}

/// Shadow rays start half a mean splat radius off the blended surface: enough to clear the
/// blend's dip below a curved surface, little enough to keep contact shadows.
pub fn shadow_bias(splats: &[Splat]) -> f32 {
    let sum: f64 = splats.iter().map(|s| s.radius as f64).sum();
    (0.5 * sum / splats.len().max(1) as f64) as f32
}

/// The shading uniform of a bake; the image size comes with the camera.
pub fn shade_params(scene: &Scene, lobes: &LobeMap, cfg: &FrameConfig) -> ShadeParams {
    shade_params_for(scene, lobes.lobes_per_splat, cfg)
}

/// `shade_params` for a lobe map of `lobes_per_splat` (what the passes need of it).
pub fn shade_params_for(scene: &Scene, lobes_per_splat: u32, cfg: &FrameConfig) -> ShadeParams {
    ShadeParams {
        lobes_per_splat,
        family: scene.bake.family.code(),
        light_count: scene.lights.len() as u32,
        area_samples: cfg.area_samples,
        shadow_bias: shadow_bias(&scene.splats),
        seed: cfg.seed,
        show: cfg.show,
        ..Default::default()
    }
}

/// The splat passes on the CPU: visibility, attributes, shade; linear HDR pixels.
pub fn cpu_frame(
    scene: &Scene,
    grid: &SplatGrid,
    lobes: &LobeMap,
    cam: &Camera,
    params: &ShadeParams,
) -> Vec<[f32; 4]> {
    let tiles = cpu::splat_visibility::bin_tiles(cam, &scene.splats);
    let depth = cpu::splat_visibility::splat_visibility(cam, &scene.splats, &tiles);
    let sums = cpu::splat_attributes::splat_attributes(
        cam,
        &scene.splats,
        params,
        &scene.materials,
        &lobes.light,
        &lobes.lobes,
        crate::convolution::lobe_norms(),
        &depth,
        &tiles,
    );
    let geo = Geometry {
        grid,
        splats: &scene.splats,
    };
    cpu::shade::shade(cam, params, &sums, &scene.lights, &geo)
}

/// The reference on the CPU: the gather pass in place of visibility and attributes, then the
/// same shade pass (which reads no lobes: an empty map gives it its other settings).
pub fn cpu_reference(
    scene: &Scene,
    grid: &SplatGrid,
    bins: &PhotonBins,
    em: &EmParams,
    cam: &Camera,
    cfg: &FrameConfig,
) -> Vec<[f32; 4]> {
    let params = shade_params(scene, &LobeMap::default(), cfg);
    let geo = Geometry {
        grid,
        splats: &scene.splats,
    };
    let sums = cpu::reference_gather::reference_gather(cam, em, &scene.materials, bins, &geo);
    cpu::shade::shade(cam, &params, &sums, &scene.lights, &geo)
}
