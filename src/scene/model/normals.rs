//! Point clouds without faces: PCA normals from the k nearest neighbours, oriented
//! consistently by propagation along a minimum spanning tree of the neighbour graph (Hoppe et
//! al. 1992), and disk radii from the neighbour spacing.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::num::NonZeroUsize;

use glam::{Mat3, Vec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Neighbours used for a normal (the point itself included).
const NORMAL_K: usize = 12;
/// The disk radius is this fraction of the distance to the `RADIUS_K`-th neighbour. On a
/// square lattice of spacing h the 6th neighbour is at √2·h and disks need h/√2 to close.
const RADIUS_K: usize = 6;
const RADIUS_FACTOR: f32 = 0.8;

fn knn(points: &[Vec3], k: usize) -> Vec<Vec<(u32, f32)>> {
    let entries: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    let Ok(tree) = ImmutableKdTree::<f32, 3>::new_from_slice(&entries) else {
        return vec![Vec::new(); points.len()];
    };
    let k = NonZeroUsize::new(k.min(points.len()).max(1)).unwrap_or(NonZeroUsize::MIN);
    // Each query is independent: in parallel, in the points' order.
    entries
        .par_iter()
        .map(|q| {
            tree.query(q)
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .execute()
                .into_iter()
                .map(|r| (r.item, r.distance.sqrt()))
                .collect()
        })
        .collect()
}

/// Radius of each point's disk from the distance to its `RADIUS_K`-th neighbour.
pub fn spacing_radii(points: &[Vec3]) -> Vec<f32> {
    knn(points, RADIUS_K + 1)
        .iter()
        .map(|nb| nb.last().map_or(0.0, |&(_, d)| d * RADIUS_FACTOR))
        .collect()
}

/// Unit normals by PCA, oriented consistently; zero where the neighbourhood is degenerate.
pub fn pca_normals(points: &[Vec3]) -> Vec<Vec3> {
    let neighbours = knn(points, NORMAL_K);
    let mut normals: Vec<Vec3> = neighbours
        .iter()
        .map(|nb| {
            let pts: Vec<Vec3> = nb.iter().map(|&(j, _)| points[j as usize]).collect();
            smallest_eigenvector(&covariance(&pts))
        })
        .collect();
    orient(points, &neighbours, &mut normals);
    normals
}

/// Turns given normals (whose sign means nothing, as a Gaussian's) to one consistent side, as
/// `pca_normals` orients its own.
pub fn orient_normals(points: &[Vec3], normals: &mut [Vec3]) {
    let neighbours = knn(points, NORMAL_K);
    orient(points, &neighbours, normals);
}

fn covariance(pts: &[Vec3]) -> Mat3 {
    let mean = pts.iter().copied().sum::<Vec3>() / pts.len().max(1) as f32;
    let mut c = Mat3::ZERO;
    for p in pts {
        let d = *p - mean;
        c += Mat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    c
}

/// Eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix (cyclic Jacobi).
pub fn smallest_eigenvector(m: &Mat3) -> Vec3 {
    let mut a = m.to_cols_array_2d().map(|c| c.map(|x| x as f64));
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0f64]];
    for _sweep in 0..32 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off < 1e-30 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
            // A ← Jᵀ A J: columns p and q, then rows p and q.
            for row in a.iter_mut() {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * rp[k] - s * rq[k]);
            a[q] = std::array::from_fn(|k| s * rp[k] + c * rq[k]);
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let k = (0..3)
        .min_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(0);
    let e = Vec3::new(v[0][k] as f32, v[1][k] as f32, v[2][k] as f32);
    if e.is_finite() {
        e.normalize_or_zero()
    } else {
        Vec3::ZERO
    }
}

/// Propagates a consistent orientation over the k-NN graph: each connected part starts at its
/// highest point, whose normal is turned to +z (the outside of a closed object there), then
/// Prim's tree over weights 1 − |nᵢ·nⱼ| flips each normal to agree with its parent's.
fn orient(points: &[Vec3], neighbours: &[Vec<(u32, f32)>], normals: &mut [Vec3]) {
    let n = points.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| {
        points[b as usize]
            .z
            .total_cmp(&points[a as usize].z)
            .then(a.cmp(&b))
    });
    let mut done = vec![false; n];
    // Heap of (weight bits, node, parent); the bits of a non-negative f32 order like the value.
    let mut heap = BinaryHeap::new();
    for &seed in &order {
        if done[seed as usize] {
            continue;
        }
        if normals[seed as usize].z < 0.0 {
            normals[seed as usize] = -normals[seed as usize];
        }
        heap.push(Reverse((0u32, seed, seed)));
        while let Some(Reverse((_, node, parent))) = heap.pop() {
            let i = node as usize;
            if done[i] {
                continue;
            }
            done[i] = true;
            if normals[i].dot(normals[parent as usize]) < 0.0 {
                normals[i] = -normals[i];
            }
            for &(j, _) in &neighbours[i] {
                if !done[j as usize] {
                    let w = 1.0 - normals[i].dot(normals[j as usize]).abs();
                    heap.push(Reverse((w.max(0.0).to_bits(), j, node)));
                }
            }
        }
    }
}
