//! The settings each bake stage takes from a scene's `[bake]` (and its size). They live with
//! the scene so that the stages know nothing of scene files.

use super::Scene;
use crate::em::EmConfig;
use crate::photons::{DEFAULT_BATCH, ITERATION_BUDGET, PhotonConfig};

impl PhotonConfig {
    pub fn from_scene(scene: &Scene) -> PhotonConfig {
        PhotonConfig {
            photons: scene.bake.photons,
            seed: scene.bake.seed,
            max_depth: scene.bake.max_depth,
            store: scene.bake.store,
            batch: DEFAULT_BATCH,
            iteration_budget: ITERATION_BUDGET,
            initial_capacity: 0,
            page_limit: 0,
            memory: scene.budget,
        }
    }
}

impl EmConfig {
    pub fn from_scene(scene: &Scene) -> EmConfig {
        let b = &scene.bake;
        EmConfig {
            lobes: b.lobes,
            iterations: b.iterations,
            family: b.family,
            sparse: b.sparse,
            priors: true,
            fit_all: false,
            prune: b.prune,
            radius: scene.search_radius(),
            slab: b.slab,
            fit_candidates: b.fit_candidates,
            gather: b.gather,
            estimate: b.estimate,
            share: b.share,
            smooth: b.smooth,
        }
    }
}
