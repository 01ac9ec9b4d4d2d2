//! Mirror of `wgsl/deposit_add.wgsl`: each photon adds itself to its splat's deposit, in 64-bit
//! integer sums (added here as u64, which is what the device's carried words hold).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use glam::Vec3;

use crate::shared::deposits::{
    DEPOSIT_COUNT, DEPOSIT_OFFSET, DEPOSIT_OFFSET_SUM, DEPOSIT_POSITION_UNITS, DEPOSIT_POWER,
    DEPOSIT_SQUARE_SUM, DEPOSIT_WORDS, fixed,
};
use crate::types::{DepositParams, Photon, Splat};

pub const WG: u32 = 64;

/// Adds `v` to the 64-bit sum at word `at` (low word first).
fn add_wide(deposits: &mut [u32], at: usize, v: u32) {
    let sum = (deposits[at] as u64 | (deposits[at + 1] as u64) << 32).wrapping_add(v as u64);
    deposits[at] = sum as u32;
    deposits[at + 1] = (sum >> 32) as u32;
}

pub fn deposit_add(
    deposit: &DepositParams,
    photons: &[Photon],
    splats: &[Splat],
    deposits: &mut [u32],
    groups: u32,
) {
    let count = (groups * WG).min(deposit.photon_count) as usize;
    for p in &photons[..count.min(photons.len())] {
        let local = p.splat.wrapping_sub(deposit.first_splat);
        if local >= deposit.splat_count {
            continue;
        }
        let s = &splats[p.splat as usize];
        let o = ((Vec3::from(p.position) - Vec3::from(s.center)) / s.radius)
            .clamp(Vec3::splat(-DEPOSIT_OFFSET), Vec3::splat(DEPOSIT_OFFSET));
        let base = (local * DEPOSIT_WORDS) as usize;
        deposits[base + DEPOSIT_COUNT as usize] += 1;
        for c in 0..3 {
            let power = fixed(p.power[c].max(0.0), deposit.power_scale);
            add_wide(deposits, base + DEPOSIT_POWER as usize + 2 * c, power);
            let offset = fixed(o[c] + DEPOSIT_OFFSET, DEPOSIT_POSITION_UNITS);
            add_wide(deposits, base + DEPOSIT_OFFSET_SUM as usize + 2 * c, offset);
        }
        let square = fixed(o.dot(o), DEPOSIT_POSITION_UNITS);
        add_wide(deposits, base + DEPOSIT_SQUARE_SUM as usize, square);
    }
}

/// The executor's entry: `deposit_add`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let photons = b.get(1)?;
    let splats = b.get(2)?;
    let mut deposits = b.get_mut(3)?;
    deposit_add(&p, view(&photons), view(&splats), &mut deposits, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::DepositAdd,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
