//! The moving frames' internal resolution. The viewer keeps a target frame time
//! (`--target-ms`) by drawing moving frames smaller than the window, on a ladder of sizes each
//! about half the pixels of the one above, and the present pass upsamples them; at rest the
//! refinement frames draw at the window's size. Below the smallest size the ladder coarsens
//! the level of detail instead: there a frame's cost follows the splats it draws, not its
//! pixels (docs/viewer.md).
//!
//! After each moving frame the controller steps one rung down when the frame took longer than
//! the target and the frame before it at this size did too, or when it took half as long
//! again (a lone slow frame of a software rasterizer's noise moves nothing). It steps up only
//! `FORGET` moving frames after its last step down, and only from a frame that left room
//! (`PROBE`): the rung above was too slow when it was left, the view changes what a frame
//! costs, and a try that fails costs one slow frame.

/// One step of the ladder: a linear scale of the window's size, and a factor on the moving
/// frames' level of detail (`--lod`, in pixels of the frame drawn).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rung {
    pub scale: f32,
    pub lod: f32,
}

const fn rung(scale: f32, lod: f32) -> Rung {
    Rung { scale, lod }
}

/// The ladder, costliest first. Each size about halves the pixels of the one above, down to
/// an eighth of the window's width (160×90 of 1280×720). Below about 320×180 the bunny's
/// frame costs about 3 µs a splat drawn on llvmpipe and little a pixel: at 160×90 the merge
/// tree's 1.5-pixel disks still draw 22 k splats (the walls' own splats are 0.85 pixels wide
/// there, their first merged level 2 pixels), so the last steps widen the merged disks by √2
/// each, about halving the splats drawn (22 k, 14 k, 8.7 k, 5.0 k, 2.7 k; 92 → 29 ms).
pub const RUNGS: [Rung; 11] = [
    rung(1.0, 1.0),
    rung(0.707, 1.0),
    rung(0.5, 1.0),
    rung(0.354, 1.0),
    rung(0.25, 1.0),
    rung(0.177, 1.0),
    rung(0.125, 1.0),
    rung(0.125, 1.414),
    rung(0.125, 2.0),
    rung(0.125, 2.828),
    rung(0.125, 4.0),
];

/// Moving frames after which a size found too slow is tried again.
const FORGET: u64 = 60;
/// The share of the target a frame must stay under before the rung above is tried again.
const PROBE: f64 = 0.7;
/// A frame this many times the target steps down alone, without a slow frame before it.
const FAR_OVER: f64 = 1.5;

/// The target frame time of `view` when `--target-ms` is not given.
pub const DEFAULT_TARGET_MS: f64 = 33.0;

#[derive(Clone, Debug)]
pub struct Resolution {
    /// Milliseconds a frame may take; 0: moving frames at the window's size.
    target_ms: f64,
    /// Index into `RUNGS` of the next moving frame's rung.
    level: usize,
    /// Moving frames drawn so far, and the one of the last step down.
    frames: u64,
    left_above: u64,
    /// The last frame was the first at its size: its time includes making its targets, so it
    /// moves nothing.
    changed: bool,
    /// The last frame at this size took longer than the target.
    over: bool,
}

impl Resolution {
    pub fn new(target_ms: f64) -> Resolution {
        Resolution {
            target_ms,
            level: 0,
            frames: 0,
            left_above: 0,
            changed: false,
            over: false,
        }
    }

    /// The size (width, height) of the next moving frame in a window of `window`.
    pub fn size(&self, (width, height): (u32, u32)) -> (u32, u32) {
        let s = RUNGS[self.level].scale;
        let scaled = |n: u32| ((n as f32 * s).round() as u32).clamp(1, n.max(1));
        (scaled(width), scaled(height))
    }

    /// The next moving frame's level of detail in pixels, for `lod` at the window's size (0,
    /// every splat drawn, stays 0).
    pub fn lod(&self, lod: f32) -> f32 {
        lod * RUNGS[self.level].lod
    }

    /// Takes the time of the moving frame just drawn at `size()` and picks the next one's.
    pub fn record(&mut self, ms: f64) {
        self.frames += 1;
        if self.target_ms <= 0.0 || std::mem::take(&mut self.changed) {
            return;
        }
        let over = ms > self.target_ms;
        let over_before = std::mem::replace(&mut self.over, over);
        let slow = over && (over_before || ms > FAR_OVER * self.target_ms);
        if slow && self.level + 1 < RUNGS.len() {
            self.level += 1;
            self.left_above = self.frames;
            (self.changed, self.over) = (true, false);
        } else if self.level > 0
            && self.frames - self.left_above >= FORGET
            && ms < PROBE * self.target_ms
        {
            self.level -= 1;
            (self.changed, self.over) = (true, false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame's time in a model of the viewer on a software rasterizer: a part that follows
    /// the splats drawn (about the inverse square of the level of detail's disks) and a part
    /// that follows the pixels.
    fn model(splats: f64, window: f64) -> impl Fn((u32, u32), f32) -> f64 {
        move |(w, h), lod| splats / (lod * lod) as f64 + window * (w * h) as f64 / (1280.0 * 720.0)
    }

    /// Runs `frames` moving frames of a 1280×720 window at a level of detail of 1 pixel, frame
    /// k costing `cost(k, size, lod)`; returns each frame's size, level of detail and time.
    fn run(
        target_ms: f64,
        frames: usize,
        cost: impl Fn(usize, (u32, u32), f32) -> f64,
    ) -> Vec<((u32, u32), f32, f64)> {
        let mut r = Resolution::new(target_ms);
        (0..frames)
            .map(|k| {
                let (size, lod) = (r.size((1280, 720)), r.lod(1.0));
                let ms = cost(k, size, lod);
                r.record(ms);
                (size, lod, ms)
            })
            .collect()
    }

    #[test]
    fn frames_settle_on_the_largest_size_within_the_target() {
        // 40 + 200 / 4 = 90 ms at half the width, 140 ms at 0.707 of it.
        let frames = run(95.0, 200, |_, size, lod| model(40.0, 200.0)(size, lod));
        let settled = &frames[10..];
        assert!(
            settled
                .iter()
                .all(|f| f.0 == (640, 360) && f.1 == 1.0 && f.2 <= 95.0),
            "{settled:?}"
        );
    }

    #[test]
    fn a_cheaper_view_gets_the_larger_sizes_back() {
        // 60 + 80 / 4 = 80 ms at half the width, 100 ms at 0.707 of it; the view turns away
        // from the costly splats at frame 100, and every size fits.
        let cost = |k: usize, size, lod| model(if k < 100 { 60.0 } else { 0.0 }, 80.0)(size, lod);
        let frames = run(90.0, 400, cost);
        assert_eq!(frames[99].0, (640, 360));
        // Two probes up (each after FORGET frames at a size), then the window's size for good.
        let back = 100 + 2 * FORGET as usize + 4;
        assert!(
            frames[back..].iter().all(|f| f.0 == (1280, 720)),
            "{:?}",
            &frames[back..]
        );
    }

    #[test]
    fn a_lone_slow_frame_moves_nothing() {
        // 90 ms at half the width within a target of 95 ms; every tenth frame 30 % slower.
        let cost = |k: usize, size, lod| {
            model(40.0, 200.0)(size, lod) * if k % 10 == 9 { 1.3 } else { 1.0 }
        };
        let frames = run(95.0, 200, cost);
        assert!(frames[10..].iter().all(|f| f.0 == (640, 360)), "{frames:?}");
    }

    #[test]
    fn splats_that_no_size_pays_for_coarsen_the_level_of_detail() {
        // 80 ms of splats at full detail: no size meets 40 ms, the disks twice as wide do
        // (80 / 4 + 200 / 64 = 23 ms), 1.41 times as wide do not (43 ms).
        let frames = run(40.0, 200, |_, size, lod| model(80.0, 200.0)(size, lod));
        let settled = &frames[30..];
        assert!(
            settled
                .iter()
                .all(|f| f.0 == (160, 90) && f.1 >= 1.414 && f.1 <= 2.0),
            "{settled:?}"
        );
        // The finer rung is tried again after FORGET frames, for two frames each time.
        let probes = settled.iter().filter(|f| f.1 < 2.0).count();
        assert!((1..=6).contains(&probes), "{settled:?}");
    }

    #[test]
    fn an_unreachable_target_draws_the_last_rung() {
        let frames = run(1.0, 30, |_, size, lod| model(40.0, 200.0)(size, lod));
        let last = RUNGS[RUNGS.len() - 1];
        assert_eq!(
            frames.last().map(|f| (f.0, f.1)),
            Some(((160, 90), last.lod))
        );
    }

    #[test]
    fn no_target_keeps_the_window_size() {
        let cost = |_, size, lod| model(40.0, 200.0)(size, lod);
        let whole = |f: &((u32, u32), f32, f64)| f.0 == (1280, 720) && f.1 == 1.0;
        assert!(run(0.0, 10, cost).iter().all(whole));
        // A target every size meets keeps it too.
        assert!(run(1000.0, 10, cost).iter().all(whole));
    }
}
