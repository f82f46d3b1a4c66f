//! Exact utilities of walks near a base walk: where a candidate's observations begin as
//! the base walk's do, the leading block of the base's factorisation is the candidate's
//! too, and only the rest is computed ([`dense::factor_after`]).
//!
//! The S-side form of the dense path ([`super::dense_gain`]) factors the joint matrix
//! ordered `[V, D, obs]` and the observations' own `[D, obs]`. The leading `k x k` block
//! of a Cholesky factor is the factor of the matrix's leading `k x k` block, which for
//! `k = |V| + |D| + c` depends only on the vertices, the prior observations and the first
//! `c` observations. A search that rebuilds a stretch of its walk changes the
//! observations from that stretch on (a person's samples fall by arc length, so the rest
//! of the walk moves too), and every candidate of a batch is drawn from the same walk:
//! each pays for the rows from its first changed observation only. A floor whose
//! observations did not change at all keeps the base's value.
//!
//! The values agree with [`UtilityEngine::utility`] to rounding: the same entries, the
//! same factorisation, only the leading block taken from another one (the tests hold
//! them to 1e-12 relative).

use super::{
    Ctx, DENSE, DENSE_KEEP_MAX, DispatchArg, DispatchOut, Entries, Factor, Prior, UtilityEngine,
    dense, dense_gain, dispatch, keep_dense, s_side_layouts, s_side_logdet,
};
use crate::gp::Point;
use crate::utility::simd::Points;
use crate::{Error, Result};

/// One floor's share of a base walk's factorisation.
#[derive(Debug, Clone)]
pub(super) struct BasePart {
    /// The floor's observations of the base walk (merged, [`super::merge_coincident`]).
    obs: Vec<(Point, f64)>,
    /// Twice the floor's share of the utility.
    gain: f64,
    /// The factored `[D, obs]` and `[V, D, obs]` matrices and their layouts; empty when
    /// the floor took the V side (then a candidate's change is evaluated whole).
    alone: Vec<f64>,
    alone_layout: dense::Layout,
    joint: Vec<f64>,
    joint_layout: dense::Layout,
}

/// A walk whose factorisation the exact utility of walks near it reuses
/// ([`UtilityEngine::near_base`], [`UtilityEngine::utility_near`]).
#[derive(Debug, Clone)]
pub struct NearBase {
    walk: Vec<usize>,
    utility: f64,
    parts: Vec<BasePart>,
}

impl NearBase {
    /// The base walk.
    pub fn walk(&self) -> &[usize] {
        &self.walk
    }

    /// Its exact utility (SPEC 3).
    pub fn utility(&self) -> f64 {
        self.utility
    }

    /// Whether it keeps a factorisation to start from on some floor: on none (every
    /// floor takes the V side, or is too large to keep) a walk near it is evaluated
    /// whole on every floor where it differs, and the base was one evaluation more.
    pub fn reuses(&self) -> bool {
        self.parts.iter().any(|p| !p.joint.is_empty())
    }
}

/// Most doubles a planner lets a [`NearBase`] keep (32 MiB), over all floors
/// ([`UtilityEngine::near_base`]); the large-building search keeps less where the
/// request's memory budget leaves less (`Problem::near_base_max`).
pub const BASE_MAX: usize = DENSE_KEEP_MAX;

/// Whether the dense path takes the S side for `ns` observations (with the prior's).
fn s_side(prior: &Prior, ns: usize) -> bool {
    let known = prior.known as f64;
    prior.known > 0 && known.powi(3) > 1.5 * (ns as f64).powi(3)
}

fn points(obs: &[(Point, f64)]) -> Points {
    let mut rp = Points::default();
    for (p, _) in obs {
        rp.push(p);
    }
    rp
}

/// The base's share of one floor.
#[inline(always)]
pub(super) fn base_part<const FMA: bool>(
    ctx: &Ctx,
    prior: &Prior,
    obs: &[(Point, f64)],
    max: usize,
) -> Option<BasePart> {
    let (alone_layout, joint_layout) = s_side_layouts(ctx, prior, obs);
    let keep = s_side(prior, prior.pts.len() + obs.len())
        && joint_layout.len() + alone_layout.len() <= max;
    if !keep {
        return Some(BasePart {
            obs: obs.to_vec(),
            gain: dense_gain::<FMA>(ctx, prior, obs)?,
            alone: Vec::new(),
            alone_layout,
            joint: Vec::new(),
            joint_layout,
        });
    }
    let rp = points(obs);
    let e = Entries {
        ctx,
        prior,
        obs,
        rp: &rp,
    };
    let mut alone = vec![0.0; alone_layout.len()];
    let mut joint = vec![0.0; joint_layout.len()];
    let ld_s = s_side_logdet::<FMA>(e, &mut alone, alone_layout, 0, false)?;
    let ld_post = s_side_logdet::<FMA>(e, &mut joint, joint_layout, prior.known, true)?;
    Some(BasePart {
        obs: obs.to_vec(),
        gain: ld_s - ld_post,
        alone,
        alone_layout,
        joint,
        joint_layout,
    })
}

/// Copies rows `..k` of `from` (columns `i..k` of row `i`) into `to`.
fn copy_block(from: &[f64], from_ld: usize, to: &mut [f64], to_ld: usize, k: usize) {
    for i in 0..k {
        to[i * to_ld + i..i * to_ld + k].copy_from_slice(&from[i * from_ld + i..i * from_ld + k]);
    }
}

/// Twice one floor's share of the utility of `obs`, from the base's factorisation.
#[inline(always)]
pub(super) fn near_part<const FMA: bool>(
    ctx: &Ctx,
    prior: &Prior,
    obs: &[(Point, f64)],
    base: &BasePart,
) -> Option<f64> {
    let same = |a: &(Point, f64), b: &(Point, f64)| {
        a.0.x.to_bits() == b.0.x.to_bits()
            && a.0.y.to_bits() == b.0.y.to_bits()
            && a.0.floor == b.0.floor
            && a.1.to_bits() == b.1.to_bits()
    };
    let c = obs
        .iter()
        .zip(&base.obs)
        .take_while(|(a, b)| same(a, b))
        .count();
    if c == obs.len() && c == base.obs.len() {
        return Some(base.gain);
    }
    let nd = prior.pts.len();
    if base.joint.is_empty() || !s_side(prior, nd + obs.len()) {
        return dense_gain::<FMA>(ctx, prior, obs);
    }
    let step = dense::KNOWN_STEP;
    let known_alone = (nd + c) / step * step;
    let known_joint = ((ctx.nv + nd + c) / step * step).max(prior.known);
    let (alone_layout, joint_layout) = s_side_layouts(ctx, prior, obs);
    let rp = points(obs);
    let mut a = DENSE.take();
    let need = alone_layout.len().max(joint_layout.len());
    if a.len() < need {
        a.resize(need, 0.0);
    }
    copy_block(
        &base.alone,
        base.alone_layout.ld,
        &mut a,
        alone_layout.ld,
        known_alone,
    );
    let e = Entries {
        ctx,
        prior,
        obs,
        rp: &rp,
    };
    let ld_s = s_side_logdet::<FMA>(e, &mut a, alone_layout, known_alone, false);
    let ld_post = ld_s.and_then(|_| {
        copy_block(
            &base.joint,
            base.joint_layout.ld,
            &mut a,
            joint_layout.ld,
            known_joint,
        );
        s_side_logdet::<FMA>(e, &mut a, joint_layout, known_joint, true)
    });
    keep_dense(a);
    Some(ld_s? - ld_post?)
}

impl UtilityEngine {
    /// `walk` as a base for [`utility_near`](Self::utility_near): its exact utility
    /// (the same as [`utility`](Self::utility)) and its factorisation, about one dense
    /// matrix per floor, at most `max` doubles in all (a floor whose share of `max`
    /// cannot hold its matrices keeps none: a walk near the base is evaluated whole
    /// there).
    pub fn near_base(&self, walk: &[usize], max: usize) -> Result<NearBase> {
        let obs = self.walk_observations(walk)?;
        let mut parts = Vec::with_capacity(self.parts.len());
        let mut gain = 0.0;
        for (part, obs) in self.parts.iter().zip(self.per_part(&obs)) {
            let mut unused = Factor::default();
            match dispatch(
                self.isa,
                &mut unused,
                &part.ctx,
                DispatchArg::NearBase(&part.prior, &obs, max / self.parts.len()),
            ) {
                DispatchOut::Base(Some(b)) => {
                    gain += b.gain;
                    parts.push(b);
                }
                _ => return Err(not_pd()),
            }
        }
        Ok(NearBase {
            walk: walk.to_vec(),
            utility: (0.5 * gain).max(0.0),
            parts,
        })
    }

    /// The exact utility of `walk` (SPEC 3; as [`utility`](Self::utility) to rounding),
    /// computing only what differs from `base`: the rows from its first observation that
    /// is not the base walk's, on the floors where there is one.
    pub fn utility_near(&self, base: &NearBase, walk: &[usize]) -> Result<f64> {
        if walk == base.walk.as_slice() {
            return Ok(base.utility);
        }
        let obs = self.walk_observations(walk)?;
        let mut gain = 0.0;
        for ((part, obs), b) in self.parts.iter().zip(self.per_part(&obs)).zip(&base.parts) {
            let mut unused = Factor::default();
            match dispatch(
                self.isa,
                &mut unused,
                &part.ctx,
                DispatchArg::Near(&part.prior, &obs, b),
            ) {
                DispatchOut::LogDet(Some(g)) => gain += g,
                _ => return Err(not_pd()),
            }
        }
        Ok((0.5 * gain).max(0.0))
    }
}

fn not_pd() -> Error {
    Error::Numerical("posterior covariance is not positive definite".into())
}
