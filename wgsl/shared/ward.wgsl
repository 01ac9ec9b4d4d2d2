// Isotropic Ward BRDF, Duer normalisation (DESIGN.md section 3), and its importance sampling
// (Ward 1992, pdf from Walter 2005). Twin: src/shared/ward.rs.
// Directions point away from the surface; wi is where light comes from.

// #import sampling

// Specular part without rho_s: exp(-tan^2(th)/a^2) / (4 pi a^2 cos_i cos_o).
fn ward_specular(n: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>, alpha: f32) -> f32 {
    let ci = dot(n, wi);
    let co = dot(n, wo);
    if ci <= 0.0 || co <= 0.0 {
        return 0.0;
    }
    let h = normalize(wi + wo);
    let ch = dot(n, h);
    let a2 = alpha * alpha;
    let tan2 = max(0.0, 1.0 - ch * ch) / (ch * ch);
    return exp(-tan2 / a2) / (4.0 * PI * a2 * ci * co);
}

// Half-vector in the local frame (z = normal): tan^2(th) = -a^2 ln(1 - u1), phi = 2 pi u2.
fn ward_half_vector(u1: f32, u2: f32, alpha: f32) -> vec3<f32> {
    let tan2 = -alpha * alpha * log(1.0 - u1);
    return polar(inverseSqrt(1.0 + tan2), u2);
}

// Walter's pdf of wo = reflect(wi, h): exp(-tan^2/a^2) / (4 pi a^2 (h.wi) cos^3(th)).
fn ward_pdf(n: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>, alpha: f32) -> f32 {
    let h = normalize(wi + wo);
    let ch = dot(n, h);
    let hi = dot(h, wi);
    if ch <= 0.0 || hi <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let tan2 = max(0.0, 1.0 - ch * ch) / (ch * ch);
    return exp(-tan2 / a2) / (4.0 * PI * a2 * hi * ch * ch * ch);
}

struct WardSample {
    wo: vec3<f32>,
    // f_s cos_o / pdf without rho_s: (h.wi) cos^3(th) / cos_i. 0 when wo is below the surface.
    weight: f32,
}

fn ward_sample(f: Frame, wi: vec3<f32>, u1: f32, u2: f32, alpha: f32) -> WardSample {
    let h = to_world(f, ward_half_vector(u1, u2, alpha));
    let hi = dot(h, wi);
    var s: WardSample;
    s.wo = 2.0 * hi * h - wi;
    let ci = dot(f.n, wi);
    let co = dot(f.n, s.wo);
    let ch = dot(f.n, h);
    s.weight = select(0.0, hi * ch * ch * ch / ci, co > 0.0 && hi > 0.0 && ci > 0.0);
    return s;
}
