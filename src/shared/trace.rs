//! Twin of `wgsl/shared/trace.wgsl`: the nearest front-facing disk along a ray through the
//! splat grid, where its surface keeps it, with the same hit policy and the same traversal
//! steps (see the WGSL file).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{BVec3, IVec3, Vec3};

use crate::grid::{DIST_MASK, SplatGrid, cone_faces_away, floor_cell};
use crate::types::{Hit, NO_SPLAT, Splat, SurfaceClip};

pub const PARALLEL_COS: f32 = 1e-6;
pub const FAR: f32 = 3.0e38;

/// Bind group 1 of the tracing stages.
#[derive(Clone, Copy, Debug)]
pub struct Geometry<'a> {
    pub grid: &'a SplatGrid,
    pub splats: &'a [Splat],
    /// Per surface (`Splat::object`), where its disks end; a surface past the end clips nothing.
    pub clips: &'a [SurfaceClip],
    /// The environment light's map (`scene::sky::SkyTable`; its header alone where none).
    pub sky: &'a [[f32; 4]],
}

impl Geometry<'_> {
    /// Ray parameter of the hit with splat `s`'s disk where its surface keeps it, or −1.
    pub fn intersect(&self, s: &Splat, o: Vec3, d: Vec3) -> f32 {
        let t = intersect_disk(s, o, d);
        if t < 0.0 || self.keeps(s, o + t * d) {
            t
        } else {
            -1.0
        }
    }

    /// Whether splat `s`'s surface keeps the point `p` of its disk (`SurfaceClip`).
    pub fn keeps(&self, s: &Splat, p: Vec3) -> bool {
        self.clips.get(s.object as usize).is_none_or(|c| c.keeps(p))
    }
}

/// Ray parameter of the hit with a disk's front face, or −1.
pub fn intersect_disk(s: &Splat, o: Vec3, d: Vec3) -> f32 {
    intersect_sided::<false>(s, o, d)
}

/// `intersect_disk`, or with `EITHER_SIDE` the hit with either face: the host's test of what
/// the back of a disk faces (`scene::sides`), not the stages' policy.
fn intersect_sided<const EITHER_SIDE: bool>(s: &Splat, o: Vec3, d: Vec3) -> f32 {
    let n = Vec3::from(s.normal);
    let c = Vec3::from(s.center);
    let denom = n.dot(d);
    let facing = match EITHER_SIDE {
        true => denom.abs() > PARALLEL_COS,
        false => denom < -PARALLEL_COS,
    };
    if !facing {
        return -1.0;
    }
    let t = n.dot(c - o) / denom;
    let q = o + t * d - c;
    if !(q.dot(q) <= s.radius * s.radius) {
        return -1.0;
    }
    t
}

pub fn miss(t_max: f32) -> Hit {
    Hit {
        t: t_max,
        splat: NO_SPLAT,
        aborted: 0,
        _pad: 0,
    }
}

fn select_i(f: IVec3, t: IVec3, m: BVec3) -> IVec3 {
    IVec3::select(m, t, f)
}

/// `d` must be a unit vector; t is then a distance.
pub fn trace_ray(geo: &Geometry, o: Vec3, d: Vec3, skip: u32, t_max: f32, budget: &mut u32) -> Hit {
    trace_sided::<false>(geo, o, d, skip, t_max, budget)
}

/// `trace_ray`, or with `EITHER_SIDE` meeting disks from either side (no facing cones): the
/// nearest disk, which the caller tells front from back by its normal. Host only: the stages'
/// disks are one-sided.
pub fn trace_sided<const EITHER_SIDE: bool>(
    geo: &Geometry,
    o: Vec3,
    d: Vec3,
    skip: u32,
    t_max: f32,
    budget: &mut u32,
) -> Hit {
    let g = &geo.grid.params;
    let mut hit = miss(t_max);
    let lo = Vec3::from(g.origin);
    let cs = g.cell_size;
    let dims = IVec3::new(g.dims[0] as i32, g.dims[1] as i32, g.dims[2] as i32);
    let hi = lo + dims.as_vec3() * cs;
    let moving = d.abs().cmpgt(Vec3::splat(1e-30));
    let inv = 1.0 / Vec3::select(moving, d, Vec3::ONE);
    let outside = o.cmplt(lo) | o.cmpgt(hi);
    if (!moving & outside).any() {
        return hit;
    }
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let near = Vec3::select(moving, ta.min(tb), Vec3::splat(-FAR));
    let far = Vec3::select(moving, ta.max(tb), Vec3::splat(FAR));
    let t_enter = 0f32.max(near.x.max(near.y.max(near.z)));
    let t_leave = t_max.min(far.x.min(far.y.min(far.z)));
    if !(t_enter <= t_leave) {
        return hit;
    }
    let positive = d.cmpgt(Vec3::ZERO);
    let negative = d.cmplt(Vec3::ZERO);
    let step = select_i(
        IVec3::ZERO,
        select_i(IVec3::NEG_ONE, IVec3::ONE, positive),
        moving,
    );
    let p0 = o + t_enter * d;
    let mut c = floor_cell((p0 - lo) * g.inv_cell_size).clamp(IVec3::ZERO, dims - 1);
    let mut t = t_enter;
    loop {
        if *budget == 0 {
            hit.aborted = 1;
            return hit;
        }
        *budget -= 1;
        let ci = (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
        let word = geo.grid.cell_dist[ci];
        let dist = word & DIST_MASK;
        let k = (dist.max(1) - 1) as i32;
        let face = select_i(c - k, c + k + 1, step.cmpgt(IVec3::ZERO));
        let tf = Vec3::select(
            moving,
            (lo + face.as_vec3() * cs - o) * inv,
            Vec3::splat(FAR),
        );
        let t_exit = tf.x.min(tf.y.min(tf.z));
        // A listed cell whose disks all face away from the ray: none read, the budget spent
        // as if each had been (as the WGSL twin).
        let mut search = dist == 0;
        if search && !EITHER_SIDE && cone_faces_away(word, d) {
            let listed = geo.grid.cell_start[ci + 1] - geo.grid.cell_start[ci];
            if *budget < listed {
                *budget = 0;
                hit.aborted = 1;
                return hit;
            }
            *budget -= listed;
            search = false;
        }
        if search {
            let limit = t_exit + 1e-4 * cs;
            let (start, end) = (geo.grid.cell_start[ci], geo.grid.cell_start[ci + 1]);
            // The cell's nearest disk in (t, list position) order, searched again past one its
            // surface's clip passes over (as the WGSL twin, which reads the clip once a cell).
            let (mut floor_t, mut floor_e) = (0.0f32, NO_SPLAT);
            loop {
                let (mut best_t, mut best, mut best_e) = (hit.t, NO_SPLAT, 0);
                for e in start..end {
                    if *budget == 0 {
                        hit.aborted = 1;
                        return hit;
                    }
                    *budget -= 1;
                    let s = geo.grid.cell_splats[e as usize];
                    if s == skip {
                        continue;
                    }
                    let th = intersect_sided::<EITHER_SIDE>(&geo.splats[s as usize], o, d);
                    let past =
                        th > floor_t || (th == floor_t && floor_e != NO_SPLAT && e > floor_e);
                    if past && th < best_t && th <= limit {
                        (best_t, best, best_e) = (th, s, e);
                    }
                }
                if best == NO_SPLAT || geo.keeps(&geo.splats[best as usize], o + best_t * d) {
                    if best != NO_SPLAT {
                        hit.t = best_t;
                    }
                    hit.splat = best;
                    break;
                }
                (floor_t, floor_e) = (best_t, best_e);
            }
            if hit.splat != NO_SPLAT {
                return hit;
            }
        }
        if t_exit >= t_leave {
            return hit;
        }
        t = t.max(t_exit);
        let at = floor_cell((o + t * d - lo) * g.inv_cell_size);
        let mut n = select_i(at.clamp(c, c + k), at.clamp(c - k, c), negative & moving);
        n = select_i(n, c, !moving);
        let exit_x = tf.x <= tf.y && tf.x <= tf.z;
        let exit_y = !exit_x && tf.y <= tf.z;
        let exit_axis = BVec3::new(exit_x, exit_y, !exit_x && !exit_y);
        n = select_i(n, select_i(face - 1, face, positive & moving), exit_axis);
        if n.cmplt(IVec3::ZERO).any() || n.cmpge(dims).any() {
            return hit;
        }
        c = n;
    }
}
