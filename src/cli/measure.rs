//! Figures shared by the measuring commands (bench, sweep, rebake, the viewer's report).

/// The median of timings (the upper one of an even count); 0 for none.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}
