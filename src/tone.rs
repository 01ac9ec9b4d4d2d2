//! Tone mapping settings (docs/design.md §9) and the level plan of the log-average reduction that
//! the GPU path (`gpu::tone`) and the CPU mirror (`cpu::tone_map`) share.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::shared::dispatch::groups_for;
use crate::shared::tone::{TONE_LINEAR, TONE_REINHARD};
use crate::types::ToneParams;

/// How HDR radiance becomes display values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum ToneMode {
    /// The thesis's operator: log-average luminance to the key, Reinhard's curve, scotopic blend.
    #[default]
    Reinhard,
    /// No operator: radiance times the exposure, clipped (EXR output keeps it unclipped).
    None,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ToneConfig {
    pub mode: ToneMode,
    /// The display value the log-average luminance maps to (Reinhard's a).
    pub key: f32,
    /// Exposure in stops, applied after the operator.
    pub exposure: f32,
    /// cd/m² per unit of radiance, for the scotopic blend (dim scenes turn blue-grey).
    pub luminance_scale: f32,
}

impl Default for ToneConfig {
    fn default() -> Self {
        ToneConfig {
            mode: ToneMode::Reinhard,
            key: 0.18,
            exposure: 0.0,
            luminance_scale: 100.0,
        }
    }
}

/// ε of log(ε + Y): black pixels weigh as a luminance of 1e-4, not as −∞.
pub const LOG_EPSILON: f32 = 1e-4;

impl ToneConfig {
    pub fn validate(&self) -> Result<()> {
        let ok = |x: f32| x.is_finite() && x > 0.0;
        if !ok(self.key) {
            return Err(Error::Invalid(format!(
                "the tone-map key must be a positive number, got {}",
                self.key
            )));
        }
        if !self.exposure.is_finite() || self.exposure.abs() > 64.0 {
            return Err(Error::Invalid(format!(
                "exposure must be within ±64 stops, got {}",
                self.exposure
            )));
        }
        if !ok(self.luminance_scale) {
            return Err(Error::Invalid(format!(
                "the luminance scale must be a positive number, got {}",
                self.luminance_scale
            )));
        }
        Ok(())
    }

    /// The uniform of the reduction level over `count` values, or of the apply pass.
    pub fn params(&self, count: u32, level: u32) -> ToneParams {
        ToneParams {
            count,
            level,
            mode: match self.mode {
                ToneMode::Reinhard => TONE_REINHARD,
                ToneMode::None => TONE_LINEAR,
            },
            _pad0: 0,
            key: self.key,
            exposure: self.exposure.exp2(),
            luminance_scale: self.luminance_scale,
            epsilon: LOG_EPSILON,
        }
    }
}

/// The value counts of the reduction's levels over `pixels`: pixels, then partial sums, down
/// to one workgroup (whose single sum is the result); a workgroup reduces `block` values
/// (`tonemap_reduce`'s workgroup size × items per invocation).
pub fn reduce_levels(pixels: u32, block: u32) -> Vec<u32> {
    let mut levels = vec![pixels];
    let mut n = pixels;
    while groups_for(n, block) > 1 {
        n = groups_for(n, block);
        levels.push(n);
    }
    levels
}

/// exp(Σ log(ε + Y) / count): the log-average luminance from the reduction's result.
pub fn log_average(log_sum: [f32; 2]) -> f32 {
    (log_sum[0] / log_sum[1].max(1.0)).exp()
}
