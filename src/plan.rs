//! The bake's plan (docs/design.md §4–6): what every bake stage takes of a scene, derived
//! once — the photons' and the fit's settings with the photon search radius, the deposits'
//! uniform, and the direct bake's uniform (with the shadow bias) that final gathering reads —
//! so that no stage walks the splats again for them. `bake` derives one per bake.

use crate::direct::direct_params;
use crate::em::{EmConfig, GatherSetup, deposit_params};
use crate::error::Result;
use crate::photons::PhotonConfig;
use crate::scene::Scene;
use crate::types::{DepositParams, DirectParams};

/// What the bake of one scene needs besides its splats, lights and materials.
#[derive(Clone, Debug)]
pub struct BakePlan {
    pub photons: PhotonConfig,
    /// The lobe fit's settings; `em.radius` is the photon search radius R.
    pub em: EmConfig,
    /// The direct bake's uniform, which final gathering's rays read; its shadow bias
    /// (`direct::shadow_bias`) is where they start.
    pub direct: DirectParams,
    /// The deposits' uniform, where the fit reads deposits (`EmConfig::uses_deposits`).
    pub deposits: Option<DepositParams>,
}

impl BakePlan {
    /// The plan of `scene`'s bake: each figure computed once, the splats walked at most three
    /// times (bounds where the scene names no radius, shadow bias, the largest radius of the
    /// deposits' reach).
    pub fn new(scene: &Scene) -> Result<BakePlan> {
        let em = EmConfig::from_scene(scene);
        let deposits = match em.uses_deposits() {
            true => Some(deposit_params(
                &scene.lights,
                scene.bake.photons,
                &scene.splats,
                em.radius,
            )?),
            false => None,
        };
        Ok(BakePlan {
            photons: PhotonConfig::from_scene(scene),
            em,
            direct: direct_params(scene),
            deposits,
        })
    }

    /// What final gathering reads of the scene (`EmConfig::gather`): its lights, baked as
    /// frames bake them, and rays that start where shadow rays do.
    pub fn gather_setup<'a>(&self, scene: &'a Scene) -> GatherSetup<'a> {
        GatherSetup::new(&scene.lights, self.direct)
    }
}
