//! The bake's plan (docs/design.md §4–6): what every bake stage takes of a scene, derived
//! once — the photons' and the fit's settings, the scene's bounds, photon search radius and
//! shadow bias, the deposits' uniform, the direct bake's and final gathering's setup — so that
//! no stage walks the splats again for them. `bake` derives one per bake.

use glam::Vec3;

use crate::em::{EmConfig, GatherSetup, deposit_params};
use crate::error::Result;
use crate::frame::{direct_params_biased, shadow_bias};
use crate::photons::PhotonConfig;
use crate::scene::Scene;
use crate::types::{DepositParams, DirectParams};

/// What the bake of one scene needs besides its splats, lights and materials.
#[derive(Clone, Debug)]
pub struct BakePlan {
    pub photons: PhotonConfig,
    /// The lobe fit's settings; `em.radius` is the photon search radius R.
    pub em: EmConfig,
    /// The scene's bounds (`Scene::bounds`).
    pub bounds: (Vec3, Vec3),
    /// How far off a splat's plane rays start (`frame::shadow_bias`).
    pub shadow_bias: f32,
    /// The direct bake's uniform, which final gathering's rays read.
    pub direct: DirectParams,
    /// The deposits' uniform, where the fit reads deposits (`EmConfig::uses_deposits`).
    pub deposits: Option<DepositParams>,
    /// The bake's seed (`[bake] seed`).
    pub seed: u32,
}

impl BakePlan {
    /// The plan of `scene`'s bake: each figure computed once, the splats walked three times
    /// (bounds, shadow bias, the largest radius of the deposits' reach).
    pub fn new(scene: &Scene) -> Result<BakePlan> {
        let bounds = scene.bounds();
        let radius = scene.bake.radius.unwrap_or_else(|| {
            let (lo, hi) = bounds;
            crate::scene::default_search_radius(lo, hi)
        });
        let em = EmConfig {
            radius,
            ..EmConfig::from_settings(&scene.bake)
        };
        let bias = shadow_bias(&scene.splats);
        let direct = direct_params_biased(scene, bias);
        let deposits = match em.uses_deposits() {
            true => Some(deposit_params(
                &scene.lights,
                scene.bake.photons,
                &scene.splats,
                radius,
            )?),
            false => None,
        };
        Ok(BakePlan {
            photons: PhotonConfig::from_scene(scene),
            em,
            bounds,
            shadow_bias: bias,
            direct,
            deposits,
            seed: scene.bake.seed,
        })
    }

    /// What final gathering reads of the scene (`EmConfig::gather`): its lights, baked as
    /// frames bake them, and rays that start where shadow rays do.
    pub fn gather_setup<'a>(&self, scene: &'a Scene) -> GatherSetup<'a> {
        GatherSetup {
            lights: &scene.lights,
            direct: self.direct,
            seed: self.seed,
            shadow_bias: self.shadow_bias,
        }
    }
}
