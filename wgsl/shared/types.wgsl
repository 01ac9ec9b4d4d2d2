// Twins of the #[repr(C)] structs in src/types.rs; tests/layout.rs checks offsets and sizes.
// vec3 members are followed by a 4-byte scalar so that Rust's [f32; 3] lines up without padding.

struct Splat {
    center: vec3<f32>,
    radius: f32,
    normal: vec3<f32>,
    material: u32,
    diffuse: vec3<f32>,
    object: u32,
}

// Where a surface's disks end: world -> the surface's unit cube, rows of an affine map; a hit
// counts where all three land within 1 (src/types.rs). Zero rows clip nothing.
struct SurfaceClip {
    x: vec4<f32>,
    y: vec4<f32>,
    z: vec4<f32>,
}

fn clip_keeps(c: SurfaceClip, p: vec3<f32>) -> bool {
    let q = vec4<f32>(p, 1.0);
    return abs(dot(c.x, q)) <= 1.0 && abs(dot(c.y, q)) <= 1.0 && abs(dot(c.z, q)) <= 1.0;
}

// Whether row r of a clip keeps all of splat s's disk: r's extreme over the disk is its value
// at the centre plus the radius times r's gradient within the disk's plane.
fn clip_row_holds(r: vec4<f32>, s: Splat) -> bool {
    let a = r.xyz;
    let along = dot(a, s.normal);
    let reach = s.radius * sqrt(max(dot(a, a) - along * along, 0.0));
    return abs(dot(a, s.center) + r.w) + reach <= 1.0;
}

// Whether clip c keeps every point of splat s's disk (then no hit on it needs the test).
fn clip_holds_disk(c: SurfaceClip, s: Splat) -> bool {
    return clip_row_holds(c.x, s) && clip_row_holds(c.y, s) && clip_row_holds(c.z, s);
}

// The rows of clip c that cut splat s's disk, the first two of them, zero where fewer do (a
// zero row keeps everything): what a drawn disk needs tested per pixel. A disk of a box's face
// lies in the face's plane, whose row keeps it; the two others cut it at a corner.
fn clip_drawn_rows(c: SurfaceClip, s: Splat) -> array<vec4<f32>, 2> {
    let cuts = clip_cut_rows(c, s);
    var rows = array<vec4<f32>, 2>(vec4<f32>(0.0), vec4<f32>(0.0));
    var k = 0u;
    if (cuts & 1u) != 0u {
        rows[k] = c.x;
        k += 1u;
    }
    if (cuts & 2u) != 0u {
        rows[k] = c.y;
        k += 1u;
    }
    if (cuts & 4u) != 0u {
        rows[k] = c.z;
    }
    return rows;
}

// Which of clip c's rows clip_drawn_rows picks for splat s, as bits (x 1, y 2, z 4): those
// that cut its disk, the first two of them.
fn clip_cut_rows(c: SurfaceClip, s: Splat) -> u32 {
    let x = !clip_row_holds(c.x, s);
    let y = !clip_row_holds(c.y, s);
    let z = !clip_row_holds(c.z, s) && !(x && y);
    return select(0u, 1u, x) | select(0u, 2u, y) | select(0u, 4u, z);
}

// A splat's place in the level of detail's merge tree (src/types.rs).
struct SplatLod {
    extent: array<f32, 5>,
    top: u32,
    parent_extent: f32,
    parent_gap: f32,
}

// A run of splats a frame culls as one (SplatChunk in src/types.rs).
struct SplatChunk {
    center: vec3<f32>,
    centre_reach: f32,
    first: u32,
    ends: array<u32, 6>,
    level_fit: array<f32, 6>,
    parent_fit: array<f32, 6>,
    parent_gap: array<f32, 6>,
    _pad: array<u32, 3>,
}

struct Material {
    specular: vec3<f32>,
    roughness: f32,
}

const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_AREA: u32 = 2u;
const LIGHT_DIRECTIONAL: u32 = 3u;
const LIGHT_ENVIRONMENT: u32 = 4u;
const LIGHT_SUN: u32 = 5u;
// Light.flags: an area light whose front reflects as a surface does (light_flags::REFLECTS).
const LIGHT_REFLECTS: u32 = 1u;

// A distance beyond everything: a ray without end, a directional light's.
const FAR: f32 = 3.0e38;

struct Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    cos_outer: f32,
    power: vec3<f32>,
    cos_inner: f32,
    edge_u: vec3<f32>,
    area: f32,
    edge_v: vec3<f32>,
    flags: u32,
}

struct Photon {
    position: vec3<f32>,
    bounce: u32,
    direction: vec3<f32>,
    splat: u32,
    power: vec3<f32>,
    path: u32,
}

struct Emitter {
    light: Light,
    first: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
    photon_power: vec3<f32>,
    falloff_norm: f32,
}

struct TraceParams {
    seed: u32,
    path_offset: u32,
    path_count: u32,
    emitter_count: u32,
    max_depth: u32,
    min_bounce: u32,
    iteration_budget: u32,
    _pad0: u32,
}

struct PhotonViewParams {
    count: u32,
    width: u32,
    height: u32,
    scale: f32,
}

// Atomic twin of TraceCounters; `capacity` is written by the host only.
struct TraceCounters {
    stored: atomic<u32>,
    capacity: u32,
    overflow: atomic<u32>,
    escaped: atomic<u32>,
    absorbed: atomic<u32>,
    depth_capped: atomic<u32>,
    aborted: atomic<u32>,
    _pad: u32,
}

struct Ray {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    skip: u32,
}

struct Hit {
    t: f32,
    splat: u32,
    aborted: u32,
    _pad: u32,
}

const NO_SPLAT: u32 = 0xffffffffu;

struct DistanceParams {
    axis: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct Lobe {
    axis: vec3<f32>,
    sharpness: f32,
    irradiance: vec3<f32>,
    weight: f32,
}

struct SplatLight {
    irradiance: vec3<f32>,
    photons: u32,
    log_likelihood: f32,
    weight: f32,
    lobes: u32,
    first_lobe: u32,
}

struct BinnedPhoton {
    position: vec3<f32>,
    direction: u32,
}

struct BinParams {
    origin: vec3<f32>,
    cell_size: f32,
    dims: vec3<u32>,
    cell_count: u32,
    inv_cell_size: f32,
    photon_count: u32,
    rank_chunk: u32,
    sub: u32,
}

struct EmParams {
    lobes: u32,
    iterations: u32,
    family: u32,
    flags: u32,
    radius: f32,
    radius2: f32,
    slab: f32,
    inv_area: f32,
    splat_count: u32,
    active_count: u32,
    iteration_begin: u32,
    iteration_end: u32,
    workgroup_size: u32,
    prune: u32,
    fit_candidates: u32,
    gathered: u32,
    list_first: u32,
    smooth_radii: f32,
    _pad1: u32,
    _pad2: u32,
}

struct DepositParams {
    power_scale: f32,
    photon_count: u32,
    splat_count: u32,
    reach: f32,
    first_splat: u32,
    spread_max: f32,
    _pad1: u32,
    _pad2: u32,
}

struct Camera {
    eye: vec3<f32>,
    near: f32,
    forward: vec3<f32>,
    depth_tolerance: f32,
    right: vec3<f32>,
    tan_x: f32,
    up: vec3<f32>,
    tan_y: f32,
    size: vec2<f32>,
    jitter: vec2<f32>,
    lod: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

struct PresentParams {
    image_width: u32,
    image_height: u32,
    target_width: u32,
    target_height: u32,
    decode: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct TemporalParams {
    width: u32,
    height: u32,
    reset: u32,
    max_frames: u32,
    depth_tolerance: f32,
    normal_cos: f32,
    _pad0: u32,
    _pad1: u32,
}

struct ShadeParams {
    lobes_per_splat: u32,
    family: u32,
    light_count: u32,
    area_samples: u32,
    shadow_bias: f32,
    seed: u32,
    show: u32,
    direct: u32,
    area_first: u32,
    area_count: u32,
    sample: u32,
    glossy_rays: u32,
    // What the camera sees where its ray meets nothing: w = 1 the colour xyz, w = 0 the sky.
    background: vec4<f32>,
}

const DIRECT_RAYS: u32 = 0u;
const DIRECT_BAKED: u32 = 1u;

struct TileParams {
    tiles_x: u32,
    tiles_y: u32,
    splat_count: u32,
    entry_count: u32,
}

struct PathParams {
    width: u32,
    height: u32,
    sample: u32,
    seed: u32,
    max_depth: u32,
    light_count: u32,
    show: u32,
    shadow_bias: f32,
    background: vec4<f32>,
}

struct GatherParams {
    splat_count: u32,
    samples: u32,
    seed: u32,
    shadow_bias: f32,
    first: u32,
    light_count: u32,
    group_starts: u32,
    group_members: u32,
}

struct DirectParams {
    splat_count: u32,
    light_count: u32,
    samples: u32,
    seed: u32,
    shadow_bias: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct GridParams {
    origin: vec3<f32>,
    cell_size: f32,
    dims: vec3<u32>,
    cell_count: u32,
    inv_cell_size: f32,
    splat_count: u32,
    entry_count: u32,
    _pad0: u32,
}

struct ScanParams {
    len: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct ToneParams {
    count: u32,
    level: u32,
    mode: u32,
    _pad0: u32,
    key: f32,
    exposure: f32,
    luminance_scale: f32,
    epsilon: f32,
}
