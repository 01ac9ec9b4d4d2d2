//! GPU-visible structs. Each one is `#[repr(C)]` + `Pod` with explicit padding and has a twin of
//! the same name in `wgsl/shared/types.wgsl`; `tests/layout.rs` checks that naga lays the twin out
//! with the same member offsets and size.

use bytemuck::{Pod, Zeroable};

/// An oriented disk. `diffuse` is the splat's own diffuse albedo (the material's, or a model's
/// vertex colour), so that per-vertex colours cost no indirection at shading time.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Splat {
    pub center: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub material: u32,
    pub diffuse: [f32; 3],
    /// The scene surface it belongs to, an index into `Scene::surfaces`: what an object-ID
    /// image names, so that errors can be measured per object.
    pub object: u32,
}

/// Where a surface's disks end (docs/design.md §4): a hit on one of its disks counts only where
/// the affine map `rows` (world → the surface's unit cube, grown by a slack) takes the hit
/// point within [−1, 1]³. A box's disks overhang its faces' edges by up to a third of the
/// spacing; one-sided, the overhang stops light falling past a convex edge that a ray leaving
/// the face below passes (from the overhang's back), so light would not be reciprocal there.
/// Clipped, both see the box. All-zero rows (a model, a sphere, a scan) clip nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SurfaceClip {
    pub x: [f32; 4],
    pub y: [f32; 4],
    pub z: [f32; 4],
}

impl SurfaceClip {
    /// The clip of the volume `m` maps the cube [−1, 1]³ onto, grown by `slack` (world units)
    /// on every side, so that the faces' disks meet at an edge without a crack; none where `m`
    /// has no finite inverse (a flat or degenerate transform clips nothing, not everything).
    pub fn of_cube(m: &glam::Affine3A, slack: f32) -> SurfaceClip {
        let inv = m.inverse();
        let c = inv.matrix3;
        let t = inv.translation;
        // Row r reads 1 at a distance 1 / |r.xyz| from the centre plane: scaled by
        // 1 / (1 + slack |r.xyz|), it reads 1 that much farther out.
        let row = |a: glam::Vec3, w: f32| {
            let k = 1.0 / (1.0 + slack * a.length());
            [a.x * k, a.y * k, a.z * k, w * k]
        };
        let rows = [
            row(glam::Vec3::new(c.x_axis.x, c.y_axis.x, c.z_axis.x), t.x),
            row(glam::Vec3::new(c.x_axis.y, c.y_axis.y, c.z_axis.y), t.y),
            row(glam::Vec3::new(c.x_axis.z, c.y_axis.z, c.z_axis.z), t.z),
        ];
        if m.matrix3.determinant().abs() > 0.0 && rows.iter().flatten().all(|v| v.is_finite()) {
            SurfaceClip {
                x: rows[0],
                y: rows[1],
                z: rows[2],
            }
        } else {
            SurfaceClip::default()
        }
    }

    /// The same clip for a scene mapped by `m` (a point p is now m(p)): the rows composed with
    /// m's inverse. Zero rows stay zero.
    pub fn mapped(&self, m: &glam::Affine3A) -> SurfaceClip {
        let inv = glam::Mat4::from(m.inverse());
        let row = |r: [f32; 4]| (inv.transpose() * glam::Vec4::from(r)).to_array();
        SurfaceClip {
            x: row(self.x),
            y: row(self.y),
            z: row(self.z),
        }
    }

    /// Whether the clip keeps every point of splat `s`'s disk (then no hit on it needs the
    /// test): each row's extreme over the disk is its value at the centre plus the radius
    /// times the row's gradient within the disk's plane.
    pub fn holds_disk(&self, s: &Splat) -> bool {
        [self.x, self.y, self.z].iter().all(|r| row_holds(r, s))
    }

    /// The rows that cut splat `s`'s disk, the first two of them, zero where fewer do (a zero
    /// row keeps everything): what a drawn disk is tested against per pixel. A disk of a box's
    /// face lies in the face's plane, whose row keeps it; the two others cut it at a corner.
    pub fn drawn_rows(&self, s: &Splat) -> [[f32; 4]; 2] {
        let mut rows = [[0.0; 4]; 2];
        let cutting = [self.x, self.y, self.z]
            .into_iter()
            .filter(|r| !row_holds(r, s));
        for (slot, r) in rows.iter_mut().zip(cutting) {
            *slot = r;
        }
        rows
    }

    /// Whether a hit at `p` counts (NaN does not).
    pub fn keeps(&self, p: glam::Vec3) -> bool {
        let p = p.extend(1.0);
        [self.x, self.y, self.z]
            .iter()
            .all(|r| glam::Vec4::from(*r).dot(p).abs() <= 1.0)
    }
}

/// Whether clip row `r` keeps all of splat `s`'s disk (`SurfaceClip::holds_disk`).
fn row_holds(r: &[f32; 4], s: &Splat) -> bool {
    let (c, n) = (glam::Vec3::from(s.center), glam::Vec3::from(s.normal));
    let a = glam::Vec3::new(r[0], r[1], r[2]);
    let along = a.dot(n);
    let reach = s.radius * (a.dot(a) - along * along).max(0.0).sqrt();
    (a.dot(c) + r[3]).abs() + reach <= 1.0
}

/// A splat's place in the level of detail's merge tree (`lod`, docs/design.md §8). Level L's
/// splats are a subset of level L − 1's; each splat of level L − 1 is merged into one of them,
/// whose disk at level L is grown to cover every splat merged into it, at every level below.
/// A frame draws each splat at the coarsest of its levels whose disk projects within the level
/// of detail (`Camera::lod`), unless its parent's disk does too (`shared::splat::lod_radius`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SplatLod {
    /// The radius of the splat's disk at levels 1 to 5 (up to `top`).
    pub extent: [f32; 5],
    /// The highest level the splat belongs to (0 to `LOD_MAX_LEVEL`).
    pub top: u32,
    /// The radius of its parent's disk at level `top + 1` (the splat its top level merges
    /// into), and the distance between their centres; 0 when `top` is the tree's last level.
    pub parent_extent: f32,
    pub parent_gap: f32,
}

/// The normals of the splats merged into a splat's disk, per level 1 to 5 of the merge tree,
/// as a glossy disk is shaded there (`shared::splat::lod_roughness`, `lod_normal`): a word a
/// level, its lowest byte how far they spread as Ward roughness beyond the splat's own
/// (`lod::normal_spread`, in units of `1 / LOD_SPREAD_SCALE`), its upper 24 bits their mean
/// direction (the octahedral code's two snorm16 cut to 12 bits each). Apart from `SplatLod`:
/// only the shading of glossy disks reads it.
pub type LodSpread = [u32; 5];

/// Levels of the merge tree, the splats' own included (0 to `LOD_MAX_LEVEL`).
pub const LOD_LEVELS: usize = 6;

/// A run of up to `lod::CHUNK` splats near one another, which a frame culls as one
/// (`shared::splat::chunk_visits`, docs/design.md §8): its entries of `LodTree::order`, sorted
/// by their top level, and per level the bounds over its splats of that top level which tell,
/// from its nearest depth alone, that the level of detail draws none of them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SplatChunk {
    /// A centre of the chunk, and the farthest of its splats' centres from it.
    pub center: [f32; 3],
    pub centre_reach: f32,
    /// Its first entry in the order.
    pub first: u32,
    /// Where the entries of splats whose top level is t end (from `first`): level t's entries
    /// are `ends[t - 1]..ends[t]`, with 0 before level 0.
    pub ends: [u32; LOD_LEVELS],
    /// Over level t's splats: their largest disk at level t (their own radius at 0), the
    /// largest they are drawn with.
    pub level_fit: [f32; LOD_LEVELS],
    /// Their largest parent's disk (`SplatLod::parent_extent`); below 0 where one has no
    /// parent (a root, always drawn where its disk fits).
    pub parent_fit: [f32; LOD_LEVELS],
    /// Their largest distance to their parent.
    pub parent_gap: [f32; LOD_LEVELS],
    pub _pad: [u32; 3],
}

impl SplatChunk {
    /// The entries (from `first`) of its splats whose top level is `t`; for a node, the count
    /// of its subtree's splats before and through that level.
    pub fn level(&self, t: usize) -> std::ops::Range<u32> {
        let start = if t == 0 { 0 } else { self.ends[t - 1] };
        start..self.ends[t]
    }
}

/// Isotropic Ward material (docs/design.md §3): the specular part; the diffuse albedo lives per splat.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    pub specular: [f32; 3],
    pub roughness: f32,
}

impl Material {
    /// Whether it reflects glossily (some specular part): its splats need lobes.
    pub fn is_glossy(&self) -> bool {
        self.specular.iter().any(|&s| s > 0.0)
    }
}

/// Light kinds, the values of `Light::kind`.
pub mod light_kind {
    pub const POINT: u32 = 0;
    pub const SPOT: u32 = 1;
    pub const AREA: u32 = 2;
    pub const DIRECTIONAL: u32 = 3;
    pub const ENVIRONMENT: u32 = 4;
    pub const SUN: u32 = 5;
}

/// Whether a light of `kind` is sampled on a grid of strata (`n × n` points of an area light,
/// directions of an environment light or of the sun's disk) rather than at one point.
pub fn stratified(kind: u32) -> bool {
    matches!(
        kind,
        light_kind::AREA | light_kind::ENVIRONMENT | light_kind::SUN
    )
}

/// Bits of `Light::flags`.
pub mod light_flags {
    /// An area light whose front reflects as a surface does (it carries a material): rays and
    /// photons that meet it go on to the splats of its surface, just behind its emitting face.
    pub const REFLECTS: u32 = 1;
}

/// One light. Which fields matter depends on `kind`:
/// point: position, power; spot: also direction and the cosines of the cone;
/// area: position is a corner, `edge_u`/`edge_v` span the rectangle (`edge_u × edge_v` points
/// along `direction`, its normal), `area` its area;
/// directional: direction (the way light travels); photons start on a disk of area `area`
/// centred at `position`, perpendicular to the direction, that covers the scene's bounds;
/// environment: the radiance of the scene's sky (`scene::sky::SkyTable`) from every direction,
/// in the frame of `edge_u` (the map's x), `direction` (its y, up) and `edge_v` (its z);
/// photons start on a disk of area `area` perpendicular to their direction, two of its radii
/// out from `position`, the centre of the scene's bounds;
/// sun: a directional light from a disk of the sky, the cone of cosine `cos_outer` about
/// −`direction` (its angular radius), `cos_inner` holding `1 − cos_outer` exactly (f32 cannot
/// get it back from a cosine that near 1); photons as a directional light's, their directions
/// spread over the cone.
/// `power` is total emitted RGB power (W) for every kind; emission sampling shares photons by it.
/// `flags`: `light_flags`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub cos_outer: f32,
    pub power: [f32; 3],
    pub cos_inner: f32,
    pub edge_u: [f32; 3],
    pub area: f32,
    pub edge_v: [f32; 3],
    pub flags: u32,
}

/// A stored photon: where it landed (on splat `splat`), the direction it came from (pointing
/// away from the surface), its RGB power, the number of bounces before it was stored, and the
/// index of the emitted photon (`path`) whose path it belongs to.
/// `(path, bounce)` is unique and independent of scheduling: it is the photons' sort key, since
/// their slots come from an atomic counter.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    pub position: [f32; 3],
    pub bounce: u32,
    pub direction: [f32; 3],
    pub splat: u32,
    pub power: [f32; 3],
    pub path: u32,
}

impl Photon {
    /// The scheduling-independent order of stored photons.
    pub fn key(&self) -> (u32, u32) {
        (self.path, self.bounce)
    }
}

/// A light prepared for photon emission: the light, the range of emitted-photon indices
/// (paths) it owns, and the power each of its photons carries, computed once on the host so
/// the GPU and the CPU mirror read the same bits.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Emitter {
    pub light: Light,
    pub first: u32,
    pub count: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    /// `light.power / count`.
    pub photon_power: [f32; 3],
    /// Spot lights: 1 / (mean of the smooth cone falloff over the sampled cone), so that
    /// weighting each photon by its falloff keeps the total power. 1 for other kinds.
    pub falloff_norm: f32,
}

/// Uniform of one `photon_trace` dispatch (one batch of emitted photons).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceParams {
    pub seed: u32,
    /// First emitted-photon index (path) of this batch, and the batch's size.
    pub path_offset: u32,
    pub path_count: u32,
    pub emitter_count: u32,
    /// Most hits a path may have.
    pub max_depth: u32,
    /// Photons are stored at hits whose bounce count is at least this (1: indirect only).
    pub min_bounce: u32,
    /// Loop iterations (cells plus disk tests) one path may spend before it is aborted and
    /// counted; keeps every invocation far below llvmpipe's silent loop limit.
    pub iteration_budget: u32,
    pub _pad0: u32,
}

/// Uniform of `photon_view` and `photon_resolve`: the stored photons splatted into the pixels
/// the camera sees them in, as fixed-point sums (integer atomics keep the image
/// deterministic).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonViewParams {
    /// Photons in this dispatch (one page), or pixels for `photon_resolve`.
    pub count: u32,
    /// Image width and height in pixels.
    pub width: u32,
    pub height: u32,
    /// Fixed-point units per unit of power (`photon_view::fixed_scale`).
    pub scale: f32,
}

/// Counters of the photon store and of how paths ended, read back after each batch.
/// `stored` counts every store attempt, also those past `capacity` (which set `overflow` and
/// write nothing): after an overflow it is exactly the capacity the batch needs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct TraceCounters {
    pub stored: u32,
    pub capacity: u32,
    pub overflow: u32,
    /// Paths that left the grid.
    pub escaped: u32,
    /// Paths ended by Russian roulette (or by a specular bounce below the surface).
    pub absorbed: u32,
    /// Paths that reached `max_depth` hits.
    pub depth_capped: u32,
    /// Paths aborted because they used up `iteration_budget`.
    pub aborted: u32,
    pub _pad: u32,
}

/// A ray for `trace_rays`: the nearest front-facing disk hit with `0 < t < t_max`, ignoring
/// splat `skip` (the one the ray leaves; `NO_SPLAT` for none).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub t_max: f32,
    pub direction: [f32; 3],
    pub skip: u32,
}

/// Result of tracing one ray: `splat` is `NO_SPLAT` on a miss; `aborted` is 1 when the
/// iteration budget ran out before the answer was known.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Hit {
    pub t: f32,
    pub splat: u32,
    pub aborted: u32,
    pub _pad: u32,
}

/// `Hit::splat` and `Ray::skip` when there is no splat.
pub const NO_SPLAT: u32 = u32::MAX;

/// Uniform of one pass of the grid's distance field (`grid_distance`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DistanceParams {
    /// 0, 1, 2: the axis this pass sweeps (x reads occupancy from the cell lists).
    pub axis: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// One lobe of a splat's incident light (docs/design.md §6): unit `axis`, `sharpness` in the
/// family's own exponent (vMF: κ in `exp(κ(ω·μ − 1))`; Ward-like: 1/β² in `exp(−tan²δ/β²)`),
/// the RGB irradiance it carries and its mixture weight λ.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Lobe {
    pub axis: [f32; 3],
    pub sharpness: f32,
    pub irradiance: [f32; 3],
    pub weight: f32,
}

/// What the lobe fit keeps per splat besides its lobes: total RGB irradiance of the gathered
/// photons, how many were gathered, and the fit's weighted log-likelihood with the photons'
/// summed weight (so `-log_likelihood / weight` is the negative log-likelihood per unit of
/// photon weight, the fit error).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SplatLight {
    pub irradiance: [f32; 3],
    pub photons: u32,
    pub log_likelihood: f32,
    pub weight: f32,
    /// Lobes written for this splat (0: no photons, or a splat that needs no lobes).
    pub lobes: u32,
    /// Where they start in the packed lobe buffer (`LobeMap::pack`): only splats with lobes
    /// take room there.
    pub first_lobe: u32,
}

/// A binned photon's geometry: position and the octahedral-encoded incident direction
/// (two snorm16, see `wgsl/shared/octahedral.wgsl`). Its power lives in a parallel
/// `vec4` array (RGB, then the surface it landed on, `surface_encode` of its splat's normal;
/// its EM weight is `mean(RGB)`), so each array is 16 bytes a photon.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BinnedPhoton {
    pub position: [f32; 3],
    pub direction: u32,
}

/// The photon binning grid (cells at least the search radius, x-fastest like `GridParams`)
/// and the extent of one binning dispatch.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BinParams {
    pub origin: [f32; 3],
    pub cell_size: f32,
    pub dims: [u32; 3],
    pub cell_count: u32,
    /// `1 / cell_size`, computed once on the host so GPU and CPU round cell indices alike.
    pub inv_cell_size: f32,
    /// Photons this dispatch covers: one page for `bin_count`/`bin_scatter`, all binned
    /// photons for `bin_rank`/`bin_place`.
    pub photon_count: u32,
    /// `bin_rank`: the chunk of every cell list this dispatch compares against.
    pub rank_chunk: u32,
    /// Sub-cells per cell along an axis (1 to 4): each cell's photons are listed by
    /// sub-cell, so that ranking a list (quadratic in its length) stays cheap when cells hold
    /// many photons; a cell's sub-cell lists are contiguous, so a cell is still one run.
    pub sub: u32,
}

/// Uniform of the lobe fit (`fit_select`, `em_fit`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct EmParams {
    /// Lobes per splat K (1..=8) and EM iterations.
    pub lobes: u32,
    pub iterations: u32,
    /// `em::family::VMF` or `em::family::WARD`.
    pub family: u32,
    /// `em::flags::*`.
    pub flags: u32,
    /// Search radius R, R², and half the thickness of the slab around a splat's plane.
    pub radius: f32,
    pub radius2: f32,
    pub slab: f32,
    /// 1 / (π R²): photon power to irradiance.
    pub inv_area: f32,
    pub splat_count: u32,
    /// Entries of the active-splat list (`em_fit`'s workgroup count).
    pub active_count: u32,
    /// The EM iterations `[iteration_begin, iteration_end)` of this `em_fit` dispatch: a
    /// dispatch that does not start at 0 resumes from the mixture the previous one left in
    /// the lobe buffer; the one that ends at `iterations` also runs the final pass.
    pub iteration_begin: u32,
    pub iteration_end: u32,
    /// Invocations per `em_fit` workgroup (the shader's `WG`, fixed with its pipeline).
    pub workgroup_size: u32,
    /// Most lobes a splat may drop during its fit (0: every fitted splat keeps `lobes`); see
    /// `em_fit.wgsl`, "Pruning".
    pub prune: u32,
    /// Most candidate photons a fitted splat's EM visits; past it an even subset, reweighted
    /// (0: all); see `em_fit.wgsl`, "Bounded cost".
    pub fit_candidates: u32,
    /// Rays a splat of final gathering's samples, the candidates of this dispatch's fitted
    /// splats (0: the binned photons); see `em_fit.wgsl`, "Gathered samples".
    pub gathered: u32,
    /// The fit-list entry of this dispatch's first workgroup (batches of gathered samples:
    /// the samples of entry `list_first + k` begin at k · gathered).
    pub list_first: u32,
    /// `estimate_smooth`'s widest kernel, in search radii (its other is half as wide).
    pub smooth_radii: f32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The uniform of the deposit passes (`deposit_add`, `deposit_list`, `deposit_share`; design
/// §6, "Deposits").
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DepositParams {
    /// Fixed-point units of one unit of photon power in a deposit's sums.
    pub power_scale: f32,
    /// Photons of this `deposit_add` dispatch (one store page).
    pub photon_count: u32,
    /// The splats whose deposits this dispatch's deposit buffer holds, from `first_splat`
    /// (deposits larger than one storage binding are split by splat ranges).
    pub splat_count: u32,
    /// How far from a splat's centre a deposit's mean may lie and still reach its gather
    /// disk: R plus the most a deposit's disk reaches past its mean (`deposit_share`'s box).
    pub reach: f32,
    pub first_splat: u32,
    /// The widest a deposit's disk is taken to be (`deposit_list` clamps its spread to it):
    /// the reach past R, sized by nearly every splat's radius, not by the largest one's.
    pub spread_max: f32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Per-frame camera uniform of the splat passes: a pinhole at `eye` looking along `forward`,
/// with `right`/`up` unit vectors and the tangents of the half fields of view. A pixel's ray
/// and the depth mapping are `wgsl/shared/splat.wgsl`'s `pixel_ray` and `view_depth`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Camera {
    pub eye: [f32; 3],
    /// The near plane (view-space z). Depth is reversed, `near / z`: 1 at the near plane,
    /// towards 0 at infinity, with the same relative precision at every distance.
    pub near: f32,
    pub forward: [f32; 3],
    /// How far behind the visible surface (in radii of the splat that made it, along view z)
    /// a splat still blends into the pixel.
    pub depth_tolerance: f32,
    pub right: [f32; 3],
    pub tan_x: f32,
    pub up: [f32; 3],
    pub tan_y: f32,
    /// Image width and height in pixels.
    pub size: [f32; 2],
    /// Sub-pixel offset of every view ray (pixels, within ±0.5): successive jittered frames
    /// average into an anti-aliased image (`frame::jitter`).
    pub jitter: [f32; 2],
    /// Level of detail (`shared::splat::lod_radius`), in pixels: neighbouring splats are drawn
    /// merged into one disk (`SplatLod`) wherever that disk projects at most this many pixels
    /// in radius; 0 draws every splat as it is (refinement frames, shadow rays, the compute
    /// splatter).
    pub lod: f32,
    pub _pad0: f32,
    pub _pad1: f32,
    pub _pad2: f32,
}

/// Uniform of the shading passes (`splat_attributes`, `shade`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadeParams {
    /// Lobe slots per splat in the lobe buffer, and their family (`em::family`).
    pub lobes_per_splat: u32,
    pub family: u32,
    pub light_count: u32,
    /// Area lights are sampled on an `area_samples`² stratified grid per pixel.
    pub area_samples: u32,
    /// Shadow rays start this far off the surface, along its normal (scene units).
    pub shadow_bias: f32,
    pub seed: u32,
    /// Which light terms the frame shows (`shared::splat::SHOW_*` bits).
    pub show: u32,
    /// Where direct light comes from: `DIRECT_RAYS` (shadow rays per pixel, in `shade`) or
    /// `DIRECT_BAKED` (each splat's baked visibility, in `splat_attributes`).
    pub direct: u32,
    /// The area-light strata this frame traces, `area_first..area_first + area_count` (mod
    /// `area_samples`²): all of them in one frame, or spread over refinement frames.
    pub area_first: u32,
    pub area_count: u32,
    /// The refinement sample this frame is: 0 writes the HDR image, k > 0 adds to the running
    /// mean of the k frames before it.
    pub sample: u32,
    /// Rays a pixel and frame that trace the glossy surfaces' indirect light (`shade.wgsl`,
    /// "Glossy rays"); the lobes then give only the diffuse part (0: the lobes give both).
    pub glossy_rays: u32,
    /// What the camera sees where its ray meets nothing: with w = 1 the colour xyz, with
    /// w = 0 the sky and the sun's disk (black without them; `Background::uniform`).
    pub background: [f32; 4],
}

/// `ShadeParams::direct`: shadow rays per pixel.
pub const DIRECT_RAYS: u32 = 0;
/// `ShadeParams::direct`: the bake's per-splat visibility (`direct_bake`).
pub const DIRECT_BAKED: u32 = 1;

/// Uniform of `present`, the window's last pass: the tone-mapped image of `image_width ×
/// image_height` drawn onto a target of `target_width × target_height`, bilinearly where the
/// two differ (moving frames drawn at a lower internal resolution).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PresentParams {
    pub image_width: u32,
    pub image_height: u32,
    pub target_width: u32,
    pub target_height: u32,
    /// 1: the target's format is sRGB, so the bytes are decoded to linear (the hardware
    /// encodes them again on write).
    pub decode: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl PresentParams {
    /// An image of `image` pixels (width, height) drawn onto a target of `target` pixels,
    /// decoded to linear where `decode`.
    pub fn new(image: (u32, u32), target: (u32, u32), decode: bool) -> PresentParams {
        PresentParams {
            image_width: image.0,
            image_height: image.1,
            target_width: target.0,
            target_height: target.1,
            decode: decode as u32,
            ..Default::default()
        }
    }
}

/// Uniform of `temporal`, the moving frames' anti-aliasing: this frame's jittered samples
/// blended into the last resolved image, reprojected by depth and camera motion.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TemporalParams {
    pub width: u32,
    pub height: u32,
    /// 1: no history (the first moving frame, or after a change of scene, light or view
    /// mode): the frame is its own resolved image.
    pub reset: u32,
    /// The most frames the history's running mean counts: the current frame weighs at least
    /// 1 / `max_frames`.
    pub max_frames: u32,
    /// History is kept where its distance from the previous eye is within this share of the
    /// distance the reprojected surface should have.
    pub depth_tolerance: f32,
    /// ... and where its normal is within this cosine of the surface's.
    pub normal_cos: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// Uniform of the compute splatter's stages (`splat_tile_count`, `splat_tile_scatter`,
/// `splat_compute`): the image in `TILE`² pixel tiles, tiles numbered x-fastest.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TileParams {
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub splat_count: u32,
    /// (tile, splat) entries, known once the counts are scanned.
    pub entry_count: u32,
}

/// Uniform of `path_trace`: one sample per pixel of a progressive path-traced image.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathParams {
    pub width: u32,
    pub height: u32,
    /// This sample's place in the running mean (0 writes the image).
    pub sample: u32,
    pub seed: u32,
    /// Surface vertices a path may have (the bake's `max_depth`).
    pub max_depth: u32,
    pub light_count: u32,
    /// Which light terms to show (`shared::splat::SHOW_*` bits, split as path_trace.wgsl says).
    pub show: u32,
    /// How far next events' shadow rays start off the surface, along the hit disk's normal:
    /// the renderer's `direct::shadow_bias`, so that both render one scene (design §10).
    pub shadow_bias: f32,
    /// What a camera ray that meets nothing sees (`ShadeParams::background`).
    pub background: [f32; 4],
}

/// Uniform of `final_gather`: rays from each fitted splat of the fit list over its hemisphere,
/// and the light each brings back from the surface it meets.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherParams {
    /// How many entries of the fit list this batch takes, from `first`.
    pub splat_count: u32,
    /// Rays a splat: a `samples` × `samples` stratified grid over its cosine-weighted hemisphere.
    pub samples: u32,
    pub seed: u32,
    /// How far off the splat's plane the rays start (`direct::shadow_bias`).
    pub shadow_bias: f32,
    /// The batch's first fit-list entry: sample j of entry `first + k` is at k · samples² + j.
    pub first: u32,
    /// Lights bound: a ray that meets an area light before a surface brings none back.
    pub light_count: u32,
    /// Where the shared fits' group starts and members lie in the groups' words
    /// (`fit_groups::FitGroups`); `group_members` 0: no groups, each splat casts its own rays.
    pub group_starts: u32,
    pub group_members: u32,
}

/// Uniform of `direct_bake`: every splat's direct light from every light, shadowed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DirectParams {
    pub splat_count: u32,
    pub light_count: u32,
    /// Area lights are sampled on a `samples`² jittered grid per splat.
    pub samples: u32,
    pub seed: u32,
    /// Shadow rays start this far off the splat, along its normal.
    pub shadow_bias: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The uniform grid over the splats: `cell = floor((p - origin) / cell_size)`, cells numbered
/// x-fastest. Shared by grid build, photon tracing and shadow rays.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridParams {
    pub origin: [f32; 3],
    pub cell_size: f32,
    pub dims: [u32; 3],
    pub cell_count: u32,
    /// `1 / cell_size`, computed once on the host so GPU and CPU round cell indices alike.
    pub inv_cell_size: f32,
    pub splat_count: u32,
    /// Number of (cell, splat) entries; known once the counts are scanned.
    pub entry_count: u32,
    pub _pad0: u32,
}

/// Parameters of one level of the multi-level exclusive scan.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ScanParams {
    /// Number of elements in this level.
    pub len: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Tone mapping (docs/design.md §9): one level of the log-average reduction, and the operator.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ToneParams {
    /// Values at this level of the reduction (pixels at level 0); pixels for `tonemap_apply`.
    pub count: u32,
    /// 0: the reduction reads HDR pixels; above: the previous level's partial sums.
    pub level: u32,
    /// `TONE_REINHARD` or `TONE_LINEAR` (`wgsl/shared/tone.wgsl`).
    pub mode: u32,
    pub _pad0: u32,
    /// The key `a` that the log-average luminance maps to.
    pub key: f32,
    /// A multiplier after the operator: 2^EV.
    pub exposure: f32,
    /// cd/m² per unit of radiance, for the scotopic blend.
    pub luminance_scale: f32,
    /// ε of log(ε + Y).
    pub epsilon: f32,
}
