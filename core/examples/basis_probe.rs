//! An edge basis for the exact utility (development aid, not used by the planners): how
//! close and how fast `f_D` is when every sample's `L^-1 k_V(p)` is interpolated from
//! `m` Chebyshev nodes on its edge and the nodes' Gram matrix is computed once.
//! `docs/benchmark-scale.md` ("Measured for a next step: an edge basis") has its
//! figures, and those of the basis built into the engine's exact phase (not kept).
//!
//! Why: a person's walk of 1,018 m on the 565-vertex mall has 213 samples, and an exact
//! evaluation is dominated by the triangular solve of their kernel columns against `A`'s
//! factor (`nv^2 / 2` multiply-adds a sample) and the product of the solved columns
//! (`nv ns^2 / 2`). With the basis, the sample-pair entries of `K_SV A^-1 K_VS` cost
//! `m^2` each from the Gram matrix, and what is left is the `ns x ns` factorisation.
//! Along an edge `k(v, p(t))` is smooth in `t` (the kernel's kink is at `p = v`, an end
//! of the edge), so a few nodes suffice; the search may rank by such a value, every
//! reported utility stays the exact one (SPEC 3).
//!
//! `cargo run --release -p trailprint-core --example basis_probe -- FILE PLAN.json
//! robot|human` (a one-floor building; `PLAN.json` from `trailprint plan --json`). It
//! prints the exact utility and, for m = 4, 5 and 6, the basis value, its error, the
//! set-up time and memory, and one evaluation's time (plain nalgebra loops here).
use std::collections::HashMap;
use std::time::Instant;

use nalgebra::DMatrix;
use trailprint::Error;
use trailprint::gp::kernel::{Kernel, Point};
use trailprint::samples::{point_on_edge, sample_walk};

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(4, "basis_probe FILE PLAN.json robot|human")?;
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let model = cases::model_named(&a[3]);
    if b.floors.len() > 1 {
        return Err(Error::InvalidRequest(
            "basis_probe: one floor only (a stair edge needs a basis per half)".into(),
        ));
    }
    let text = std::fs::read_to_string(&a[2])
        .map_err(|e| Error::InvalidRequest(format!("{}: {e}", a[2])))?;
    let plan: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Error::InvalidRequest(format!("{}: {e}", a[2])))?;
    let walk = plan["walk"]
        .as_array()
        .ok_or_else(|| Error::InvalidRequest(format!("{}: no `walk` array", a[2])))?
        .iter()
        .map(|v| b.require_vertex(v.as_str().unwrap_or("")))
        .collect::<trailprint::Result<Vec<usize>>>()?;
    if walk.len() < 2 {
        return Err(Error::InvalidRequest(
            "basis_probe: a walk of one vertex".into(),
        ));
    }
    let (first, last) = (walk[0], walk[walk.len() - 1]);
    let p = trailprint::plan::Problem::new(b.clone(), kernel, model, first, last, 1e9)?;
    p.utility(&walk)?;
    let t0 = Instant::now();
    let exact = p.utility(&walk)?;
    println!(
        "exact {exact:.9} ({:.3} ms, a whole evaluation)",
        t0.elapsed().as_secs_f64() * 1e3
    );

    let vp: Vec<Point> = b.vertices.iter().map(|v| v.pos).collect();
    let nv = vp.len();
    let pilot = b.pilot_points();
    let nd = pilot.len();
    let am = DMatrix::from_fn(nv, nv, |i, j| {
        kernel.k(&vp[i], &vp[j]) + if i == j { kernel.sn2 } else { 0.0 }
    });
    let l = am
        .cholesky()
        .ok_or_else(|| Error::Numerical("K_VV + sn2 I".into()))?
        .l();
    let solve = |k: DMatrix<f64>| {
        l.solve_lower_triangular(&k)
            .ok_or_else(|| Error::Numerical("triangular solve".into()))
    };
    let gd = solve(DMatrix::from_fn(nv, nd, |i, j| kernel.k(&vp[i], &pilot[j])))?;
    let mut index = HashMap::new();
    let mut edges = Vec::new();
    for e in &b.edges {
        let key = (e.a.min(e.b), e.a.max(e.b));
        index.entry(key).or_insert_with(|| {
            edges.push(key);
            edges.len() - 1
        });
    }
    let samples = sample_walk(&b, &walk, &model, &kernel)?;
    let places = sample_places(&vp, &walk, &samples, &index);
    let pts: Vec<(Point, f64)> = pilot
        .iter()
        .map(|&q| (q, 0.0))
        .chain(samples.iter().map(|s| (s.pos, s.extra_noise)))
        .collect();

    for m in [4usize, 5, 6] {
        let nodes: Vec<f64> = (0..m)
            .map(|k| 0.5 - 0.5 * ((2 * k + 1) as f64 * std::f64::consts::PI / (2 * m) as f64).cos())
            .collect();
        let t0 = Instant::now();
        let nn = edges.len() * m;
        let vpr = &vp;
        let node_pts: Vec<Point> = edges
            .iter()
            .flat_map(|&(u, v)| {
                nodes
                    .iter()
                    .map(move |&t| point_on_edge(&vpr[u], &vpr[v], t))
            })
            .collect();
        let gn = solve(DMatrix::from_fn(nv, nn, |i, j| {
            kernel.k(&vp[i], &node_pts[j])
        }))?;
        let t_solve = t0.elapsed();
        let basis = Basis {
            m,
            h: gn.transpose() * &gn,
            hd: gn.transpose() * &gd,
            hdd: gd.transpose() * &gd,
            nd,
        };
        let t_gram = t0.elapsed() - t_solve;
        let weights: Vec<(usize, Vec<f64>)> = places
            .iter()
            .map(|&(e, f)| (e, lagrange(&nodes, f)))
            .collect();
        let mut best = f64::INFINITY;
        let mut value = 0.0;
        for _ in 0..5 {
            let t1 = Instant::now();
            value = basis.utility(&kernel, &pts, &weights)?;
            best = best.min(t1.elapsed().as_secs_f64());
        }
        println!(
            "m {m}: {value:.9} error {:.3e} (relative {:.3e}); {nn} nodes, solve {:.0} ms, \
             Gram {:.0} ms ({} MiB); one evaluation {:.3} ms",
            value - exact,
            (value - exact) / exact,
            t_solve.as_secs_f64() * 1e3,
            t_gram.as_secs_f64() * 1e3,
            (nn * nn * 8) >> 20,
            best * 1e3
        );
    }
    Ok(())
}

/// The Gram matrices of the solved node columns `G_N = L^-1 K_VN` and pilot columns
/// `G_D`: `h = G_N^T G_N`, `hd = G_N^T G_D`, `hdd = G_D^T G_D`.
struct Basis {
    m: usize,
    h: DMatrix<f64>,
    hd: DMatrix<f64>,
    hdd: DMatrix<f64>,
    nd: usize,
}

impl Basis {
    /// `f_D` of the observations `pts` (pilot first, then the samples, whose edges and
    /// interpolation weights `weights` gives): `1/2 (ln det C - ln det (C - Q))`, `C =
    /// K_SS + N_S`, `Q` the basis's `K_SV A^-1 K_VS`.
    fn utility(
        &self,
        kernel: &Kernel,
        pts: &[(Point, f64)],
        weights: &[(usize, Vec<f64>)],
    ) -> trailprint::Result<f64> {
        let (m, nd) = (self.m, self.nd);
        let ns = pts.len();
        let c = DMatrix::from_fn(ns, ns, |i, j| {
            kernel.k(&pts[i].0, &pts[j].0) + if i == j { kernel.sn2 + pts[i].1 } else { 0.0 }
        });
        let q = |i: usize, j: usize| -> f64 {
            let (i, j) = (i.max(j), i.min(j));
            match (i < nd, j < nd) {
                (true, _) => self.hdd[(i, j)],
                (false, true) => {
                    let (e, w) = &weights[i - nd];
                    (0..m).map(|k| w[k] * self.hd[(e * m + k, j)]).sum()
                }
                (false, false) => {
                    let ((e1, w1), (e2, w2)) = (&weights[i - nd], &weights[j - nd]);
                    (0..m)
                        .map(|k1| {
                            let row: f64 = (0..m)
                                .map(|k2| self.h[(e1 * m + k1, e2 * m + k2)] * w2[k2])
                                .sum();
                            w1[k1] * row
                        })
                        .sum()
                }
            }
        };
        let post = DMatrix::from_fn(ns, ns, |i, j| c[(i, j)] - q(i, j));
        let ld = |x: DMatrix<f64>, what: &str| {
            x.cholesky()
                .map(|f| f.ln_determinant())
                .ok_or_else(|| Error::Numerical(format!("{what} is not positive definite")))
        };
        Ok(0.5 * (ld(c, "K_SS + N_S")? - ld(post, "the basis's posterior")?))
    }
}

/// Each sample's edge (index into the building's edges, ends in increasing order) and
/// fraction along it from the lower end, from its arc length along `walk`.
fn sample_places(
    vp: &[Point],
    walk: &[usize],
    samples: &[trailprint::samples::Sample],
    index: &HashMap<(usize, usize), usize>,
) -> Vec<(usize, f64)> {
    let mut cum = vec![0.0];
    for w in walk.windows(2) {
        let (p, q) = (vp[w[0]], vp[w[1]]);
        cum.push(cum[cum.len() - 1] + (p.x - q.x).hypot(p.y - q.y));
    }
    samples
        .iter()
        .map(|s| {
            let mut k = cum
                .partition_point(|&c| c <= s.arc)
                .saturating_sub(1)
                .min(walk.len() - 2);
            while k + 2 < cum.len() && cum[k + 1] - cum[k] < 1e-12 {
                k += 1;
            }
            let len = cum[k + 1] - cum[k];
            let f = if len > 0.0 {
                ((s.arc - cum[k]) / len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (u, v) = (walk[k], walk[k + 1]);
            let (key, f) = if u < v {
                ((u, v), f)
            } else {
                ((v, u), 1.0 - f)
            };
            (index.get(&key).copied().unwrap_or(0), f)
        })
        .collect()
}

/// Lagrange interpolation weights of the point `f` on the nodes `nodes`.
fn lagrange(nodes: &[f64], f: f64) -> Vec<f64> {
    (0..nodes.len())
        .map(|k| {
            (0..nodes.len())
                .filter(|&j| j != k)
                .map(|j| (f - nodes[j]) / (nodes[k] - nodes[j]))
                .product()
        })
        .collect()
}
