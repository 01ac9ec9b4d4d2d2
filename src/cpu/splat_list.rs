//! Mirror of `wgsl/splat_list.wgsl`: the drawn splats (drawn radius above 0) in index order,
//! each workgroup's from its offset in the scanned counts.

pub const WG: u32 = 64;

pub fn splat_list(offsets: &[u32], drawn: &[f32]) -> Vec<u32> {
    let count = offsets.last().copied().unwrap_or(0) as usize
        + drawn
            .chunks(WG as usize)
            .last()
            .map_or(0, |c| c.iter().filter(|&&r| r > 0.0).count());
    let mut selected = vec![0; count];
    for (group, chunk) in drawn.chunks(WG as usize).enumerate() {
        let mut rank = 0;
        for (lid, &r) in chunk.iter().enumerate() {
            if r > 0.0 {
                selected[(offsets[group] + rank) as usize] = (group * WG as usize + lid) as u32;
                rank += 1;
            }
        }
    }
    selected
}
