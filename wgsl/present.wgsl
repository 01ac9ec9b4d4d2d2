// Shows the tone-mapped image (packed sRGB bytes, tonemap_apply's output) in a window: a
// full-screen triangle whose fragments read their pixel. An image smaller than the target (a
// moving frame drawn at a lower internal resolution) is filtered bilinearly, on the display
// values the bytes hold; at equal sizes each fragment reads exactly its own pixel. Where the
// surface's format is sRGB the hardware encodes on write, so the value is decoded to linear
// first (params.decode = 1).
// Twin: src/cpu/present.rs.

// #import types
// #import fullscreen

@group(0) @binding(0) var<uniform> params: PresentParams;
@group(0) @binding(1) var<storage, read> rgba: array<u32>;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

fn texel(x: i32, y: i32) -> vec3<f32> {
    let last = vec2<i32>(i32(params.image_width), i32(params.image_height)) - vec2<i32>(1);
    let p = vec2<u32>(clamp(vec2<i32>(x, y), vec2<i32>(0), last));
    return unpack4x8unorm(rgba[p.y * params.image_width + p.x]).rgb;
}

@vertex
fn vs_main(@builtin(vertex_index) corner: u32) -> @builtin(position) vec4<f32> {
    return fullscreen_corner(corner);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let image = vec2<f32>(f32(params.image_width), f32(params.image_height));
    let target_size = vec2<f32>(f32(params.target_width), f32(params.target_height));
    // The fragment's centre in the image's pixels, less half a pixel: the integer part is the
    // upper-left tap, the fraction the weights.
    let s = pixel.xy * (image / target_size) - vec2<f32>(0.5);
    let f = floor(s);
    let t = s - f;
    let x = i32(f.x);
    let y = i32(f.y);
    let top = mix(texel(x, y), texel(x + 1, y), t.x);
    let bottom = mix(texel(x, y + 1), texel(x + 1, y + 1), t.x);
    let c = mix(top, bottom, t.y);
    return vec4<f32>(select(c, srgb_to_linear(c), params.decode != 0u), 1.0);
}
