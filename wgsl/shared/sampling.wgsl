// Frames and direction sampling shared by emission and bounces; twin: src/shared/sampling.rs.

const PI: f32 = 3.14159265358979;

// Orthonormal tangents (t, b) with t x b = n for a unit n (Duff et al. 2017, branch-free).
struct Frame {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
}

fn frame_of(n: vec3<f32>) -> Frame {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    var f: Frame;
    f.t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    f.b = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

fn to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return f.t * v.x + f.b * v.y + f.n * v.z;
}

// Direction at polar cosine `c` and azimuth 2*pi*u about +z.
fn polar(c: f32, u: f32) -> vec3<f32> {
    let s = sqrt(max(0.0, 1.0 - c * c));
    let phi = 2.0 * PI * u;
    return vec3<f32>(s * cos(phi), s * sin(phi), c);
}

// Cosine-weighted hemisphere about +z (pdf cos(theta) / pi).
fn sample_cosine(u1: f32, u2: f32) -> vec3<f32> {
    return polar(sqrt(1.0 - u1), u2);
}

fn sample_sphere(u1: f32, u2: f32) -> vec3<f32> {
    return polar(1.0 - 2.0 * u1, u2);
}

// Uniform in the cone cos(theta) >= cos_max about +z.
fn sample_cone(u1: f32, u2: f32, cos_max: f32) -> vec3<f32> {
    return polar(1.0 - u1 * (1.0 - cos_max), u2);
}

// Uniform in the unit disk, in the plane z = 0.
fn sample_disk(u1: f32, u2: f32) -> vec2<f32> {
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    return vec2<f32>(r * cos(phi), r * sin(phi));
}

// The power heuristic's weight of a strategy of pdf a against one of pdf b (each pdf times its
// sample count).
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    return select(0.0, a2 / (a2 + b * b), a2 > 0.0);
}
