//! Mirror of `wgsl/photon_resolve.wgsl`: fixed-point sums to HDR pixels.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view_mut};
use crate::error::Result;
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

/// The executor's entry: `photon_resolve`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let sums = b.get(1)?;
    let mut hdr = b.get_mut(2)?;
    photon_resolve(&p, &sums, view_mut(&mut hdr));
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::PhotonResolve,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
