//! What the device holds of a bake (`plan::BakeLimits`) and the lobe fit's shape on it (the
//! fit itself: `host::fit_lobes`, `bake::fit`).

use super::Gpu;
use crate::em::{FitShape, workgroup_size};
use crate::plan::{BakeLimits, GATHER_BATCH_BYTES};

/// The fit's shape on this device: loop-limited on llvmpipe (which silently cuts long shader
/// loops); a subgroup reduction where subgroup operations are enabled and a subgroup always
/// holds the whole workgroup.
pub fn fit_shape(gpu: &Gpu) -> FitShape {
    let loop_limited = gpu.is_software();
    FitShape {
        loop_limited,
        subgroup_reduce: gpu.subgroups
            && gpu.info.subgroup_min_size >= workgroup_size(loop_limited),
    }
}

impl Gpu {
    /// What this device holds of a bake (`plan::BakeLimits`): photon pages and deposit
    /// buffers of one binding, the binning's arrays paged, gathering batches of one page, and
    /// the fit in the device's shape.
    pub fn bake_limits(&self) -> BakeLimits {
        let photon = std::mem::size_of::<crate::types::Photon>() as u64;
        let deposit = crate::shared::deposits::DEPOSIT_WORDS as u64 * 4;
        BakeLimits {
            photon_page: self.max_binding_bytes() / photon,
            binned_bytes: self.max_array_bytes(16),
            deposit_range: (self.page_bytes() / deposit).clamp(1, u32::MAX as u64) as u32,
            gather_batch_bytes: self.page_bytes().min(GATHER_BATCH_BYTES),
            fit_shape: fit_shape(self),
        }
    }
}
