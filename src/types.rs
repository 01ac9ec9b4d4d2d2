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
    pub _pad: u32,
}

/// Isotropic Ward material (DESIGN.md §3): the specular part; the diffuse albedo lives per splat.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    pub specular: [f32; 3],
    pub roughness: f32,
}

/// Light kinds, the values of `Light::kind`.
pub mod light_kind {
    pub const POINT: u32 = 0;
    pub const SPOT: u32 = 1;
    pub const AREA: u32 = 2;
    pub const DIRECTIONAL: u32 = 3;
}

/// One light. Which fields matter depends on `kind`:
/// point: position, power; spot: also direction and the cosines of the cone;
/// area: position is a corner, `edge_u`/`edge_v` span the rectangle (`edge_u × edge_v` points
/// along `direction`, its normal), `area` its area;
/// directional: direction (the way light travels); photons start on a disk of area `area`
/// centred at `position`, perpendicular to the direction, that covers the scene's bounds.
/// `power` is total emitted RGB power (W) for every kind; emission sampling shares photons by it.
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
    pub _pad: u32,
}

/// A stored photon: where it landed, the direction it came from (pointing away from the
/// surface), its RGB power and the number of bounces before it was stored.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    pub position: [f32; 3],
    pub bounce: u32,
    pub direction: [f32; 3],
    pub splat: u32,
    pub power: [f32; 3],
    pub _pad: u32,
}

/// One Gaussian lobe of a splat's incident light: unit axis, angular width, and the RGB
/// irradiance it carries.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Lobe {
    pub axis: [f32; 3],
    pub width: f32,
    pub irradiance: [f32; 3],
    pub weight: f32,
}

/// Per-frame camera uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Camera {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub fov_y: f32,
    pub resolution: [u32; 2],
    pub _pad: [u32; 2],
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

/// Growable-buffer counters: a slot counter and an overflow flag the host reads back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Counters {
    pub count: u32,
    pub capacity: u32,
    pub overflow: u32,
    pub _pad: u32,
}
