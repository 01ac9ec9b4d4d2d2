//! Mirror of `wgsl/photon_resolve.wgsl`: fixed-point sums to HDR pixels.

use crate::types::PhotonViewParams;

pub const WG: u32 = 64;

pub fn photon_resolve(params: &PhotonViewParams, sums: &[u32], hdr: &mut [[f32; 4]]) {
    for (i, out) in hdr.iter_mut().enumerate().take(params.count as usize) {
        let c = &sums[3 * i..3 * i + 3];
        *out = [
            c[0] as f32 / params.scale,
            c[1] as f32 / params.scale,
            c[2] as f32 / params.scale,
            1.0,
        ];
    }
}
