//! The table of light-lobe norms the shading divides by (`shared::lobe_brdf`): the
//! hemispherical integral of a Ward-like lobe `exp(−tan²δ/β²) / (4πβ²)` at each node of
//! (cos θL, log2 β²). No closed form holds once the horizon cuts a broad or grazing lobe
//! (cos θL · κ(β²) is 14 % off at β² = 1 even at normal incidence), so the nodes come from
//! the convolution study's quadrature, computed once per process.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::convolution::{Case, Reference};
use crate::shared::lobe_brdf::{NORM_B2_NODES, NORM_COS_NODES, norm_node};

/// Quadrature points per edge of the lobe's sample map (the reference tests use 32–64).
const NORM_QUADRATURE: usize = 64;

/// `NORM_COS_NODES × NORM_B2_NODES` norms, rows of constant β².
pub fn lobe_norms() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..NORM_COS_NODES * NORM_B2_NODES)
            .into_par_iter()
            .map(|i| {
                let (cos_l, beta2) = norm_node(i % NORM_COS_NODES, i / NORM_COS_NODES);
                let case = Case {
                    alpha: 0.0,
                    beta2: beta2 as f64,
                    angle: (cos_l as f64).acos(),
                };
                Reference::new(case, NORM_QUADRATURE).norm as f32
            })
            .collect()
    })
}
