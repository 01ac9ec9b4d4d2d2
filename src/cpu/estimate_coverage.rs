//! Mirror of `wgsl/estimate_coverage.wgsl`: the share of its gather disk a group's leader's surface
//! covers (`main`, one invocation a group), and each splat's photon irradiance divided by its
//! group's share (`apply`).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{IVec3, UVec3, Vec2, Vec3};
use rayon::prelude::*;

use crate::grid::{DIST_MASK, cell_index, point_cell};
use crate::shared::bins::SURFACE_COS_MIN;
use crate::shared::sampling::frame_of;
use crate::shared::trace::Geometry;
use crate::types::{EmParams, GridParams, SplatLight};

pub const WG: u32 = 64;
/// The least share divided by: a splat's disk on a thin feature keeps a bounded estimate.
pub const COVERAGE_MIN: f32 = 0.2;
/// Disk tests a splat may spend.
pub const COVERAGE_BUDGET: u32 = 16384;
/// Points of the gather disk where its coverage is measured, in units of R: a Vogel spiral,
/// point k at radius √((k + ½)/N), turned by the golden angle from the one before. Each stands
/// for an equal area, ring by ring, so the share within any radius is right to half a point: a
/// square grid's rings (69 points) cut a curved model's cap, which ends at a radius between
/// them, 10–15 % off. The last `COVERAGE_PROBES`, nearest the rim and spread around it,
/// are tested first: a splat whose probes are all covered lies inside its face and keeps its
/// estimate. Written out (f32 literals), as in the WGSL twin, so both test the same points.
pub const COVERAGE_POINTS: [[f32; 2]; 64] = [
    [0.088388346, 0.0],
    [-0.11288609, 0.10341291],
    [0.017279025, -0.19688559],
    [0.14228562, 0.18558638],
    [-0.2611116, -0.046186965],
    [0.2473477, -0.15734236],
    [-0.08273296, 0.3077625],
    [-0.15778074, -0.30379722],
    [0.34232107, 0.12501511],
    [-0.35612804, 0.14700449],
    [0.17167725, -0.36686432],
    [0.12686512, 0.404466],
    [-0.38237295, -0.22159293],
    [0.448567, -0.0986162],
    [-0.27375346, 0.38938612],
    [-0.06324339, -0.48804486],
    [0.38825238, 0.32721952],
    [-0.522466, 0.021605609],
    [0.38109884, -0.37924424],
    [-0.025496988, 0.5513959],
    [-0.36261675, -0.43453607],
    [0.574425, 0.07728807],
    [-0.48670912, 0.33863953],
    [0.13299693, -0.5911847],
    [0.30761498, 0.5368291],
    [-0.6013578, -0.19184956],
    [0.5841426, -0.2698887],
    [-0.25306517, 0.6046863],
    [-0.2258551, -0.6279347],
    [0.60097617, 0.31585622],
    [-0.6675333, 0.17595963],
    [0.37943053, -0.59010166],
    [0.12069909, 0.7023135],
    [-0.57200783, -0.442995],
    [0.7317019, -0.06062001],
    [-0.50576025, 0.54671204],
    [0.003684028, -0.7551814],
    [0.51430494, 0.56694615],
    [-0.7722949, -0.07157611],
    [0.6257873, -0.47495025],
    [-0.14238057, 0.7826495],
    [-0.42888394, -0.6815395],
    [0.78592014, 0.21538812],
    [-0.7334855, 0.37641266],
    [0.28986168, -0.7818521],
    [0.31791148, 0.7809416],
    [-0.7702639, -0.36504245],
    [0.8232633, -0.25382087],
    [-0.44015652, 0.7510491],
    [-0.18464324, -0.85985136],
    [0.72417736, 0.5144217],
    [-0.89015734, 0.1109386],
    [0.58705425, -0.6896954],
    [0.033319898, 0.91368884],
    [-0.64772695, -0.6572764],
    [0.93001413, 0.047552247],
    [-0.7243231, 0.5984718],
    [0.13097532, -0.9387667],
    [0.5422049, 0.7874493],
    [-0.93964905, -0.21621105],
    [0.8459368, -0.47927395],
    [-0.3024919, 0.93243563],
    [-0.4100971, -0.89910114],
    [0.91697586, 0.38902795],
];
/// How many of `COVERAGE_POINTS`, the last, are tested first.
pub const COVERAGE_PROBES: usize = 8;

/// The photons a covered point stands for, against a point of the plane: a disk whose
/// normal turns from the plane's by an angle of cosine `cos` holds 1/cos as much surface over
/// the point (photons land on the surface, not on its shadow in the plane), of which the
/// photons that arrive at the plane's front count, (1 + cos)/2 of light spread as cosine about
/// the disk's normal (`front_share`). 1 on a flat face.
pub fn surface_weight(cos: f32) -> f32 {
    (1.0 + cos) / (2.0 * cos)
}

/// What point `q` of the gather disk of centre `c` and normal `n` counts towards its
/// covered share: `surface_weight` of the first disk that reaches over `q` at a point the
/// photons' test keeps (within `slab` of the plane, within R of `c`, facing within
/// `SURFACE_COS_MIN`), where its surface keeps it; else 0. Where the surface curves away from
/// the plane, the surface over `q` lies up to the slab away from it along `n`, in another
/// cell: the cells along `n` through `q` are searched, `q`'s own first, then from one end of
/// the slab to the other in steps of half a cell.
fn covered(
    geo: &Geometry,
    em: &EmParams,
    q: Vec3,
    (c, n): (Vec3, Vec3),
    slab: f32,
    budget: &mut u32,
) -> f32 {
    let g = &geo.grid.params;
    let own = cell_at(q, g);
    if let Some(w) = own.and_then(|ci| covered_in_cell(geo, em, ci, q, (c, n), slab, budget)) {
        return w;
    }
    let step = 0.5 * g.cell_size;
    let steps = (slab / step).ceil() as i32;
    let mut last = own;
    for k in -steps..=steps {
        let ci = cell_at(q + (k as f32 * step) * n, g);
        if ci.is_none() || ci == own || ci == last {
            continue;
        }
        last = ci;
        if let Some(w) = ci.and_then(|ci| covered_in_cell(geo, em, ci, q, (c, n), slab, budget)) {
            return w;
        }
    }
    0.0
}

/// The grid cell of `p`, if it lies in the grid.
fn cell_at(p: Vec3, g: &GridParams) -> Option<u32> {
    let cell = point_cell(p, g);
    if cell.cmplt(IVec3::ZERO).any() || cell.cmpge(UVec3::from(g.dims).as_ivec3()).any() {
        return None;
    }
    Some(cell_index(cell.as_uvec3(), g))
}

/// `covered` within cell `ci`: the weight of the first of its disks that reaches over `q`
/// where its surface keeps it, if any.
fn covered_in_cell(
    geo: &Geometry,
    em: &EmParams,
    ci: u32,
    q: Vec3,
    (c, n): (Vec3, Vec3),
    slab: f32,
    budget: &mut u32,
) -> Option<f32> {
    // An empty cell (the distance field's nonzero) lists no disk.
    if geo.grid.cell_dist[ci as usize] & DIST_MASK != 0 {
        return None;
    }
    // The next disk that reaches over q, then its clip (as the WGSL twin reads it).
    let mut disks = geo.grid.cell(ci).iter();
    loop {
        let mut found = None;
        for &j in disks.by_ref() {
            if *budget == 0 {
                break;
            }
            *budget -= 1;
            let s = &geo.splats[j as usize];
            let sn = Vec3::from(s.normal);
            let cos = sn.dot(n);
            if cos < SURFACE_COS_MIN {
                continue;
            }
            // The line through q along n meets this disk's plane at height t over the gather
            // disk's plane: the point whose shadow in the plane q is, tested as photons are.
            let t = -(q - Vec3::from(s.center)).dot(sn) / cos;
            let at = q + t * n;
            let p = at - Vec3::from(s.center);
            if t.abs() <= slab
                && p.dot(p) <= s.radius * s.radius
                && (at - c).length_squared() <= em.radius2
            {
                found = Some((s, at, cos));
                break;
            }
        }
        match found {
            None => return None,
            Some((s, at, cos)) if geo.keeps(s, at) => return Some(surface_weight(cos)),
            Some(_) => {}
        }
    }
}

/// The share of splat `i`'s gather disk its surface covers, 1 where the search was cut short.
fn share(em: &EmParams, geo: &Geometry, i: usize) -> f32 {
    let s = &geo.splats[i];
    let (centre, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let f = frame_of(normal);
    let slab = em.slab * s.radius;
    let mut budget = COVERAGE_BUDGET;
    let point = |u: Vec2| centre + em.radius * (u.x * f.t + u.y * f.b);
    let disk = (centre, normal);
    let n = COVERAGE_POINTS.len();
    let (mut probes, mut area) = (0, 0f32);
    for u in &COVERAGE_POINTS[n - COVERAGE_PROBES..] {
        let w = covered(geo, em, point(Vec2::from(*u)), disk, slab, &mut budget);
        probes += (w > 0.0) as usize;
        area += w;
    }
    if probes == COVERAGE_PROBES {
        return 1.0;
    }
    for u in &COVERAGE_POINTS[..n - COVERAGE_PROBES] {
        area += covered(geo, em, point(Vec2::from(*u)), disk, slab, &mut budget);
    }
    // A search cut short corrects nothing.
    if budget == 0 {
        return 1.0;
    }
    (area / n as f32).clamp(COVERAGE_MIN, 1.0)
}

/// The first pass (`main`): each of `em.active_count` groups' share, at its leader (`cover`'s
/// words after the splats').
pub fn estimate_coverage(
    em: &EmParams,
    (cover, shares): (&[u32], &mut [f32]),
    geo: &Geometry,
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    let count = invocations.min(em.active_count as usize);
    let leaders = &cover[em.splat_count as usize..];
    shares[..count]
        .par_iter_mut()
        .zip(&leaders[..count])
        .for_each(|(share_out, &leader)| *share_out = share(em, geo, leader as usize));
}

/// The second pass (`apply`): each splat's irradiance divided by its group's share.
pub fn apply(em: &EmParams, light: &mut [SplatLight], (cover, shares): (&[u32], &[f32]), groups: u32) {
    let invocations = (groups * WG) as usize;
    let count = invocations.min(em.splat_count as usize);
    light[..count]
        .par_iter_mut()
        .zip(&cover[..count])
        .for_each(|(l, &group)| {
            if l.photons == 0 || l.lobes > 0 {
                return;
            }
            l.irradiance = (Vec3::from(l.irradiance) / shares[group as usize]).into();
        });
}

/// The executor's entry of `main`: `estimate_coverage`'s bindings, unpacked in the order its
/// WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let cover = b.get(2)?;
    let mut shares = b.get_mut(3)?;
    let on = (view(&cover), view_mut(&mut shares));
    estimate_coverage(&em, on, geo, groups);
    Ok(())
}

/// The executor's entry of `apply` (bound as `main` is, the scene's geometry unread).
pub fn dispatch_apply(b: &Bindings, _geo: &Geometry, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let mut light = b.get_mut(1)?;
    let cover = b.get(2)?;
    let shares = b.get(3)?;
    apply(&em, view_mut(&mut light), (view(&cover), view(&shares)), groups);
    Ok(())
}

/// This file's rows of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::EstimateCoverage,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
    MirrorRow {
        stage: Stage::EstimateCoverage,
        entry: "apply",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch_apply)),
    },
];
