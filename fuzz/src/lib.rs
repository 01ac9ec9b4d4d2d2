//! What every fuzz target shares: a small memory budget, so that an input the budget should
//! refuse shows as the fuzzer's out-of-memory crash rather than passing under the machine's
//! default; and the checks every parsed model must pass.

use std::path::Path;

use lobelight::budget::{Budget, Source};
use lobelight::scene::model::{Mesh, Reading, to_splats};

/// The budget every target runs within: well under libFuzzer's default RSS limit of 2 GiB.
pub const BUDGET: u64 = 256 << 20;

/// Sets the budget (`--max-memory`), and a panic hook that lets a decoder's panic be what
/// `reading::guarded` turns into an error (libFuzzer's hook aborts at any panic, caught or
/// not); once per process.
pub fn init() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        lobelight::budget::set_default(BUDGET);
        let abort = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !lobelight::scene::model::reading::in_decoder() {
                abort(info)
            }
        }));
    });
}

/// The reading a target parses with: bad points skipped (the path that keeps going).
pub fn reading() -> Reading {
    init();
    Reading {
        budget: Budget {
            bytes: BUDGET,
            source: Source::Flag,
        },
        strict: false,
    }
}

/// A parsed model must be sane: as many normals, colours and radii as points, every point
/// finite; its splats, where it makes any, finite with positive radii and
/// unit normals.
pub fn check(mesh: &Mesh, path: &Path) {
    let n = mesh.positions.len();
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    for len in [
        mesh.normals.as_ref().map(Vec::len),
        mesh.colors.as_ref().map(Vec::len),
        mesh.radii.as_ref().map(Vec::len),
    ]
    .into_iter()
    .flatten()
    {
        assert_eq!(len, n);
    }
    // Faces out of range are `to_splats`'s to refuse (`load` refuses them the same way).
    if let Ok(set) = to_splats(mesh, path) {
        for d in &set.disks {
            assert!(d.center.is_finite() && d.radius > 0.0 && d.radius.is_finite());
            assert!((d.normal.length() - 1.0).abs() < 1e-3, "{:?}", d.normal);
        }
    }
}
