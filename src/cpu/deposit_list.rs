//! Mirror of `wgsl/deposit_list.wgsl`: each splat with a deposit lists it as a photon
//! record at its photons' mean, and writes their spread and count, for one range of splats.
//! Sequential, so the list is in splat order (the device's is in any order; binning sorts both
//! alike).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;

use crate::shared::deposits::{
    DEPOSIT_COUNT, DEPOSIT_OFFSET, DEPOSIT_OFFSET_SUM, DEPOSIT_POSITION_UNITS, DEPOSIT_POWER,
    DEPOSIT_SQUARE_SUM, DEPOSIT_WORDS, deposit_value,
};
use crate::types::{DepositParams, Photon, Splat};

pub const WG: u32 = 64;

pub fn deposit_list(
    deposit: &DepositParams,
    splats: &[Splat],
    deposits: &[u32],
    deposit_list: &mut [Photon],
    spread: &mut [[f32; 2]],
    listed: &mut u32,
    groups: u32,
) {
    let wide = |at: usize| deposit_value(deposits[at], deposits[at + 1]);
    for local in 0..(groups * WG).min(deposit.splat_count) {
        let j = deposit.first_splat + local;
        let base = (local * DEPOSIT_WORDS) as usize;
        let count = deposits[base + DEPOSIT_COUNT as usize];
        if count == 0 {
            continue;
        }
        let s = &splats[j as usize];
        let per_photon = 1.0 / count as f32;
        let mut power = [0.0f32; 3];
        let mut mean = Vec3::ZERO;
        for c in 0..3 {
            power[c] = wide(base + DEPOSIT_POWER as usize + 2 * c) / deposit.power_scale;
            mean[c] = wide(base + DEPOSIT_OFFSET_SUM as usize + 2 * c) / DEPOSIT_POSITION_UNITS
                * per_photon
                - DEPOSIT_OFFSET;
        }
        let square = wide(base + DEPOSIT_SQUARE_SUM as usize) / DEPOSIT_POSITION_UNITS * per_photon;
        let rho =
            (s.radius * (2.0 * (square - mean.dot(mean)).max(0.0)).sqrt()).min(deposit.spread_max);
        deposit_list[*listed as usize] = Photon {
            position: (Vec3::from(s.center) + mean * s.radius).into(),
            bounce: 0,
            direction: s.normal,
            splat: j,
            power,
            path: j,
        };
        *listed += 1;
        spread[j as usize] = [rho, count as f32];
    }
}

/// The executor's entry: `deposit_list`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let splats = b.get(1)?;
    let deposits = b.get(2)?;
    let mut list = b.get_mut(3)?;
    let mut spread = b.get_mut(4)?;
    let mut listed = b.get_mut(5)?;
    let listed = listed
        .first_mut()
        .ok_or_else(|| b.internal("no list counter"))?;
    deposit_list(
        &p,
        view(&splats),
        &deposits,
        view_mut(&mut list),
        view_mut(&mut spread),
        listed,
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::DepositList,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
