//! One memory budget for what a scene makes: splats from shapes, model surfaces and clouds, and
//! decompressed model files. Each maker estimates its bytes before it allocates and asks
//! `Budget::check`; past the budget the error names the object, the estimate and the budget,
//! and says what to change. The budget defaults to `DEFAULT_SHARE` of the machine's memory (or
//! of the process's address-space limit, `ulimit -v`, where that is lower) and is set by
//! `--max-memory` (`set_default`) or a scene file's `max_memory`.

use std::sync::atomic::{AtomicU64, Ordering};

/// The share of the machine's memory (or of the address-space limit) the budget defaults to.
pub const DEFAULT_SHARE: f64 = 0.5;

/// What one splat costs from its load through the bake and the frames, in bytes: its record
/// (48 B), the disk and colour it is made from, the vectors' growth, the grid's lists, its
/// light and direct bake. Measured on the CPU mirror: 182 B a splat for a sampled surface
/// (peak RSS of `render --cpu` of one triangle at spacing 1e-9: 16.8 M splats, 3.05 GB), 360 B
/// a splat for a cloud through its load and grid (normals estimated; `info --cpu` of the 20 k-
/// and 60 k-point terrains of `bench scale`, the difference over the 40 k points between them);
/// rounded up.
pub const SPLAT_BYTES: u64 = 400;

/// What one pixel of a still image costs through the CPU mirror's frames (its samples,
/// accumulations, history and the written image): measured 187 B (peak RSS of `render
/// scenes/cornell.toml --cpu --photons 20000` at 256² and 1024²: 183 MB more for 983 k more
/// pixels), rounded up. A device holds its frames in its own memory, within its limits.
pub const PIXEL_BYTES: u64 = 192;

/// The budget `--max-memory` set (0: none, the machine's share).
static DEFAULT: AtomicU64 = AtomicU64::new(0);

/// A memory budget in bytes, and where it came from (for the error's advice).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    pub bytes: u64,
    pub source: Source,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// `DEFAULT_SHARE` of the machine's memory or address-space limit.
    Machine,
    /// `--max-memory`.
    Flag,
    /// The scene file's `max_memory`.
    Scene,
}

impl Budget {
    /// The budget in force: `--max-memory`'s, else the machine's share.
    pub fn current() -> Budget {
        match DEFAULT.load(Ordering::Relaxed) {
            0 => Budget {
                bytes: machine_share(),
                source: Source::Machine,
            },
            bytes => Budget {
                bytes,
                source: Source::Flag,
            },
        }
    }

    /// The budget for a scene whose file asks for `scene` bytes (`max_memory`): the flag's
    /// where it was given (the command line wins), else the file's, else the machine's share.
    pub fn for_scene(scene: Option<u64>) -> Budget {
        match (Budget::current(), scene) {
            (b, _) if b.source == Source::Flag => b,
            (_, Some(bytes)) => Budget {
                bytes,
                source: Source::Scene,
            },
            (b, None) => b,
        }
    }

    /// Refuses `what`, which would take `bytes`, past the budget, in one line the caller
    /// places (its file, line or object); `advice` says what to change given the factor by
    /// which the estimate must shrink (above 1).
    pub fn check(
        &self,
        what: &str,
        bytes: u64,
        advice: impl FnOnce(f64) -> String,
    ) -> std::result::Result<(), String> {
        if bytes <= self.bytes {
            return Ok(());
        }
        let factor = bytes as f64 / self.bytes.max(1) as f64;
        Err(format!(
            "{what} would take about {} of memory, past the budget of {} ({}): {}",
            human(bytes),
            human(self.bytes),
            match self.source {
                Source::Machine => {
                    "half this machine's memory or address space; --max-memory sets another"
                }
                Source::Flag => "--max-memory",
                Source::Scene => "the scene's max_memory",
            },
            advice(factor)
        ))
    }

    /// `check` of the splats `count_at(spacing)` makes (`SPLAT_BYTES` each): the advice is
    /// the least spacing at which they fit, found by bisection over `count_at`.
    pub fn check_splats(
        &self,
        what: &str,
        spacing: f32,
        count_at: &dyn Fn(f32) -> f64,
    ) -> std::result::Result<(), String> {
        let splats = count_at(spacing);
        let bytes = bytes_of(splats);
        self.check(
            &format!("{what}: {} splats", count(splats)),
            bytes,
            |_| match self.spacing_that_fits(spacing, count_at) {
                Some(s) => format!("raise `spacing` to {s:.3e} or more"),
                None => "no spacing fits: make the scene smaller".into(),
            },
        )
    }

    /// The least spacing above `spacing` (within 1 %) at which `count_at`'s splats fit.
    fn spacing_that_fits(&self, spacing: f32, count_at: &dyn Fn(f32) -> f64) -> Option<f32> {
        let fits = |s: f32| bytes_of(count_at(s)) <= self.bytes;
        let mut hi = spacing.max(f32::MIN_POSITIVE);
        while !fits(hi) {
            hi *= 2.0;
            if !hi.is_finite() {
                return None;
            }
        }
        let mut lo = hi / 2.0;
        while hi / lo > 1.01 {
            let mid = (lo * hi).sqrt();
            if fits(mid) { hi = mid } else { lo = mid }
        }
        Some(hi)
    }

    /// Reads the whole of `path` (a regular file: `Error::read_regular_file`), refusing before
    /// a byte is read a file larger than the budget: a reader holds the file's bytes whole.
    pub fn read_file(&self, path: &std::path::Path) -> crate::error::Result<Vec<u8>> {
        use crate::error::Error;
        if let Ok(meta) = std::fs::metadata(path) {
            let advice = |factor: f64| format!("it must be {factor:.1} times smaller: split it");
            (self.check("the file", meta.len(), advice))
                .map_err(|m| Error::parse(path, "size", m))?;
        }
        Error::read_regular_file(path)
    }

    /// `check` of a `width` × `height` image drawn on the CPU mirror (`PIXEL_BYTES` a pixel):
    /// the advice is the size that fits, at the same aspect.
    pub fn check_image(&self, width: u32, height: u32) -> std::result::Result<(), String> {
        let pixels = width as u64 * height as u64;
        self.check(
            &format!("a {width}×{height} image on the CPU mirror"),
            pixels.saturating_mul(PIXEL_BYTES),
            |factor| {
                let shrink = factor.sqrt();
                let side = |s: u32| (s as f64 / shrink).floor() as u32;
                format!("render at {}×{} or less", side(width), side(height))
            },
        )
    }

    /// `check` of a cloud's `points`, a splat each: the advice is the subsampling that fits.
    pub fn check_points(&self, what: &str, points: f64) -> std::result::Result<(), String> {
        self.check(
            &format!("{what}: {} points", count(points)),
            bytes_of(points),
            |factor| {
                format!(
                    "subsample the cloud to one point in {}",
                    factor.ceil() as u64
                )
            },
        )
    }
}

/// The bytes `splats` splats take (`SPLAT_BYTES` each), saturating.
fn bytes_of(splats: f64) -> u64 {
    match splats * SPLAT_BYTES as f64 {
        b if b.is_finite() => b.min(u64::MAX as f64) as u64,
        _ => u64::MAX,
    }
}

/// Sets the budget `Budget::current` gives (`--max-memory`).
pub fn set_default(bytes: u64) {
    DEFAULT.store(bytes.max(1), Ordering::Relaxed);
}

/// `DEFAULT_SHARE` of the machine's physical memory, or of the address-space limit where that
/// is lower; 4 GiB where neither can be read.
fn machine_share() -> u64 {
    let physical = physical_memory();
    let limit = address_space_limit();
    let base = match (physical, limit) {
        (Some(p), Some(l)) => p.min(l),
        (Some(x), None) | (None, Some(x)) => x,
        (None, None) => 8 << 30,
    };
    (base as f64 * DEFAULT_SHARE) as u64
}

#[cfg(unix)]
fn physical_memory() -> Option<u64> {
    // SAFETY: sysconf reads a system constant and has no preconditions.
    let (pages, size) = unsafe {
        (
            libc::sysconf(libc::_SC_PHYS_PAGES),
            libc::sysconf(libc::_SC_PAGESIZE),
        )
    };
    (pages > 0 && size > 0).then(|| pages as u64 * size as u64)
}

#[cfg(not(unix))]
fn physical_memory() -> Option<u64> {
    None
}

#[cfg(unix)]
fn address_space_limit() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given, which lives on this stack frame.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } == 0;
    // rlim_t is u64 on Linux, not on every unix.
    #[allow(clippy::unnecessary_cast)]
    let current = limit.rlim_cur as u64;
    (ok && limit.rlim_cur != libc::RLIM_INFINITY).then_some(current)
}

#[cfg(not(unix))]
fn address_space_limit() -> Option<u64> {
    None
}

/// Parses a size: a number of bytes, or with a unit K, M, G, T (powers of 1024; `KB`, `KiB`
/// and lower case read alike), e.g. `8G`, `512MiB`, `1.5g`.
pub fn parse_size(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let bad =
        || format!("`{text}` is not a size: write bytes, or a number with K, M, G or T (e.g. 8G)");
    let value: f64 = number.parse().map_err(|_| bad())?;
    let shift = match unit
        .trim()
        .to_ascii_lowercase()
        .trim_end_matches('b')
        .trim_end_matches('i')
    {
        "" => 0,
        "k" => 10,
        "m" => 20,
        "g" => 30,
        "t" => 40,
        _ => return Err(bad()),
    };
    let bytes = value * (1u64 << shift) as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes > u64::MAX as f64 {
        return Err(format!("`{text}` is not a size between 1 byte and 16 EiB"));
    }
    Ok(bytes as u64)
}

/// Bytes in the largest unit that keeps a whole number in front (`1.5 GiB`).
pub fn human(bytes: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    match unit {
        0 => format!("{bytes} B"),
        _ => format!("{value:.1} {}", units[unit]),
    }
}

/// A count in the words a user reads (`65.4 M`).
fn count(n: f64) -> String {
    match n {
        n if !n.is_finite() => "too many".into(),
        n if n >= 1e9 => format!("{:.1} G", n / 1e9),
        n if n >= 1e6 => format!("{:.1} M", n / 1e6),
        n if n >= 1e3 => format!("{:.1} k", n / 1e3),
        n => format!("{n:.0}"),
    }
}
