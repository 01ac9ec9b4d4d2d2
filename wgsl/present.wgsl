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
// The target's format is sRGB (params.decode, which the mirror reads, says the same): a
// pipeline constant, since llvmpipe pays for a branch on a uniform even where it is not taken.
override DECODE: bool = false;

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
    let w = params.image_width;
    let image = vec2<f32>(f32(w), f32(params.image_height));
    let target_size = vec2<f32>(f32(params.target_width), f32(params.target_height));
    // The fragment's centre in the image's pixels, less half a pixel: the integer part is the
    // upper-left tap, the fraction the weights (0 at equal sizes: the fragment's own pixel).
    // A tap past the image's edge reads the edge's pixel.
    let s = max(pixel.xy * (image / target_size) - vec2<f32>(0.5), vec2<f32>(0.0));
    let f = floor(s);
    let t = s - f;
    let x0 = u32(f.x);
    let x1 = min(x0 + 1u, w - 1u);
    let row0 = u32(f.y) * w;
    let row1 = min(u32(f.y) + 1u, params.image_height - 1u) * w;
    let top = mix(unpack4x8unorm(rgba[row0 + x0]), unpack4x8unorm(rgba[row0 + x1]), t.x);
    let bottom = mix(unpack4x8unorm(rgba[row1 + x0]), unpack4x8unorm(rgba[row1 + x1]), t.x);
    let c = mix(top, bottom, t.y).rgb;
    if DECODE {
        return vec4<f32>(srgb_to_linear(c), 1.0);
    }
    return vec4<f32>(c, 1.0);
}
