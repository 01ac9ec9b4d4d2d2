// The full-screen passes' vertex: one triangle over the whole viewport, corners (-1, -1),
// (3, -1) and (-1, 3) for vertex indices 0, 1, 2, so that every pixel gets one fragment.
// Only the GPU rasterizes it: the CPU mirrors of these passes loop over pixels.

fn fullscreen_corner(corner: u32) -> vec4<f32> {
    let x = f32(corner & 1u) * 4.0 - 1.0;
    let y = f32(corner >> 1u) * 4.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}
