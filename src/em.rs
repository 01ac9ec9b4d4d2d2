//! The lobe fit (docs/design.md §6): settings, the plan of `em_fit` dispatches, and the result.
//! The passes are `fit_select` (list the splats with photons near them) and `em_fit` (one
//! workgroup per listed splat); `sequence::fit_lobes` runs them alike on either engine.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::shared::lobes::{
    EM_FIT_ALL, EM_PRIORS, EM_SPARSE, EM_SUBGROUP_REDUCE, FAMILY_VMF, FAMILY_WARD,
};
use crate::types::{DirectParams, EmParams, Light, Lobe, SplatLight};

/// The lobe family fitted to each splat's photon directions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum LobeFamily {
    /// von Mises–Fisher lobes, closed-form M-step with light priors: with 8 lobes the
    /// closest to the path-traced truth on glossy surfaces (docs/measurements.md, "Glossy
    /// light against the path tracer"), hence the default.
    #[default]
    Vmf,
    /// The thesis's Ward-like lobe with its heuristic axis update: the lower fit error
    /// (likelihood) at equal time, but broader lobes that read brighter against the truth.
    Ward,
}

impl LobeFamily {
    pub fn code(self) -> u32 {
        match self {
            LobeFamily::Vmf => FAMILY_VMF,
            LobeFamily::Ward => FAMILY_WARD,
        }
    }
}

/// Where each splat's photon irradiance comes from (design §6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Estimate {
    /// Each splat's photons summed into its deposit, and a splat's irradiance the share of
    /// its neighbours' deposits that its gather disk holds (`deposit_share`): time bounded by
    /// splats, not photons. Fitted splats need final gathering for their lobes; with
    /// `gather` 0 the photons' estimate is used.
    #[default]
    Deposits,
    /// Every photon within R of the splat (`estimate_gather`, `em_fit`): time grows with photons.
    Photons,
}

/// Settings of the lobe fit.
#[derive(Clone, Debug, PartialEq)]
pub struct EmConfig {
    pub lobes: u32,
    pub iterations: u32,
    pub family: LobeFamily,
    /// Sparse EM (thesis §3.5): responsibilities under 0.02 stay frozen between full updates
    /// every 8 iterations.
    pub sparse: bool,
    /// MAP priors on weights and sharpness (vMF).
    pub priors: bool,
    /// Fit lobes on every splat with photons, not only on glossy ones (benchmarks).
    pub fit_all: bool,
    /// Drop the lobes a splat's photons do not need (BIC), so `lobes` is an upper bound.
    pub prune: bool,
    /// Photon search radius R.
    pub radius: f32,
    /// Half thickness of the slab around a splat's plane, in splat radii.
    pub slab: f32,
    /// Most candidate photons one splat's fit visits per pass (0: all): past it an even
    /// subset, reweighted, so the fit's time is bounded by splats, not photons; the splat's
    /// irradiance still sums every photon (`em_fit.wgsl`, "Bounded cost").
    pub fit_candidates: u32,
    /// Final gathering: fitted splats fit their lobes to `gather`² rays from their centres
    /// (`sequence::fit_lobes`), not to the photons (0).
    pub gather: u32,
    /// Where the splats' photon irradiance comes from.
    pub estimate: Estimate,
    /// Shared fits (`fit_groups`): fitted splats within one cell of this many search radii,
    /// facing alike, share one fit (0: each fits its own).
    pub share: f32,
    /// The photons' estimate widened where the light is smooth (`estimate_smooth`): the widest
    /// kernel, in search radii (0: each splat keeps its own estimate). Deposits only.
    pub smooth: f32,
}

impl EmConfig {
    /// Whether the irradiance comes from deposits: asked for, and final gathering fits the
    /// lobes (the photon fit needs the photons themselves).
    pub fn uses_deposits(&self) -> bool {
        self.estimate == Estimate::Deposits && self.gather > 0
    }

    pub fn validate(&self) -> Result<()> {
        let check = || -> std::result::Result<(), String> {
            check_lobes(self.lobes)?;
            if self.iterations > 1000 {
                return Err(format!(
                    "iterations must be within 0..=1000, got {}",
                    self.iterations
                ));
            }
            check_radius(self.radius)?;
            check_slab(self.slab)?;
            check_share(self.share)?;
            check_smooth(self.smooth)?;
            check_gather(self.gather)
        };
        check().map_err(Error::Invalid)
    }

    /// The uniform of a dispatch over `active` listed splats (iterations filled in per
    /// dispatch), for a device of the given shape.
    pub fn params(&self, splat_count: u32, active: u32, shape: FitShape) -> EmParams {
        let flags = if self.sparse { EM_SPARSE } else { 0 }
            | if self.priors { EM_PRIORS } else { 0 }
            | if self.fit_all { EM_FIT_ALL } else { 0 }
            | if shape.subgroup_reduce {
                EM_SUBGROUP_REDUCE
            } else {
                0
            };
        let r = self.radius;
        EmParams {
            lobes: self.lobes,
            iterations: self.iterations,
            family: self.family.code(),
            flags,
            radius: r,
            radius2: r * r,
            slab: self.slab,
            inv_area: 1.0 / (std::f32::consts::PI * r * r),
            splat_count,
            active_count: active,
            iteration_begin: 0,
            iteration_end: self.iterations,
            workgroup_size: workgroup_size(shape.loop_limited),
            prune: if self.prune {
                self.lobes.saturating_sub(1)
            } else {
                0
            },
            fit_candidates: self.fit_candidates,
            smooth_radii: self.smooth,
            ..Default::default()
        }
    }
}

/// The checks of the fit's settings that scene files and command-line overrides share.
pub fn check_lobes(lobes: u32) -> std::result::Result<(), String> {
    if !(1..=crate::shared::lobes::MAX_LOBES).contains(&lobes) {
        return Err(format!("lobes must be within 1..=8, got {lobes}"));
    }
    Ok(())
}

pub fn check_radius(radius: f32) -> std::result::Result<(), String> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(format!(
            "the search radius must be a positive number, got {radius}"
        ));
    }
    Ok(())
}

pub fn check_slab(slab: f32) -> std::result::Result<(), String> {
    if !(slab > 0.0 && slab.is_finite()) {
        return Err(format!(
            "slab must be a positive number of splat radii, got {slab}"
        ));
    }
    Ok(())
}

pub fn check_share(share: f32) -> std::result::Result<(), String> {
    if !(share.is_finite() && (0.0..=MAX_SHARE).contains(&share)) {
        return Err(format!(
            "share must be within 0..={MAX_SHARE} search radii (0: no shared fits), got {share}"
        ));
    }
    Ok(())
}

pub fn check_smooth(smooth: f32) -> std::result::Result<(), String> {
    if !(smooth.is_finite() && (0.0..=MAX_SMOOTH).contains(&smooth)) {
        return Err(format!(
            "smooth must be within 0..={MAX_SMOOTH} search radii (0: no smoothing), got {smooth}"
        ));
    }
    Ok(())
}

pub fn check_gather(gather: u32) -> std::result::Result<(), String> {
    if gather > MAX_GATHER {
        return Err(format!(
            "gather must be within 0..={MAX_GATHER} rays a side, got {gather}"
        ));
    }
    Ok(())
}

/// `EmConfig::gather` unless a scene or the command line says otherwise: 16² rays a glossy
/// splat (docs/measurements.md, "Final gathering").
pub const DEFAULT_GATHER: u32 = 16;

/// `EmConfig::share` unless a scene or the command line says otherwise (docs/measurements.md,
/// "Shared fits").
pub const DEFAULT_SHARE: f32 = 1.0;

/// `EmConfig::smooth` unless a scene or the command line says otherwise (docs/measurements.md,
/// "Smoothing").
pub const DEFAULT_SMOOTH: f32 = 2.0;

/// Widest smoothing kernel, in search radii: `estimate_smooth`'s box reaches the widest kernel plus
/// a deposit's reach past R, at most 2 reach (the `SMOOTH_SPAN` + 1 cells its box may span),
/// which holds for 2 R since the reach is at least R.
pub const MAX_SMOOTH: f32 = 2.0;

/// Largest cell of a shared fit, in search radii: past it one fit would stand for light that
/// the photons resolve apart.
pub const MAX_SHARE: f32 = 4.0;

/// Most rays a side of final gathering: 64² = 4,096 rays a splat.
pub const MAX_GATHER: u32 = 64;

/// `EmConfig::fit_candidates` unless a scene or the command line says otherwise.
pub const DEFAULT_FIT_CANDIDATES: u32 = 1024;

/// How a device runs the fit; the CPU mirror takes the same shape to add in the same order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FitShape {
    /// The device silently cuts long shader loops (llvmpipe): 8 invocations per splat, and
    /// the iterations split over dispatches.
    pub loop_limited: bool,
    /// The invocations' sums combine by a butterfly of subgroup shuffles (all of a
    /// workgroup's invocations in one subgroup), not through workgroup memory: on llvmpipe
    /// the fit runs 1.3x faster.
    pub subgroup_reduce: bool,
}

/// Invocations per `em_fit` workgroup: 8 on llvmpipe, whose subgroups are 8 wide (a barrier
/// within one subgroup is nearly free; 32 invocations ran at half the speed), 32 elsewhere.
pub fn workgroup_size(loop_limited: bool) -> u32 {
    if loop_limited { 8 } else { 32 }
}

/// Loop iterations one invocation may spend in a dispatch on a device with llvmpipe's silent
/// limit (about 65k), with a margin.
pub const LOOP_BUDGET: u64 = 48_000;

/// EM iterations per `em_fit` dispatch. On a loop-limited device (llvmpipe) the iterations
/// are split so that one invocation's loops stay under `LOOP_BUDGET`, estimated from the
/// splat with the most candidate photons; elsewhere one dispatch runs them all.
pub fn iterations_per_dispatch(
    cfg: &EmConfig,
    max_candidates: u32,
    loop_limited: bool,
) -> Result<u32> {
    let all = cfg.iterations.max(1);
    if !loop_limited {
        return Ok(all);
    }
    let wg = workgroup_size(loop_limited) as u64;
    // Per pass: each candidate visited once, each accepted one four loops over the lobes,
    // plus the rows, the sums and the reduction. With `fit_candidates` a pass visits at most
    // that many, and the final pass also tests every candidate once for the irradiance.
    let candidates = max_candidates as u64;
    let (visited, irradiance) = match cfg.fit_candidates {
        0 => (candidates, 0),
        cap => (candidates.min(cap as u64), candidates.div_ceil(wg)),
    };
    let per_pass = visited.div_ceil(wg) * (1 + 4 * cfg.lobes as u64) + 200;
    let passes = LOOP_BUDGET.saturating_sub(irradiance) / per_pass;
    if passes < 3 {
        return Err(Error::DeviceLimit(format!(
            "a splat has {max_candidates} candidate photons within the search radius, too many \
             for this software device's loop limit: lower the radius, the photon count or \
             fit_candidates"
        )));
    }
    // Two passes go to the gather and to the final (or hand-over) pass.
    Ok(((passes - 2) as u32).min(all))
}

/// The iteration ranges of the `em_fit` dispatches: `chunk` at a time, at least one range
/// (the last one runs the final pass, also with no iterations).
pub fn dispatch_ranges(iterations: u32, chunk: u32) -> Vec<(u32, u32)> {
    let mut ranges = Vec::new();
    let mut begin = 0;
    loop {
        let end = (begin + chunk.max(1)).min(iterations);
        ranges.push((begin, end));
        if end == iterations {
            return ranges;
        }
        begin = end;
    }
}

/// Counts of a lobe fit.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EmStats {
    /// Splats with candidate photons (listed by `fit_select`).
    pub listed: u32,
    /// Listed splats whose lobes were fitted (glossy, or all with `fit_all`).
    pub fitted: u32,
    pub max_candidates: u32,
    /// Photons gathered, summed over fitted splats.
    pub photons: u64,
    pub dispatches: u32,
    pub ms: f64,
    /// `ms` by pass: selection (with its readback), irradiance gather, fit.
    pub select_ms: f64,
    pub gather_ms: f64,
    pub fit_ms: f64,
    /// With final gathering: the direct bake and the rays (`final_gather`).
    pub final_gather_ms: f64,
    /// The direct bake's part of `final_gather_ms`: every splat's, so it grows with the
    /// splats where the rest of final gathering grows with the fits.
    pub direct_bake_ms: f64,
    /// Final gathering's rays (`fitted` × gather²).
    pub rays: u64,
    /// Splats served by another's fit (shared fits), besides the `fitted`.
    pub served: u32,
    /// Measures of the covered share of a gather disk (`estimate_coverage`): one a coverage group.
    pub coverages: u32,
    /// `estimate_smooth`: the lit splats by the estimate they took (their own, the plane within
    /// half the widest kernel, within all of it), and those whose box was too crowded to fit.
    pub smoothed: [u32; 4],
}

/// What final gathering reads of the scene besides the photons and the splats
/// (`EmConfig::gather`): the lights of the direct bake, whose light the rays' hits read with
/// the photons', and where the rays start.
pub struct GatherSetup<'a> {
    pub lights: &'a [Light],
    pub direct: DirectParams,
    pub seed: u32,
    /// How far off a splat's plane its rays start.
    pub shadow_bias: f32,
}

impl<'a> GatherSetup<'a> {
    /// The setup of `lights` baked with `direct`, whose seed and shadow bias the rays take.
    pub fn new(lights: &'a [Light], direct: DirectParams) -> GatherSetup<'a> {
        GatherSetup {
            lights,
            direct,
            seed: direct.seed,
            shadow_bias: direct.shadow_bias,
        }
    }
}

/// The fit's output: the light of every splat, and the lobes written, packed (splat `i`'s at
/// `light[i].first_lobe`, `light[i].lobes` of them, at most `lobes_per_splat`).
#[derive(Clone, Debug, Default)]
pub struct LobeMap {
    pub lobes_per_splat: u32,
    pub lobes: Vec<Lobe>,
    pub light: Vec<SplatLight>,
    pub stats: EmStats,
}

impl LobeMap {
    /// The map of a fit whose lobes are `dense` (`per_splat` slots for each fitted splat, from
    /// its `first_lobe`, as the fit writes them), keeping only the lobes written, in splat
    /// order: each splat's `first_lobe` then points into the packed list. Diffuse and dark splats take no room; with nothing fitted (nothing glossy lit)
    /// the map, the cache file and the frame hold no lobes at all, and `lobes_per_splat` is 0.
    pub fn pack(
        per_splat: u32,
        dense: &[Lobe],
        mut light: Vec<SplatLight>,
        stats: EmStats,
    ) -> LobeMap {
        let k = per_splat as usize;
        let mut lobes = Vec::new();
        for l in light.iter_mut() {
            let count = (l.lobes as usize).min(k);
            let at = l.first_lobe as usize;
            let written = dense.get(at..at + count).unwrap_or_default();
            l.lobes = written.len() as u32;
            // 0 for a splat without lobes: its light stays as the fit wrote it.
            l.first_lobe = if count > 0 { lobes.len() as u32 } else { 0 };
            lobes.extend_from_slice(written);
        }
        LobeMap {
            lobes_per_splat: if lobes.is_empty() { 0 } else { per_splat },
            lobes,
            light,
            stats,
        }
    }

    /// Checks that every splat's lobes lie within the packed list (a cache file read back).
    pub fn check_packed(&self) -> std::result::Result<(), String> {
        let total = self.lobes.len() as u64;
        match self.light.iter().position(|l| {
            l.lobes > self.lobes_per_splat || l.first_lobe as u64 + l.lobes as u64 > total
        }) {
            Some(i) => Err(format!("splat {i}'s lobes lie outside the {total} stored")),
            None => Ok(()),
        }
    }

    /// Refuses values no fit writes (a cache whose checksum was made to match them): an
    /// irradiance, a lobe's axis or sharpness that is not finite, a negative sharpness. (A
    /// splat's irradiance may be a little below zero: the smoothing's planes extrapolate.)
    pub fn check_values(&self) -> std::result::Result<(), String> {
        let irradiance = |rgb: &[f32; 3]| rgb.iter().all(|x| x.is_finite());
        if let Some(i) = self.light.iter().position(|l| !irradiance(&l.irradiance)) {
            let rgb = self.light[i].irradiance;
            return Err(format!("splat {i}'s irradiance {rgb:?} is not finite"));
        }
        let good_lobe = |l: &Lobe| {
            irradiance(&l.irradiance)
                && l.axis.iter().all(|x| x.is_finite())
                && l.sharpness.is_finite()
                && l.sharpness >= 0.0
        };
        match self.lobes.iter().position(|l| !good_lobe(l)) {
            Some(k) => Err(format!(
                "lobe {k} holds values no fit writes (not finite, or a negative sharpness): {:?}",
                self.lobes[k]
            )),
            None => Ok(()),
        }
    }

    /// The lobes of splat `i` that were written.
    pub fn splat_lobes(&self, i: usize) -> &[Lobe] {
        let l = &self.light[i];
        &self.lobes[l.first_lobe as usize..(l.first_lobe + l.lobes) as usize]
    }

    /// Mean photons gathered per fitted splat.
    pub fn mean_photons(&self) -> f64 {
        let (sum, n) = self
            .fitted()
            .fold((0u64, 0u64), |(s, n), l| (s + l.photons as u64, n + 1));
        sum as f64 / n.max(1) as f64
    }

    /// The fit error: negative log-likelihood per unit photon weight, averaged over fitted
    /// splats.
    pub fn nll(&self) -> f64 {
        let (sum, n) = self
            .fitted()
            .filter(|l| l.weight > 0.0)
            .fold((0.0f64, 0u64), |(s, n), l| {
                (s - l.log_likelihood as f64 / l.weight as f64, n + 1)
            });
        sum / n.max(1) as f64
    }

    /// The light of the splats whose lobes were fitted.
    pub fn fitted(&self) -> impl Iterator<Item = &SplatLight> {
        self.light.iter().filter(|l| l.lobes > 0)
    }
}

/// Fixed-point units of the largest power one emitted photon carries, in a deposit's sums:
/// 2²⁰, so that a photon keeps 6 digits and may gain 4096× its power on its bounces before
/// its value saturates.
pub const DEPOSIT_POWER_UNITS: f32 = 1_048_576.0;

/// How far past its photons' mean a deposit's disk may reach, in splat radii: photons land
/// within a radius of the centre, so the spread's disk, rho² = 2 E|x − mean|², is at most √2.
pub const DEPOSIT_REACH: f32 = std::f32::consts::SQRT_2;

/// The share of splats whose radius bounds the deposits' reach. A mesh's few large triangles
/// (the bunny's base: 113 of its 34,835 vertices cover radii 3–10× the median) would otherwise
/// size every splat's search: sized by the largest radius, the bunny scene's `deposit_share`
/// visited 48 M records, the box's 2.2 M. The deposits of the larger splats keep their photons
/// within the reach (`spread_max`), a narrower disk about the same mean.
pub const SPREAD_QUANTILE: f64 = 0.99;

/// Splat radii sampled for `SPREAD_QUANTILE`: at most about this many, evenly strided.
const SPREAD_SAMPLES: usize = 1 << 20;

/// The radius below which `SPREAD_QUANTILE` of `splats` lie (0 for none), from an evenly
/// strided sample of them, so that it costs the same at 50 M splats as at 1 M.
pub fn spread_radius(splats: &[crate::types::Splat]) -> f32 {
    let stride = splats.len().div_ceil(SPREAD_SAMPLES).max(1);
    let mut radii: Vec<f32> = splats.iter().step_by(stride).map(|s| s.radius).collect();
    if radii.is_empty() {
        return 0.0;
    }
    let at = ((radii.len() - 1) as f64 * SPREAD_QUANTILE).round() as usize;
    *radii.select_nth_unstable_by(at, f32::total_cmp).1
}

/// The deposit passes' uniform for `photons` emitted from `lights` onto `splats`, for search
/// radius `radius` (photon counts per dispatch are filled in per page).
pub fn deposit_params(
    lights: &[Light],
    photons: u64,
    splats: &[crate::types::Splat],
    radius: f32,
) -> Result<crate::types::DepositParams> {
    check_radius(radius).map_err(Error::Invalid)?;
    let unit = crate::photons::emitters(lights, photons.max(1))?
        .iter()
        .flat_map(|e| e.photon_power.map(|p| p * e.falloff_norm))
        .fold(0.0f32, f32::max);
    if !(unit > 0.0 && unit.is_finite()) {
        return Err(Error::Invalid(
            "the lights' photons carry no finite power to deposit".into(),
        ));
    }
    let splat_count = u32::try_from(splats.len())
        .map_err(|_| Error::Invalid("too many splats for the deposits".into()))?;
    let spread_max = DEPOSIT_REACH * spread_radius(splats);
    Ok(crate::types::DepositParams {
        power_scale: DEPOSIT_POWER_UNITS / unit,
        photon_count: 0,
        splat_count,
        reach: radius + spread_max,
        spread_max,
        ..Default::default()
    })
}
