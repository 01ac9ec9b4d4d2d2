//! The bake's plan (docs/design.md §4–6): what every bake stage takes of a scene and of the
//! executor it runs on, derived once — the photons' and the fit's settings with the photon
//! search radius, the emitters, the deposits' uniform, the direct bake's uniform (with the
//! shadow bias) that final gathering reads, and how the executor's limits page the work — so
//! that no stage walks the splats again for them. `bake` derives one per bake.

use crate::direct::direct_params;
use crate::em::{EmConfig, FitShape, GatherSetup, deposit_params};
use crate::error::Result;
use crate::fit_groups::FitGroups;
use crate::photons::{PhotonConfig, emitters, page_photons};
use crate::scene::Scene;
use crate::types::{DepositParams, DirectParams, Emitter};

/// The most bytes of final gathering's samples a batch holds, on the CPU and at most on a
/// device.
pub const GATHER_BATCH_BYTES: u64 = 64 << 20;

/// What the executor of a bake can hold and how it runs the fit: host memory holds anything
/// (`host`); a device's bindings page the work (`Gpu::bake_limits`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeLimits {
    /// The most photons one store page holds.
    pub photon_page: u64,
    /// The most bytes each of the binning's arrays holds (16 bytes a photon).
    pub binned_bytes: u64,
    /// The most splats whose deposits one buffer holds.
    pub deposit_range: u32,
    /// The most bytes of final gathering's samples one batch of splats holds.
    pub gather_batch_bytes: u64,
    /// The fit's reduction on this executor.
    pub fit_shape: FitShape,
}

impl BakeLimits {
    /// The CPU mirror's: one page of everything, the fit in its default shape.
    pub fn host() -> BakeLimits {
        BakeLimits {
            photon_page: u32::MAX as u64,
            binned_bytes: u64::MAX,
            deposit_range: u32::MAX,
            gather_batch_bytes: GATHER_BATCH_BYTES,
            fit_shape: FitShape::default(),
        }
    }
}

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
    /// The lights' share of the photons (`photons::emitters`).
    pub emitters: Vec<Emitter>,
    /// The executor's limits, and the most photons a store page holds under them and the
    /// photon settings' `page_limit`.
    pub limits: BakeLimits,
    pub photon_page: u64,
    /// Shared fits' groups (`EmConfig::share` > 0).
    pub groups: Option<FitGroups>,
}

impl BakePlan {
    /// The plan of `scene`'s bake on an executor with `limits`: each figure computed once, the
    /// splats walked at most four times (bounds where the scene names no radius, shadow bias,
    /// the largest radius of the deposits' reach, the shared fits' groups).
    pub fn new(scene: &Scene, limits: BakeLimits) -> Result<BakePlan> {
        let photons = PhotonConfig::from_scene(scene);
        BakePlan::of(scene, photons, EmConfig::from_scene(scene), limits)
    }

    /// The plan of `scene`'s bake with other photon and fit settings (`bench`, `sweep`).
    pub fn of(
        scene: &Scene,
        photons: PhotonConfig,
        em: EmConfig,
        limits: BakeLimits,
    ) -> Result<BakePlan> {
        photons.validate()?;
        em.validate()?;
        let deposits = match em.uses_deposits() {
            true => Some(deposit_params(
                &scene.lights,
                photons.photons,
                &scene.splats,
                em.radius,
            )?),
            false => None,
        };
        let groups = match em.share > 0.0 {
            true => Some(FitGroups::new(
                &scene.splats,
                &scene.materials,
                em.fit_all,
                em.share * em.radius,
            )?),
            false => None,
        };
        Ok(BakePlan {
            groups,
            emitters: emitters(&scene.lights, photons.photons)?,
            photon_page: page_photons(&photons, limits.photon_page),
            photons,
            em,
            direct: direct_params(scene),
            deposits,
            limits,
        })
    }

    /// What final gathering reads of the scene (`EmConfig::gather`): its lights, baked as
    /// frames bake them, and rays that start where shadow rays do.
    pub fn gather_setup<'a>(&self, scene: &'a Scene) -> GatherSetup<'a> {
        GatherSetup::new(&scene.lights, self.direct)
    }
}
