//! How a model file is read, and what its reader left out. Scans come from many tools and
//! some hold broken points: a `nan nan nan` line, a truncated last line, a coordinate past
//! f32's range. A reader skips such a point and counts it (`LeftOut::skipped`, with where the
//! first one is and why), as scan tools do, unless the reading is strict (`--strict`), when the
//! first is an error; a file whose points are all bad is an error either way. Points left out
//! by a rule of the format (a Gaussian too faint to be a surface) are counted per rule.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::budget::Budget;
use crate::error::{Error, Result};

/// Whether `--strict` was given: a bad point refuses its file.
static STRICT: AtomicBool = AtomicBool::new(false);

/// Sets whether readings refuse a file at its first bad point (`--strict`).
pub fn set_strict(strict: bool) {
    STRICT.store(strict, Ordering::Relaxed);
}

thread_local! {
    /// Whether this thread runs a decoder of another crate (`guarded`).
    static DECODING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this thread is inside `guarded`: a panic hook may leave the decoder's panics
/// unsaid, as `guarded` turns them into an error naming the file.
pub fn in_decoder() -> bool {
    DECODING.with(|d| d.get())
}

/// Runs `decode`, a decoder of another crate, turning a panic in it into an error: the LAZ
/// decoder indexes past its tables and takes items it did not check on some damaged files
/// (found by fuzzing, `fuzz/crashes/las`), and no file may take the process down.
pub fn guarded<T>(path: &std::path::Path, decode: impl FnOnce() -> Result<T>) -> Result<T> {
    DECODING.with(|d| d.set(true));
    let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(decode));
    DECODING.with(|d| d.set(false));
    caught.unwrap_or_else(|panic| {
        let why = (panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(Error::parse(
            path,
            "data",
            format!("the decoder failed on this file ({why}): it is damaged"),
        ))
    })
}

/// What a reader may take: the memory budget of what it makes, and whether a bad point
/// refuses the file (strict) or is skipped and counted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reading {
    pub budget: Budget,
    pub strict: bool,
}

impl Reading {
    /// The reading in force: the budget's and `--strict`'s.
    pub fn current() -> Reading {
        Reading::within(Budget::current())
    }

    /// The reading in force, within `budget`.
    pub fn within(budget: Budget) -> Reading {
        Reading {
            budget,
            strict: STRICT.load(Ordering::Relaxed),
        }
    }

    /// Refuses a file that announces `points` points past the budget, before any is read.
    pub fn check_points(&self, path: &std::path::Path, at: &str, points: u64) -> Result<()> {
        let what = "the points it announces";
        (self.budget.check_points(what, points as f64)).map_err(|m| Error::parse(path, at, m))
    }
}

/// What a reader left out of a model, and why.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LeftOut {
    /// Points that could not be read or were not finite: skipped, unless the reading is
    /// strict.
    pub skipped: usize,
    /// The first skipped point: where it is in the file and what was wrong.
    pub first_skipped: Option<String>,
    /// Points a rule of the format left out, per rule, in the order first met.
    pub by_rule: Vec<RuleCount>,
}

/// How many points one rule left out.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RuleCount {
    pub rule: String,
    pub count: usize,
}

impl LeftOut {
    /// Skips the point `error` describes, or returns the error where the reading is strict.
    pub fn skip(&mut self, reading: &Reading, error: Error) -> Result<()> {
        if reading.strict {
            return Err(error);
        }
        self.skipped += 1;
        if self.first_skipped.is_none() {
            self.first_skipped = Some(error.to_string());
        }
        Ok(())
    }

    /// Counts a point left out by `rule`.
    pub fn drop_by(&mut self, rule: &str) {
        match self.by_rule.iter_mut().find(|r| r.rule == rule) {
            Some(r) => r.count += 1,
            None => self.by_rule.push(RuleCount {
                rule: rule.to_string(),
                count: 1,
            }),
        }
    }

    /// Points left out by rules, all rules together.
    pub fn dropped(&self) -> usize {
        self.by_rule.iter().map(|r| r.count).sum()
    }

    /// Why a file kept no point: its skipped points and its rules' counts, in words.
    pub fn why_none(&self) -> String {
        let mut parts: Vec<String> = (self.by_rule.iter())
            .map(|r| format!("{} {}", r.count, r.rule))
            .collect();
        if let Some(first) = &self.first_skipped {
            parts.push(format!(
                "{} could not be read (the first: {first})",
                self.skipped
            ));
        }
        parts.join("; ")
    }
}

/// `value` as f32, or why not: a finite number past f32's range says so, rather than
/// reading as infinite.
pub fn to_f32(value: f64) -> std::result::Result<f32, String> {
    let v = value as f32;
    match (value.is_finite(), v.is_finite()) {
        (true, true) => Ok(v),
        (true, false) => Err(format!("{value:e} is out of f32's range (±3.4e38)")),
        (false, _) => Err(format!("{value} is not a finite number")),
    }
}

/// A point's three coordinates as f32, or why not (`to_f32`), naming what they are.
pub fn point_f32(what: &str, v: [f64; 3]) -> std::result::Result<glam::Vec3, String> {
    let mut out = [0f32; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = to_f32(x).map_err(|m| format!("{what} {v:?}: {m}"))?;
    }
    Ok(out.into())
}
