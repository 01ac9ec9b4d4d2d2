//! The lobe fit (selection, gathering, EM), final gathering's rays, and the direct bake.

use crate::em::{
    EmConfig, EmStats, FitShape, GatherSetup, LobeMap, dispatch_ranges, iterations_per_dispatch,
    workgroup_size,
};
use crate::error::{Error, Result};
use crate::shaders::Stage;
use crate::shared::lobes::{EM_DEFER_FIT, EM_GROUPS, EM_SHARE};
use crate::timing::ms_since;
use crate::types::{DirectParams, EmParams, GatherParams, Lobe, Splat, SplatLight};

use super::estimate::{
    CoverInput, Records, SharedDeposits, cover_light, share_light, smooth_light,
};
use super::{Executor, groups};

/// What `deposit_share` reads besides the binned records (`FitInput`'s bins are then the
/// deposits' bins).
pub struct DepositInput<'a, B> {
    /// `DepositParams::reach`: `fit_select` lists the splats with deposits within it.
    pub reach: f32,
    pub params: &'a B,
    pub keys: &'a B,
    pub spread: &'a B,
}

/// What the lobe fit reads of the binned photons.
pub struct FitInput<'a, B> {
    pub bin_params: &'a B,
    pub cell_start: &'a B,
    pub geom: &'a B,
    pub power: &'a B,
    /// The splats and their materials.
    pub splats: &'a B,
    pub materials: &'a B,
    pub splat_count: u32,
    /// Final gathering for the fitted splats' lobes, with `EmConfig::gather` rays a side; the
    /// executor then traces the scene's splats.
    pub gathering: Option<Gathering<'a, B>>,
    /// The bins hold deposits, not photons: every splat's irradiance comes from `deposit_share`
    /// (which needs final gathering: the deposits carry no photon directions to fit).
    pub deposits: Option<DepositInput<'a, B>>,
    /// Shared fits: only the groups' leaders are fitted, from their members' rays.
    pub groups: Option<GroupInput<'a, B>>,
    /// Shared coverage: `estimate_coverage` measures once a group (else once a splat).
    pub cover: Option<CoverInput<'a, B>>,
}

/// The shared fits' groups in the executor's memory (`fit_groups::FitGroups::words`), with
/// where their starts and members lie in it.
pub struct GroupInput<'a, B> {
    pub words: &'a B,
    pub starts_at: u32,
    pub members_at: u32,
}

/// What final gathering needs besides the photons: its setup (`em::GatherSetup`), with the
/// setup's lights where the executor holds them.
pub struct Gathering<'a, B> {
    pub setup: &'a GatherSetup<'a>,
    pub lights: &'a B,
    /// The splats on the host, whose order in space the direct bake takes them in
    /// (`grid::splat_order`, made only where final gathering runs).
    pub splats: &'a [Splat],
    /// The most bytes of samples one batch of splats holds (the rays of the fit list are
    /// cast and fitted a batch at a time).
    pub batch_bytes: u64,
}

/// The lobe fit where it ran: `cfg.lobes` slots a splat (dense, unpacked) and each splat's
/// light, with the counts the selection found.
pub struct Fit<B> {
    pub lobes: B,
    pub light: B,
    /// Splats on the fit list: those fitted, and those not fitted with too many candidates
    /// for one invocation.
    pub listed: u32,
    /// Splats on the gather list (`estimate_gather`).
    pub gathered: u32,
    pub fitted: u32,
    pub max_candidates: u32,
    pub dispatches: u32,
    /// Wall time of the passes: `fit_select` with its readback, `estimate_gather`, `em_fit`, and
    /// with final gathering the direct bake and `final_gather` (their `em_fit` in `fit_ms`).
    pub select_ms: f64,
    pub gather_ms: f64,
    pub fit_ms: f64,
    pub final_gather_ms: f64,
    /// The direct bake's part of `final_gather_ms`.
    pub direct_bake_ms: f64,
    /// With final gathering, the direct bake its rays read: every splat's, of the setup's
    /// lights, the same as the frames bake (`bake_direct`), so they may take it.
    pub direct: Option<DirectBake<B>>,
    /// `estimate_smooth`'s counts (`smooth_light`; zeros where it did not run).
    pub smoothed: [u32; 4],
}

impl<B> Fit<B> {
    /// The fit's figures, `ms` its wall time (`photons` is summed when its lobes are read).
    pub fn stats(&self, ms: f64) -> EmStats {
        EmStats {
            listed: self.listed + self.gathered,
            fitted: self.fitted,
            max_candidates: self.max_candidates,
            photons: 0,
            dispatches: self.dispatches,
            ms,
            select_ms: self.select_ms,
            gather_ms: self.gather_ms,
            fit_ms: self.fit_ms,
            final_gather_ms: self.final_gather_ms,
            direct_bake_ms: self.direct_bake_ms,
            rays: 0,
            served: 0,
            coverages: 0,
            smoothed: self.smoothed,
        }
    }

    /// The fit of `splat_count` splats, `per_splat` lobe slots each, in host memory with its
    /// lobes packed (`LobeMap::pack`); with nothing fitted no lobe is read.
    pub fn read_back<E: Executor<Buffer = B>>(
        &self,
        ex: &mut E,
        per_splat: u32,
        splat_count: u32,
        stats: EmStats,
    ) -> Result<LobeMap> {
        let dense = match self.fitted {
            0 => Vec::new(),
            n => ex.read::<Lobe>(&self.lobes, n as usize * per_splat as usize)?,
        };
        let light = ex.read::<SplatLight>(&self.light, splat_count as usize)?;
        let mut map = LobeMap::pack(per_splat, &dense, light, stats);
        map.stats.photons = map.fitted().map(|l| l.photons as u64).sum();
        Ok(map)
    }
}

/// The lobe fit: `fit_select` lists the splats with photons near them, in two lists → (split: the
/// lists' lengths and the most candidates a fit-list splat has, which sizes the dispatches on a
/// loop-limited device) → `estimate_gather`, one invocation per splat of the gather list
/// (irradiance alone) → `em_fit`, one workgroup per splat of the fit list, in one dispatch or in
/// several that hand the mixture over through the lobe buffer. With final gathering (`cfg.gather` >
/// 0), that `em_fit` gives the fitted splats only their irradiance, then `direct_bake` →
/// `final_gather` from each fitted splat → `em_fit` over those samples. With deposits
/// (`input.deposits`, final gathering only), the bins hold the deposits: `deposit_share` gives
/// every splat its irradiance in place of `estimate_gather` and the photon `em_fit`. Wherever the
/// scene's geometry is given (`input.gathering`), `estimate_coverage` divides every splat's
/// irradiance by the share of its gather disk its surface covers before final gathering, whether or
/// not anything is fitted.
pub fn fit_lobes<E: Executor>(
    ex: &mut E,
    input: &FitInput<E::Buffer>,
    cfg: &EmConfig,
    shape: FitShape,
) -> Result<Fit<E::Buffer>> {
    cfg.validate()?;
    if input.deposits.is_some() && cfg.gather == 0 {
        return Err(Error::Invalid(
            "deposits carry no photon directions: the photon fit (gather 0) needs the \
             photons' estimate"
                .into(),
        ));
    }
    let t = std::time::Instant::now();
    let splat_count = input.splat_count;
    let n = splat_count as u64;
    let light = ex.zeroed("splat light", n.max(1) * 32)?;
    let fit_list = ex.zeroed("fit list", n.max(1) * 8)?;
    let gather_list = ex.zeroed("gather list", n.max(1) * 4)?;
    let counters = ex.zeroed("em counters", 16)?;
    // Without shared fits a word stands in for the groups (no stage reads it).
    let no_groups = ex.zeroed("no fit groups", 4)?;
    let fit_groups = input.groups.as_ref().map_or(&no_groups, |g| g.words);
    let mut select_params = cfg.params(splat_count, 0, shape);
    if let Some(d) = &input.deposits {
        select_params.radius = d.reach;
        select_params.flags |= EM_SHARE;
    }
    if input.groups.is_some() {
        select_params.flags |= EM_GROUPS;
    }
    let select = ex.uniform("em select params", &select_params)?;
    let bindings = [
        &select,
        input.bin_params,
        input.splats,
        input.materials,
        input.cell_start,
        &fit_list,
        &counters,
        &gather_list,
        fit_groups,
    ];
    ex.dispatch(
        Stage::FitSelect,
        &bindings,
        groups(Stage::FitSelect, splat_count)?,
    )?;
    let (listed, max_candidates, fitted, gathered) = match ex.read::<u32>(&counters, 4)?[..] {
        [a, b, c, d] => (a, b, c, d),
        _ => return Err(Error::Gpu("em counters readback was short".into())),
    };
    let select_ms = ms_since(t);
    // The passes over every splat (deposits, coverage, smoothing) leave the photon fit's lobes
    // as they are.
    let every_splat = cfg.params(splat_count, splat_count, shape);
    match &input.deposits {
        // Every splat's irradiance from the deposits around it, summed once a coverage group,
        // at its leader, then copied to the members.
        Some(d) => {
            let deposits = SharedDeposits {
                deposit_params: d.params,
                bin_params: input.bin_params,
                splats: input.splats,
                materials: input.materials,
                cell_start: input.cell_start,
                keys: d.keys,
                geom: input.geom,
                power: input.power,
                spread: d.spread,
            };
            share_light(
                ex,
                &every_splat,
                &deposits,
                (&light, &counters),
                input.cover.as_ref(),
            )?;
        }
        None => {
            let gather = ex.uniform(
                "em gather params",
                &cfg.params(splat_count, gathered, shape),
            )?;
            let bindings = [
                &gather,
                input.bin_params,
                input.splats,
                &gather_list,
                input.cell_start,
                input.geom,
                input.power,
                &light,
            ];
            ex.dispatch(
                Stage::EstimateGather,
                &bindings,
                groups(Stage::EstimateGather, gathered)?,
            )?;
        }
    }
    // A split point of its own, so that the gather's time and the fit's are told apart (one
    // more submission, well under a millisecond); deposit_share counts the splats it lit that are
    // not fitted.
    let gathered = match (&input.deposits, &ex.read::<u32>(&counters, 4)?[..]) {
        (Some(_), &[.., lit]) => lit,
        _ => gathered,
    };
    let gather_ms = ms_since(t) - select_ms;
    // Lobes for the fitted splats alone, at the slots fit_select gave them.
    let lobes = ex.zeroed("lobes", (fitted as u64 * cfg.lobes as u64).max(1) * 32)?;
    let gathering = match (&input.gathering, cfg.gather) {
        (_, 0) => None,
        (Some(g), _) if fitted > 0 => Some(g),
        (Some(_), _) => None,
        (None, _) => {
            return Err(Error::Internal(
                "final gathering needs the scene's lights and geometry".into(),
            ));
        }
    };
    let mut params = cfg.params(splat_count, listed, shape);
    if gathering.is_some() {
        params.flags |= EM_DEFER_FIT;
    }
    let fit_input = EmFitInput {
        input,
        fit_list: &fit_list,
        candidates: [input.geom, input.power],
        lobes: &lobes,
        light: &light,
    };
    // With deposits deposit_share gave every splat its irradiance; no pass over photons is left.
    let mut dispatches = match input.deposits {
        Some(_) => 0,
        None => em_fit(ex, cfg, shape, &params, max_candidates, &fit_input)?,
    };
    // The photons' estimate where the gather disk leaves the surface, on every path that has
    // the scene's geometry: before final gathering's rays read it, and where no fit follows
    // (an all-diffuse scene fits nothing, yet its edges darkened as the glossy scene's did).
    if input.gathering.is_some() {
        cover_light(ex, &every_splat, &light, input.cover.as_ref())?;
    }
    // The deposits' estimate widened where the light is smooth, before the rays read it.
    let mut smoothed = [0; 4];
    if let (Some(d), true) = (&input.deposits, cfg.smooth > 0.0) {
        let records = Records {
            deposit_params: d.params,
            bin_params: input.bin_params,
            splats: input.splats,
            cell_start: input.cell_start,
            keys: d.keys,
        };
        smoothed = smooth_light(ex, &every_splat, &records, &light, input.cover.as_ref())?;
    }
    ex.read::<u32>(&counters, 1)?;
    let mut fit_ms = ms_since(t) - select_ms - gather_ms;
    let mut final_gather_ms = 0.0;
    let mut direct_bake_ms = 0.0;
    let mut direct = None;
    if let Some(g) = gathering {
        let refit = Refit {
            fit_input,
            counters: &counters,
            listed,
            groups: fit_groups,
        };
        let rays = fit_to_rays(ex, cfg, shape, g, &refit)?;
        let (more, gather_rays_ms, refit_ms) = (rays.dispatches, rays.rays_ms, rays.fit_ms);
        direct = Some(rays.direct);
        direct_bake_ms = rays.direct_ms;
        dispatches += more;
        final_gather_ms = gather_rays_ms;
        fit_ms += refit_ms;
    }
    Ok(Fit {
        lobes,
        light,
        listed,
        gathered,
        fitted,
        max_candidates,
        dispatches,
        select_ms,
        gather_ms,
        fit_ms,
        final_gather_ms,
        direct_bake_ms,
        direct,
        smoothed,
    })
}

/// What `fit_to_rays` takes of the photon fit: its `em_fit` buffers, its counters (read back
/// to split the passes' times) and the fit list's length.
struct Refit<'a, B> {
    fit_input: EmFitInput<'a, B>,
    counters: &'a B,
    listed: u32,
    /// The shared fits' groups (a word where there are none).
    groups: &'a B,
}

/// What `fit_to_rays` did: the `em_fit` dispatches, the milliseconds of the rays (with the
/// direct bake), of their fit and of the direct bake alone, and the direct bake.
struct Rays<B> {
    dispatches: u32,
    rays_ms: f64,
    fit_ms: f64,
    direct_ms: f64,
    direct: DirectBake<B>,
}

/// Final gathering and the fit to it (design §6), after the photon fit gave every splat its
/// irradiance: the direct bake, then per batch of the fit list `final_gather` and `em_fit` over
/// its samples.
fn fit_to_rays<E: Executor>(
    ex: &mut E,
    cfg: &EmConfig,
    shape: FitShape,
    g: &Gathering<E::Buffer>,
    refit: &Refit<E::Buffer>,
) -> Result<Rays<E::Buffer>> {
    let (input, light, counters, listed) = (
        refit.fit_input.input,
        refit.fit_input.light,
        refit.counters,
        refit.listed,
    );
    let n = input.splat_count as u64;
    let t = std::time::Instant::now();
    let order = ex.upload("direct order", &crate::grid::splat_order(g.splats))?;
    let direct = bake_direct(ex, g.lights, &order, &g.setup.direct)?;
    // A readback waits for the bake, so that its time is told apart: it grows with every
    // splat, where the rays and their fit grow with the fits.
    ex.read::<u32>(counters, 1)?;
    let direct_ms = ms_since(t);
    // The rays read the photons' irradiance where they meet a splat, also a glossy one that
    // an earlier batch has refitted: a copy keeps the result the same for any batch size.
    let photon_light = ex.zeroed("photon light", n.max(1) * 32)?;
    ex.copy(light, 0, &photon_light, 0, n * 32)?;
    let rays = cfg.gather * cfg.gather;
    let per_entry = rays as u64 * 16;
    let batch = (g.batch_bytes / per_entry).clamp(1, listed.max(1) as u64) as u32;
    let samples = ex.zeroed("gather samples", batch as u64 * per_entry)?;
    ex.read::<u32>(counters, 1)?;
    let mut rays_ms = ms_since(t);
    let mut fit_ms = 0.0;
    let mut dispatches = 0;
    // The samples stand in for the photons' power; their geometry is not read, and one
    // record stands in for it (no pages to bind).
    let no_geometry = ex.zeroed("no photon geometry", 64)?;
    let fit_input = EmFitInput {
        candidates: [&no_geometry, &samples],
        ..refit.fit_input
    };
    for first in (0..listed).step_by(batch as usize) {
        let t = std::time::Instant::now();
        let count = batch.min(listed - first);
        let (group_starts, group_members) = input
            .groups
            .as_ref()
            .map_or((0, 0), |g| (g.starts_at, g.members_at));
        let gather = GatherParams {
            splat_count: count,
            samples: cfg.gather,
            seed: g.setup.seed,
            shadow_bias: g.setup.shadow_bias,
            first,
            light_count: g.setup.direct.light_count,
            group_starts,
            group_members,
        };
        let baked = (&photon_light, &direct.direct);
        final_gather(
            ex,
            &gather,
            (fit_input.fit_list, refit.groups),
            baked,
            &samples,
            (input.materials, g.lights),
        )?;
        ex.read::<u32>(counters, 1)?;
        rays_ms += ms_since(t);
        let t = std::time::Instant::now();
        let params = EmParams {
            gathered: rays,
            inv_area: std::f32::consts::PI / rays as f32,
            list_first: first,
            ..cfg.params(input.splat_count, first + count, shape)
        };
        dispatches += em_fit(ex, cfg, shape, &params, rays, &fit_input)?;
        ex.read::<u32>(counters, 1)?;
        fit_ms += ms_since(t);
    }
    Ok(Rays {
        dispatches,
        rays_ms,
        fit_ms,
        direct_ms,
        direct,
    })
}

/// The buffers of `em_fit`'s dispatches.
struct EmFitInput<'a, B> {
    input: &'a FitInput<'a, B>,
    fit_list: &'a B,
    /// Bound as the binned photons' geometry and power.
    candidates: [&'a B; 2],
    lobes: &'a B,
    light: &'a B,
}

/// `em_fit` over the fit list with the uniform `params`, its iterations split over as many
/// dispatches as `max_candidates` a splat need on this device; returns how many.
fn em_fit<E: Executor>(
    ex: &mut E,
    cfg: &EmConfig,
    shape: FitShape,
    params: &EmParams,
    max_candidates: u32,
    b: &EmFitInput<E::Buffer>,
) -> Result<u32> {
    let chunk = iterations_per_dispatch(cfg, max_candidates, shape.loop_limited)?;
    let constants = [
        ("LOBES", cfg.lobes as f64),
        ("FAMILY", cfg.family.code() as f64),
        ("WG", workgroup_size(shape.loop_limited) as f64),
        ("SPARSE", f64::from(u8::from(cfg.sparse))),
    ];
    let defines: &[&str] = if shape.subgroup_reduce {
        &["subgroups"]
    } else {
        &[]
    };
    let mut dispatches = 0;
    for (begin, end) in dispatch_ranges(cfg.iterations, chunk) {
        let params = EmParams {
            iteration_begin: begin,
            iteration_end: end,
            ..*params
        };
        let uniform = ex.uniform("em params", &params)?;
        let bindings = [
            &uniform,
            b.input.bin_params,
            b.input.splats,
            b.fit_list,
            b.input.cell_start,
            b.candidates[0],
            b.candidates[1],
            b.lobes,
            b.light,
        ];
        ex.dispatch_variant(
            Stage::EmFit,
            defines,
            &constants,
            &bindings,
            params.active_count,
        )?;
        dispatches += 1;
    }
    Ok(dispatches)
}

/// The direct bake where it was made: per splat its shadowed irradiance (`[E, 0]`), and per
/// splat and light the light's visibility (`direct_bake.wgsl`).
pub struct DirectBake<B> {
    pub direct: B,
    pub visibility: B,
}

impl<B> DirectBake<B> {
    /// Both in host memory.
    pub fn read_back<E: Executor<Buffer = B>>(
        &self,
        ex: &mut E,
        params: &DirectParams,
    ) -> Result<DirectMap> {
        let n = params.splat_count as usize;
        Ok(DirectMap {
            direct: ex.read(&self.direct, n)?,
            visibility: ex.read(&self.visibility, n * params.light_count as usize)?,
        })
    }
}

/// The direct bake in host memory: per splat `[E, 0]`, its shadowed irradiance from every
/// light, and per splat and light (`splat * lights + light`) the light's visibility.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DirectMap {
    pub direct: Vec<[f32; 4]>,
    pub visibility: Vec<f32>,
}

/// Bakes the direct light of `lights` (`params.light_count` of them) into every splat of the
/// executor's geometry: `direct_bake` over the splats, taken in `order` (`grid::splat_order`),
/// then its `share`, which adds an environment light from the neighbours' blocked shares.
pub fn bake_direct<E: Executor>(
    ex: &mut E,
    lights: &E::Buffer,
    order: &E::Buffer,
    params: &DirectParams,
) -> Result<DirectBake<E::Buffer>> {
    let n = params.splat_count as u64;
    let direct = ex.zeroed("direct light", n.max(1) * 16)?;
    let visibility = ex.zeroed(
        "light visibility",
        (n * params.light_count as u64).max(1) * 4,
    )?;
    let blocked = ex.zeroed("sky blocked shares", n.max(1) * 4)?;
    let uniform = ex.uniform("direct params", params)?;
    let bindings = [&uniform, lights, &direct, &visibility, order, &blocked];
    let groups = groups(Stage::DirectBake, params.splat_count)?;
    ex.dispatch_traced(Stage::DirectBake, &bindings, groups)?;
    ex.dispatch_traced(Stage::DirectBake.entry("share"), &bindings, groups)?;
    Ok(DirectBake { direct, visibility })
}

/// Final gathering (`final_gather.wgsl`): `samples²` rays from each fitted splat of the fit
/// list `list`'s entries `first..first + splat_count` (`params`) over its hemisphere (with
/// shared fits, from its group's members in turn, as `groups` lists them), with the
/// radiance each brings back from the surfaces' baked light (`light`: their photon irradiance;
/// `direct`: the direct bake), their `materials` and the scene's `lights` (a ray that meets an
/// area light first brings none), into `samples`: `[radiance, direction bits]`, `samples²` an
/// entry from the batch's first.
pub fn final_gather<E: Executor>(
    ex: &mut E,
    params: &GatherParams,
    (list, fit_groups): (&E::Buffer, &E::Buffer),
    (light, direct): (&E::Buffer, &E::Buffer),
    samples: &E::Buffer,
    (materials, lights): (&E::Buffer, &E::Buffer),
) -> Result<()> {
    let per_splat = (params.samples * params.samples) as u64;
    let rays = params.splat_count as u64 * per_splat;
    let count = u32::try_from(rays).map_err(|_| {
        Error::DeviceLimit(format!(
            "final gathering: {rays} rays are more than one dispatch holds"
        ))
    })?;
    let uniform = ex.uniform("gather params", params)?;
    let bindings = [
        &uniform, list, light, direct, samples, materials, lights, fit_groups,
    ];
    ex.dispatch_traced(
        Stage::FinalGather,
        &bindings,
        groups(Stage::FinalGather, count)?,
    )
}
