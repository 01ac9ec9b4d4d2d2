// Shows the tone-mapped image (packed sRGB bytes, tonemap_apply's output) in a window: a
// full-screen triangle whose fragments read their pixel. Where the surface's format is sRGB
// the hardware encodes on write, so the bytes are decoded to linear first (params.z = 1).
// Twin: src/cpu/present.rs.

// #import fullscreen

// x: image width, y: image height, z: 1 to decode sRGB, w: unused.
@group(0) @binding(0) var<uniform> params: vec4<u32>;
@group(0) @binding(1) var<storage, read> rgba: array<u32>;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@vertex
fn vs_main(@builtin(vertex_index) corner: u32) -> @builtin(position) vec4<f32> {
    return fullscreen_corner(corner);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let p = min(vec2<u32>(pixel.xy), params.xy - vec2<u32>(1u));
    let c = unpack4x8unorm(rgba[p.y * params.x + p.x]).rgb;
    return vec4<f32>(select(c, srgb_to_linear(c), params.z != 0u), 1.0);
}
