//! One frame of the baked scene (docs/design.md §7–8): what to show, the camera uniform, the
//! shading settings and the path tracer's uniform (the direct bake's are `direct`'s). `gpu::passes`
//! records the splat passes on a device, `cpu::frames` runs them on the mirrors.

use glam::{Vec2, Vec3};

use crate::camera::View;
use crate::direct::shadow_bias;
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::types::{Camera, DIRECT_BAKED, DIRECT_RAYS, PathParams, ShadeParams, TemporalParams};

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

    /// The light terms this shows.
    pub fn terms(self) -> Terms {
        match self {
            Show::Full => Terms::ALL,
            Show::Direct => Terms::DIRECT_DIFFUSE | Terms::DIRECT_SPECULAR,
            Show::Indirect => Terms::INDIRECT_DIFFUSE | Terms::INDIRECT_SPECULAR,
            Show::Diffuse => Terms::DIRECT_DIFFUSE | Terms::INDIRECT_DIFFUSE,
            Show::Lobes => Terms::INDIRECT_SPECULAR,
        }
    }
}

/// The light terms a frame shows, any set of the four: its uniforms carry them as the
/// `shared::splat::SHOW_*` bits (`ShadeParams::show`, `PathParams::show`). `Show` names the
/// sets the command line and the viewer's keys offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Terms(u32);

impl Terms {
    pub const ALL: Terms = Terms(crate::shared::splat::SHOW_ALL);
    pub const DIRECT_DIFFUSE: Terms = Terms(crate::shared::splat::SHOW_DIRECT_DIFFUSE);
    pub const DIRECT_SPECULAR: Terms = Terms(crate::shared::splat::SHOW_DIRECT_SPECULAR);
    pub const INDIRECT_DIFFUSE: Terms = Terms(crate::shared::splat::SHOW_INDIRECT_DIFFUSE);
    pub const INDIRECT_SPECULAR: Terms = Terms(crate::shared::splat::SHOW_INDIRECT_SPECULAR);

    /// The uniforms' `show` bits.
    pub fn bits(self) -> u32 {
        self.0
    }
}

impl std::ops::BitOr for Terms {
    type Output = Terms;
    fn bitor(self, other: Terms) -> Terms {
        Terms(self.0 | other.0)
    }
}

/// Where a frame's direct light comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Direct {
    /// The direct bake: each splat's visibility of each light, made once for static lights,
    /// so a moving camera casts no shadow ray (the glossy part still follows the view).
    #[default]
    Baked,
    /// Shadow rays from every pixel, every frame: exact per pixel.
    Rays,
}

impl Direct {
    /// `ShadeParams::direct`.
    pub fn code(self) -> u32 {
        match self {
            Direct::Baked => DIRECT_BAKED,
            Direct::Rays => DIRECT_RAYS,
        }
    }

    /// The mode a `ShadeParams::direct` code names: baked, or shadow rays for any other code
    /// (as the shade pass reads it).
    pub fn of_code(code: u32) -> Direct {
        match code {
            DIRECT_BAKED => Direct::Baked,
            _ => Direct::Rays,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Direct::Baked => "baked",
            Direct::Rays => "rays",
        }
    }
}

/// How splats become pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Splatter {
    /// Two render passes over one triangle per splat (depth, then blended attributes).
    Raster,
    /// One compute pass over screen tiles of binned splats: no triangles.
    Compute,
    /// Whichever the device class draws faster (docs/measurements.md): raster on llvmpipe,
    /// where the compute splatter measured 3–4× slower, and until measured elsewhere.
    #[default]
    Auto,
}

impl Splatter {
    pub fn name(self) -> &'static str {
        match self {
            Splatter::Raster => "raster",
            Splatter::Compute => "compute",
            Splatter::Auto => "auto",
        }
    }
}

/// How a device draws a frame's splats: `Splatter` resolved (`SplatPipelines::splatting`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Splatting {
    /// The raster passes.
    Raster,
    /// The compute splatter over screen tiles.
    Compute,
}

/// Settings of the splat passes.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameConfig {
    /// Area lights are sampled on an `area_samples`² jittered grid per pixel (shadow rays), or
    /// at its strata's centres (baked visibility's glossy part).
    pub area_samples: u32,
    /// Direct light from the bake or from shadow rays (a refinement frame always casts rays).
    pub direct: Direct,
    /// Raster passes or the compute splatter (the device resolves `Auto`).
    pub splatter: Splatter,
    /// Splats within this many of their radii behind the visible surface blend into a pixel.
    pub depth_tolerance: f32,
    /// Seed of the area-light jitter.
    pub seed: u32,
    /// Which light terms to show.
    pub show: Terms,
    /// Level of detail of moving frames, in pixels (`Camera::lod`; 0: off).
    pub lod: f32,
    /// Rays a pixel and refinement frame tracing the glossy surfaces' indirect light
    /// (`ShadeParams::glossy_rays`; 0: their lobes give it, as in moving frames).
    pub glossy_rays: u32,
    /// Moving frames are jittered and blended with the ones before (`temporal`); off (the
    /// default), each is drawn alone at the pixel centres.
    pub temporal: bool,
}

impl Default for FrameConfig {
    fn default() -> Self {
        FrameConfig {
            area_samples: 4,
            direct: Direct::Baked,
            splatter: Splatter::Auto,
            depth_tolerance: 1.0,
            seed: 1,
            show: Terms::ALL,
            lod: DEFAULT_LOD,
            glossy_rays: DEFAULT_GLOSSY_RAYS,
            temporal: false,
        }
    }
}

/// Most glossy rays a pixel and frame.
pub const MAX_GLOSSY_RAYS: u32 = 64;

/// `FrameConfig::glossy_rays` unless the command line says otherwise.
pub const DEFAULT_GLOSSY_RAYS: u32 = 4;

impl FrameConfig {
    /// Whether its frames read the direct bake: for baked direct light, or at glossy rays'
    /// hits.
    pub fn needs_direct_bake(&self) -> bool {
        self.direct == Direct::Baked || self.glossy_rays > 0
    }

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
        if !(self.lod >= 0.0 && self.lod.is_finite()) {
            return Err(Error::Invalid(format!(
                "the level of detail must be a non-negative number of pixels, got {}",
                self.lod
            )));
        }
        if self.glossy_rays > MAX_GLOSSY_RAYS {
            return Err(Error::Invalid(format!(
                "glossy rays must be within 0..={MAX_GLOSSY_RAYS} a pixel and frame, got {}",
                self.glossy_rays
            )));
        }
        Ok(())
    }
}

/// Moving frames merge splats into disks of up to 1.5 pixels: the full dragon's 512² frame
/// 245 → 186 ms on lavapipe when it was measured, its relMSE against the still image 0.0066 →
/// 0.0134, and no hole (docs/measurements.md, "Merged splats for moving frames").
pub const DEFAULT_LOD: f32 = 1.5;

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
        lod: cfg.lod,
        ..Default::default()
    }
}

/// The camera of a frame's passes: the level of detail (`Camera::lod`) only in frames of baked
/// direct light drawn by the raster passes, a moving camera's; refinement frames, frames of
/// shadow rays and the compute splatter draw every splat as it is, so the still image is exact.
pub fn frame_camera(cam: &Camera, params: &ShadeParams, splatting: Splatting) -> Camera {
    let moving = Direct::of_code(params.direct) == Direct::Baked && splatting == Splatting::Raster;
    Camera {
        lod: if moving { cam.lod } else { 0.0 },
        ..*cam
    }
}

/// What one frame derives from the scene and its camera, once, as `plan::BakePlan` is the
/// bake's: the camera uniform of its view, the camera its passes read (`frame_camera`: the
/// level of detail only where it draws merged disks), its shading uniform and how splats
/// become pixels. The device's passes and the mirrors take it whole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePlan {
    /// The view's camera uniform (`camera_uniform`), jittered where the frame is.
    pub view: Camera,
    /// The camera the splat passes read.
    pub cam: Camera,
    pub params: ShadeParams,
    pub splatting: Splatting,
}

impl FramePlan {
    /// The plan of a frame of `view` (a camera uniform) shaded with `params`.
    pub fn new(view: &Camera, params: ShadeParams, splatting: Splatting) -> FramePlan {
        FramePlan {
            view: *view,
            cam: frame_camera(view, &params, splatting),
            params,
            splatting,
        }
    }

    /// The plan of a frame of `view` with `lobes_per_splat` lobes a splat, in a scene of
    /// `extent` (its shadow bias): `shade_params_for`'s uniform.
    pub fn of(
        scene: &Scene,
        extent: &SceneExtent,
        lobes_per_splat: u32,
        (view, cfg): (&Camera, &FrameConfig),
        splatting: Splatting,
    ) -> FramePlan {
        let params = shade_params_for(scene, lobes_per_splat, extent.shadow_bias, cfg);
        FramePlan::new(view, params, splatting)
    }

    /// Refinement frame `k` of `spp` of this frame's still image (`refinement`): jittered,
    /// with its share of shadow rays, every splat drawn as it is.
    pub fn refinement(&self, k: u32, spp: u32) -> FramePlan {
        let view = Camera {
            jitter: jitter(k, spp),
            ..self.view
        };
        FramePlan::new(&view, refinement(&self.params, k, spp), self.splatting)
    }

    /// This frame, its view jittered by `offset` pixels (a moving frame's `temporal_jitter`).
    pub fn jittered(&self, offset: [f32; 2]) -> FramePlan {
        let view = Camera {
            jitter: offset,
            ..self.view
        };
        FramePlan::new(&view, self.params, self.splatting)
    }

    /// Whether its passes draw the level of detail's merged disks.
    pub fn merged(&self) -> bool {
        self.cam.lod > 0.0
    }

    /// Whether it reads the direct bake (baked direct light; refinement frames cast rays).
    pub fn reads_direct_bake(&self) -> bool {
        Direct::of_code(self.params.direct) == Direct::Baked
    }
}

/// What frames take of a scene's splats, walked once (`FrameRenderer` keeps it): its bounds
/// (the camera's depth range) and its shadow bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneExtent {
    pub bounds: (glam::Vec3, glam::Vec3),
    pub shadow_bias: f32,
}

impl SceneExtent {
    pub fn of(scene: &Scene) -> SceneExtent {
        SceneExtent {
            bounds: scene.bounds(),
            shadow_bias: shadow_bias(&scene.splats),
        }
    }
}

/// The path tracer's uniform for the first sample of an image `cam.size` (set `sample` for the
/// others), with the bake's path length and seed, showing the light terms `show`
/// (`FrameConfig::show`).
pub fn path_params(scene: &Scene, cam: &Camera, show: Terms, shadow_bias: f32) -> PathParams {
    PathParams {
        width: cam.size[0] as u32,
        height: cam.size[1] as u32,
        sample: 0,
        seed: scene.bake.seed,
        max_depth: scene.bake.max_depth,
        light_count: scene.lights.len() as u32,
        show: show.bits(),
        shadow_bias,
        background: scene.camera.background.uniform(),
    }
}

/// Point `k` of the Sobol' (0, 2)-sequence digitally shifted by one half, in [0, 1)²: every
/// prefix of 2^m points (m ≥ 1) holds one point in each of its 2^m columns, rows and other
/// elementary boxes of area 2^-m, each at the box's corner, and point 0 is (½, ½).
fn sobol_2d(k: u32) -> [f64; 2] {
    let (mut y, mut v, mut i) = (0u32, 1u32 << 31, k);
    while i > 0 {
        if i & 1 == 1 {
            y ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    [k.reverse_bits(), y].map(|bits| (bits ^ (1 << 31)) as f64 / 2f64.powi(32))
}

/// The sub-pixel offset of refinement frame `k` of `n`: the pixel's centre for one frame, else
/// point `k` of the (0, 2)-sequence moved to the middle of its box of the next power of two at
/// or above `n` points, so that the points' mean is the pixel's centre. Every pixel takes the
/// same point in a frame, so an offset of that mean shifts every edge of the image alike: 16
/// frames of the Halton (2, 3) points with the centre first (their mean 0.043 pixel off in y)
/// had read the all-diffuse box's small block 2.4 % bright in direct light, its lit top a strip
/// one pixel tall at 64².
pub fn jitter(k: u32, n: u32) -> [f32; 2] {
    if n <= 1 {
        return [0.0; 2];
    }
    let half_box = 0.5 / (n as u64).next_power_of_two() as f64;
    sobol_2d(k).map(|x| (x + half_box - 0.5) as f32)
}

/// Moving frames cycle through this many sub-pixel offsets (`temporal_jitter`).
pub const TEMPORAL_JITTERS: u32 = 16;

/// The sub-pixel offset of the `k`-th moving frame since a reset: the (0, 2)-sequence's points
/// as they fall, the first at the pixel's centre, so that a frame without history is the one
/// drawn alone.
pub fn temporal_jitter(k: u32) -> [f32; 2] {
    sobol_2d(k % TEMPORAL_JITTERS).map(|x| (x - 0.5) as f32)
}

/// The temporal pass's uniform for a `width × height` moving frame: the history's running mean
/// counts up to 16 frames (the jitter cycle), kept where the surface's distance agrees within
/// 5 % and its normal within 60°. `reset`: no history to blend.
pub fn temporal_params(width: u32, height: u32, reset: bool) -> TemporalParams {
    TemporalParams {
        width,
        height,
        reset: reset as u32,
        max_frames: TEMPORAL_JITTERS,
        depth_tolerance: 0.05,
        normal_cos: 0.5,
        _pad0: 0,
        _pad1: 0,
    }
}

/// The shading uniform of refinement frame `k` of `spp`: shadow rays per pixel, the frame's
/// share of the area-light strata (all `area_samples`² over `spp` frames, so that a still
/// image holds at least as many light samples per pixel as a one-frame exact render; past
/// that, fresh jitter each round) and its place in the running mean.
pub fn refinement(base: &ShadeParams, k: u32, spp: u32) -> ShadeParams {
    let strata = base.area_samples * base.area_samples;
    let count = strata.div_ceil(spp.max(1)).max(1);
    let round = k * count / strata;
    ShadeParams {
        direct: DIRECT_RAYS,
        area_first: (k * count) % strata,
        area_count: count,
        sample: k,
        seed: if round == 0 {
            base.seed
        } else {
            crate::shared::rng::pcg_hash(base.seed.wrapping_add(round))
        },
        ..*base
    }
}

/// The shading uniform of a bake; the image size comes with the camera.
pub fn shade_params(scene: &Scene, lobes: &LobeMap, cfg: &FrameConfig) -> ShadeParams {
    shade_params_for(
        scene,
        lobes.lobes_per_splat,
        shadow_bias(&scene.splats),
        cfg,
    )
}

/// `shade_params` for a lobe map of `lobes_per_splat` (what the passes need of it), with the
/// scene's shadow bias known (`SceneExtent`).
pub fn shade_params_for(
    scene: &Scene,
    lobes_per_splat: u32,
    shadow_bias: f32,
    cfg: &FrameConfig,
) -> ShadeParams {
    ShadeParams {
        lobes_per_splat,
        family: scene.bake.family.code(),
        light_count: scene.lights.len() as u32,
        area_samples: cfg.area_samples,
        shadow_bias,
        seed: cfg.seed,
        show: cfg.show.bits(),
        direct: cfg.direct.code(),
        area_first: 0,
        area_count: cfg.area_samples * cfg.area_samples,
        sample: 0,
        glossy_rays: cfg.glossy_rays,
        background: scene.camera.background.uniform(),
    }
}
