//! Hyperparameter fit on pilot data (SPEC section 2).
//!
//! One kernel is shared by all access points. Each access point's RSS is centred on its
//! own sample mean; access points heard at fewer than half of the pilot locations are left
//! out; a missing reading of a kept access point is the floor value -100 dBm. The fit
//! maximises the sum over access points of the GP log marginal likelihood over
//! `(ln sf2, ln ell, ln sn2)`, by Nelder-Mead from several starts, within
//! `sn2 >= 1 dB²` and `0.5 m <= ell <= 1000 m` (and `1e-2 <= sf2 <= 1e5 dB²`).
//!
//! # When no access point is heard at half the locations
//! SPEC 2's rule then keeps nothing and leaves the fit undefined. That is the rule's
//! common case on a large floor, not a fault of the data: an access point is heard some
//! tens of metres around it, so on a 400 m corridor (`trailprint generate --rooms 40
//! --corridor-length 400`, 20 pilot locations, 10 access points) none is heard at half of
//! them. Rather than refuse, the fit then takes each access point heard at
//! [`HEARD_ONLY_MIN`] locations or more on *the locations that hear it* (its readings
//! centred on their own mean, no floor value): the likelihood of what was observed, with
//! the same shared kernel ([`ApRule::HeardOnly`], reported with the fit). Decision record
//! `docs/decisions/0007-fit-on-large-floors.md` has the reasons and what it gives.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::building::Fingerprint;
use crate::gp::{Kernel, Point};
use crate::{Error, Result};

/// RSS given to a kept access point that was not heard at a location, dBm.
pub const MISSING_RSS: f64 = -100.0;

/// Fewest pilot locations an access point must be heard at to enter a
/// [`ApRule::HeardOnly`] fit: with fewer, its readings say next to nothing about a length
/// scale.
pub const HEARD_ONLY_MIN: usize = 4;

/// Bounds of the fit, as `(min, max)` of each parameter.
pub const SF2_BOUNDS: (f64, f64) = (1e-2, 1e5);
pub const ELL_BOUNDS: (f64, f64) = (0.5, 1000.0);
pub const SN2_BOUNDS: (f64, f64) = (1.0, 1e4);

/// Which access points a fit used, and on which locations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ApRule {
    /// SPEC 2: those heard at half the pilot locations or more, on every location (-100
    /// dBm where not heard).
    #[default]
    HalfOfLocations,
    /// When SPEC 2's rule keeps none: each access point heard at [`HEARD_ONLY_MIN`]
    /// locations or more, on the locations that hear it (see the module docs).
    HeardOnly,
}

impl ApRule {
    /// What the rule says, for people.
    pub fn describe(self) -> &'static str {
        match self {
            ApRule::HalfOfLocations => "heard at half the pilot locations or more (SPEC 2)",
            ApRule::HeardOnly => {
                "none heard at half the pilot locations: each on the locations that hear it"
            }
        }
    }
}

/// The result of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitResult {
    pub kernel: Kernel,
    /// Summed log marginal likelihood at the optimum (nats).
    pub log_likelihood: f64,
    /// The access points that entered the fit, sorted.
    pub aps_used: Vec<String>,
    /// How they were chosen.
    #[serde(default)]
    pub ap_rule: ApRule,
    /// Number of pilot locations.
    pub locations: usize,
}

/// Pilot locations and the centred readings of the access points fitted on them.
#[derive(Debug, Clone)]
pub struct Group {
    pub points: Vec<Point>,
    /// One centred vector per access point, over `points`.
    pub centred: Vec<DVector<f64>>,
}

/// The per-access-point data the likelihood is computed on.
#[derive(Debug, Clone)]
pub struct PilotData {
    /// Every pilot location.
    pub points: Vec<Point>,
    pub aps: Vec<String>,
    pub rule: ApRule,
    /// Under [`ApRule::HalfOfLocations`] one group (every location, every kept access
    /// point); under [`ApRule::HeardOnly`] one per access point.
    pub groups: Vec<Group>,
}

impl PilotData {
    /// Selects access points and centres their readings as SPEC section 2 says (or, when
    /// that keeps none, as [`ApRule::HeardOnly`] does).
    pub fn from_fingerprints(pilot: &[Fingerprint]) -> Result<Self> {
        let n = pilot.len();
        if n < 3 {
            return Err(Error::Fit(format!(
                "need pilot data at 3 or more locations, the building has {n}"
            )));
        }
        let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
        for fp in pilot {
            for ap in fp.rss.keys() {
                *counts.entry(ap.as_str()).or_default() += 1;
            }
        }
        let points: Vec<Point> = pilot.iter().map(Fingerprint::point).collect();
        let centre = |y: Vec<f64>| {
            let y = DVector::from_vec(y);
            let mean = y.mean();
            y.add_scalar(-mean)
        };
        let half: Vec<String> = counts
            .iter()
            .filter(|(_, c)| 2 * **c >= n)
            .map(|(ap, _)| ap.to_string())
            .collect();
        let (aps, rule, groups) = if !half.is_empty() {
            let centred = half
                .iter()
                .map(|ap| {
                    centre(
                        pilot
                            .iter()
                            .map(|fp| fp.rss.get(ap).copied().unwrap_or(MISSING_RSS))
                            .collect(),
                    )
                })
                .collect();
            let g = Group {
                points: points.clone(),
                centred,
            };
            (half, ApRule::HalfOfLocations, vec![g])
        } else {
            let heard: Vec<String> = counts
                .iter()
                .filter(|(_, c)| **c >= HEARD_ONLY_MIN)
                .map(|(ap, _)| ap.to_string())
                .collect();
            if heard.is_empty() {
                let most = counts.values().copied().max().unwrap_or(0);
                return Err(Error::Fit(format!(
                    "no access point is heard at half or more of the {n} pilot locations \
                     ({} access points heard in all), nor at {HEARD_ONLY_MIN} or more of them \
                     (the most: {most}): survey more pilot locations near the access points, \
                     or give the kernel (sf2, ell, sn2) yourself",
                    counts.len()
                )));
            }
            let groups = heard
                .iter()
                .map(|ap| {
                    let (pts, y): (Vec<Point>, Vec<f64>) = pilot
                        .iter()
                        .filter_map(|fp| fp.rss.get(ap).map(|&r| (fp.point(), r)))
                        .unzip();
                    Group {
                        points: pts,
                        centred: vec![centre(y)],
                    }
                })
                .collect();
            (heard, ApRule::HeardOnly, groups)
        };
        if groups
            .iter()
            .flat_map(|g| &g.centred)
            .all(|y| y.norm_squared() < 1e-12)
        {
            return Err(Error::Fit(
                "every kept access point reads the same RSS at every pilot location: no spatial variation to fit".into(),
            ));
        }
        Ok(PilotData {
            points,
            aps,
            rule,
            groups,
        })
    }

    /// Every centred reading vector, over all groups.
    pub fn centred(&self) -> impl Iterator<Item = &DVector<f64>> {
        self.groups.iter().flat_map(|g| &g.centred)
    }

    /// Summed log marginal likelihood of all access points under `kernel`: SPEC 2's, of
    /// the centred readings; under [`ApRule::HeardOnly`] the restricted likelihood
    /// ([`restricted_log_likelihood`]) of each access point's readings.
    pub fn log_likelihood(&self, kernel: &Kernel) -> Option<f64> {
        let mut total = 0.0;
        for g in &self.groups {
            let n = g.points.len();
            let k = DMatrix::from_fn(n, n, |i, j| {
                kernel.k(&g.points[i], &g.points[j]) + if i == j { kernel.sn2 } else { 0.0 }
            });
            total += match self.rule {
                ApRule::HalfOfLocations => {
                    let (quad, logdet) =
                        crate::utility::reference::quad_and_logdet(&k, &g.centred)?;
                    let a = g.centred.len() as f64;
                    -0.5 * quad
                        - 0.5 * a * logdet
                        - 0.5 * a * n as f64 * (2.0 * std::f64::consts::PI).ln()
                }
                ApRule::HeardOnly => g
                    .centred
                    .iter()
                    .map(|y| restricted_log_likelihood(&k, y))
                    .sum::<Option<f64>>()?,
            };
        }
        Some(total)
    }
}

/// The restricted (REML) log likelihood of readings `y` under covariance `k` with an
/// unknown constant mean: the likelihood of `y`'s contrasts, which no mean shifts,
///
/// `-1/2 (y' K^-1 y - (1' K^-1 y)^2 / 1' K^-1 1) - 1/2 ln det K - 1/2 ln(1' K^-1 1)
///  - (n - 1)/2 ln 2 pi`.
///
/// Why not SPEC 2's likelihood of the readings centred on their sample mean: an access
/// point heard only on a stretch of a few length scales loses most of its variance to
/// that centring, and the fit then reads short, weak correlation (readings drawn from
/// `sf2 = 40, ell = 6 m, sn2 = 4`, each access point heard on 12 to 45 m of a 135 m
/// line: 33.2, 3.5 m, 1.07 by centring; the restricted likelihood recovers it, see the
/// tests). `None` when `k` is not positive definite.
fn restricted_log_likelihood(k: &DMatrix<f64>, y: &DVector<f64>) -> Option<f64> {
    let n = y.len();
    let l = k.clone().cholesky()?;
    let kinv_y = l.solve(y);
    let kinv_1 = l.solve(&DVector::from_element(n, 1.0));
    let one_k_one = kinv_1.sum();
    if one_k_one <= 0.0 || !one_k_one.is_finite() {
        return None;
    }
    let quad = y.dot(&kinv_y) - kinv_y.sum().powi(2) / one_k_one;
    let logdet = 2.0 * l.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
    Some(
        -0.5 * quad
            - 0.5 * logdet
            - 0.5 * one_k_one.ln()
            - 0.5 * (n as f64 - 1.0) * (2.0 * std::f64::consts::PI).ln(),
    )
}

fn clamp_params(z: [f64; 3]) -> [f64; 3] {
    [
        z[0].clamp(SF2_BOUNDS.0.ln(), SF2_BOUNDS.1.ln()),
        z[1].clamp(ELL_BOUNDS.0.ln(), ELL_BOUNDS.1.ln()),
        z[2].clamp(SN2_BOUNDS.0.ln(), SN2_BOUNDS.1.ln()),
    ]
}

fn kernel_of(z: [f64; 3]) -> Kernel {
    let z = clamp_params(z);
    Kernel::new(z[0].exp(), z[1].exp(), z[2].exp())
}

/// Nelder-Mead minimisation of `f` from `x0` with initial step `step`; returns the best
/// point and value. Deterministic.
fn nelder_mead(
    f: &dyn Fn([f64; 3]) -> f64,
    x0: [f64; 3],
    step: f64,
    max_evals: usize,
) -> ([f64; 3], f64) {
    let mut simplex: Vec<([f64; 3], f64)> = Vec::with_capacity(4);
    simplex.push((x0, f(x0)));
    for d in 0..3 {
        let mut x = x0;
        x[d] += step;
        simplex.push((x, f(x)));
    }
    let mut evals = 4;
    let lerp = |a: &[f64; 3], b: &[f64; 3], t: f64| -> [f64; 3] {
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
        ]
    };
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let spread = simplex[3].1 - simplex[0].1;
        let size = (0..3)
            .map(|d| (simplex[3].0[d] - simplex[0].0[d]).abs())
            .fold(0.0, f64::max);
        if spread.abs() < 1e-10 && size < 1e-7 {
            break;
        }
        let mut centroid = [0.0; 3];
        for (x, _) in &simplex[..3] {
            for d in 0..3 {
                centroid[d] += x[d] / 3.0;
            }
        }
        let worst = simplex[3].0;
        let xr = lerp(&centroid, &worst, -1.0);
        let fr = f(xr);
        evals += 1;
        if fr < simplex[0].1 {
            let xe = lerp(&centroid, &worst, -2.0);
            let fe = f(xe);
            evals += 1;
            simplex[3] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[2].1 {
            simplex[3] = (xr, fr);
        } else {
            let (xc, fc) = if fr < simplex[3].1 {
                let xc = lerp(&centroid, &xr, 0.5);
                (xc, f(xc))
            } else {
                let xc = lerp(&centroid, &worst, 0.5);
                (xc, f(xc))
            };
            evals += 1;
            if fc < simplex[3].1.min(fr) {
                simplex[3] = (xc, fc);
            } else {
                let best = simplex[0].0;
                for s in simplex.iter_mut().skip(1) {
                    s.0 = lerp(&best, &s.0, 0.5);
                    s.1 = f(s.0);
                    evals += 1;
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex[0]
}

/// Fits `(sf2, ell, sn2)` on pilot fingerprints.
pub fn fit_kernel(pilot: &[Fingerprint]) -> Result<FitResult> {
    let data = PilotData::from_fingerprints(pilot)?;
    fit_pilot_data(&data)
}

/// Fits on prepared pilot data (see [`PilotData::from_fingerprints`]).
pub fn fit_pilot_data(data: &PilotData) -> Result<FitResult> {
    let objective = |z: [f64; 3]| -> f64 {
        // Outside the box the clamped kernel is used plus a penalty, so that the simplex
        // is pulled back and the optimum can sit exactly on a bound.
        let c = clamp_params(z);
        let penalty: f64 = (0..3).map(|d| (z[d] - c[d]).powi(2)).sum::<f64>() * 1e3;
        match data.log_likelihood(&kernel_of(z)) {
            Some(ll) if ll.is_finite() => -ll + penalty,
            _ => f64::INFINITY,
        }
    };
    // Starts: the data's variance for sf2, a spread of length scales relative to the
    // extent of the pilot locations, and a few noise levels.
    let var = data
        .centred()
        .map(|y| y.norm_squared() / y.len() as f64)
        .sum::<f64>()
        / data.centred().count() as f64;
    let extent = super::Extent::of(data.points.iter().map(|p| (p.x, p.y)))
        .diagonal()
        .max(1.0);
    let mut best: Option<([f64; 3], f64)> = None;
    for ell_frac in [0.1, 0.5, 2.0] {
        for noise_frac in [0.05, 0.3] {
            let z0 = clamp_params([
                var.max(1e-2).ln(),
                (extent * ell_frac).ln(),
                (var * noise_frac).max(1.0).ln(),
            ]);
            let (mut z, mut fz) = nelder_mead(&objective, z0, 0.7, 600);
            // Restart from the optimum until it stops improving (Nelder-Mead can stall).
            for _ in 0..5 {
                let (z2, f2) = nelder_mead(&objective, z, 0.2, 400);
                let improved = f2 < fz - 1e-9;
                if f2 <= fz {
                    z = z2;
                    fz = f2;
                }
                if !improved {
                    break;
                }
            }
            if best.is_none_or(|(_, fb)| fz < fb) {
                best = Some((z, fz));
            }
        }
    }
    let (z, _) = best.ok_or_else(|| Error::Fit("optimiser found no finite likelihood".into()))?;
    let kernel = kernel_of(z);
    let log_likelihood = data
        .log_likelihood(&kernel)
        .filter(|v| v.is_finite())
        .ok_or_else(|| Error::Fit("the likelihood is not finite at the optimum".into()))?;
    Ok(FitResult {
        kernel,
        log_likelihood,
        aps_used: data.aps.clone(),
        ap_rule: data.rule,
        locations: data.points.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn fp(x: f64, y: f64, rss: &[(&str, f64)]) -> Fingerprint {
        Fingerprint {
            x,
            y,
            floor: 0,
            rss: rss.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        }
    }

    #[test]
    fn access_points_heard_at_fewer_than_half_are_left_out() {
        let pilot = vec![
            fp(0.0, 0.0, &[("a", -50.0), ("b", -60.0)]),
            fp(5.0, 0.0, &[("a", -55.0)]),
            fp(10.0, 0.0, &[("a", -65.0), ("c", -70.0)]),
            fp(15.0, 0.0, &[("a", -70.0), ("b", -80.0)]),
        ];
        let d = PilotData::from_fingerprints(&pilot).expect("data");
        assert_eq!(d.aps, vec!["a".to_string(), "b".to_string()]);
        // b is missing at two locations: -100 there, then centred on its mean of -85.
        assert_eq!(d.rule, ApRule::HalfOfLocations);
        let b: Vec<f64> = d.groups[0].centred[1].iter().copied().collect();
        assert_eq!(b, vec![25.0, -15.0, -15.0, 5.0]);
    }

    #[test]
    fn unsupported_pilot_data_gives_clear_errors() {
        let line = |aps: [&str; 3]| -> Vec<Fingerprint> {
            (0..3)
                .map(|i| fp(i as f64, 0.0, &[(aps[i], -50.0)]))
                .collect()
        };
        let cases = [
            (
                vec![fp(0.0, 0.0, &[("a", -50.0)])],
                "need pilot data at 3 or more locations, the building has 1",
            ),
            (
                line(["a", "b", "c"]),
                "no access point is heard at half or more of the 3 pilot locations (3 access \
                 points heard in all), nor at 4 or more of them (the most: 1)",
            ),
            (line(["a", "a", "a"]), "no spatial variation"),
        ];
        for (pilot, want) in cases {
            let e = fit_kernel(&pilot).expect_err(want);
            assert!(e.to_string().contains(want), "{e}");
        }
    }

    /// Draws `aps` independent GP samples at `n` random locations and fits them.
    ///
    /// With A independent replicates the MLE's standard error shrinks like 1/sqrt(A);
    /// at A = 150 replicates of 60 locations, a parametric bootstrap of this set-up gives
    /// relative standard deviations of about 4% (sf2), 6% (ell) and 3% (sn2), so a 20%
    /// tolerance is over three standard errors and still catches a wrong likelihood
    /// (a missing 1/2, a wrong centring, a noise term left out all move the estimate far more).
    #[test]
    fn fit_recovers_known_hyperparameters() {
        use rand::RngExt;
        let truth = Kernel::new(40.0, 6.0, 4.0);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 60;
        let pts: Vec<Point> = (0..n)
            .map(|_| Point::new(rng.random_range(0.0..30.0), rng.random_range(0.0..20.0), 0))
            .collect();
        let draw = gp_draws(&truth, &pts);
        let aps = 150;
        let mut pilot: Vec<Fingerprint> = pts.iter().map(|p| fp(p.x, p.y, &[])).collect();
        for a in 0..aps {
            let y = draw(&mut rng);
            for (i, f) in pilot.iter_mut().enumerate() {
                f.rss.insert(format!("ap{a:03}"), -60.0 + y[i]);
            }
        }
        let fit = fit_kernel(&pilot).expect("fit");
        assert_eq!(fit.aps_used.len(), aps);
        assert_within_a_fifth(&fit.kernel, &truth);
        // The optimum is at least as likely as the truth (centring costs a little).
        let d = PilotData::from_fingerprints(&pilot).expect("data");
        assert!(fit.log_likelihood >= d.log_likelihood(&truth).expect("ll") - 1e-6);
    }

    /// A large floor: every access point is heard only on a stretch of a third or less of
    /// the pilot locations, so SPEC 2's rule keeps none. The heard-only fit takes each on
    /// its own stretch and still recovers the kernel the readings were drawn from (the
    /// same 20% as above; each access point's few locations make it noisier, hence more
    /// of them).
    #[test]
    fn on_a_large_floor_each_access_point_is_fitted_where_it_is_heard() {
        use rand::RngExt;
        let truth = Kernel::new(40.0, 6.0, 4.0);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 90;
        let pts: Vec<Point> = (0..n)
            .map(|i| {
                Point::new(
                    i as f64 * 1.5 + rng.random_range(0.0..1.0),
                    rng.random_range(0.0..6.0),
                    0,
                )
            })
            .collect();
        let draw = gp_draws(&truth, &pts);
        let mut pilot: Vec<Fingerprint> = pts.iter().map(|p| fp(p.x, p.y, &[])).collect();
        let aps = 400;
        let mut heard_at = Vec::new();
        for a in 0..aps {
            let y = draw(&mut rng);
            let len = rng.random_range(8..=n / 3);
            let from = rng.random_range(0..=n - len);
            for i in from..from + len {
                pilot[i].rss.insert(format!("ap{a:03}"), -60.0 + y[i]);
            }
            heard_at.push(len);
        }
        // One more heard at only three locations: too few to enter.
        for f in pilot.iter_mut().take(3) {
            f.rss.insert("few".into(), -70.0);
        }
        let d = PilotData::from_fingerprints(&pilot).expect("data");
        assert_eq!(d.rule, ApRule::HeardOnly);
        assert_eq!(d.aps.len(), aps, "every access point but `few`");
        assert!(!d.aps.contains(&"few".to_string()));
        // Each group holds exactly the locations that hear its access point, centred.
        for (g, &len) in d.groups.iter().zip(&heard_at) {
            assert_eq!(g.points.len(), len);
            assert!(g.centred[0].sum().abs() < 1e-9);
        }
        let fit = fit_kernel(&pilot).expect("fit");
        assert_eq!(fit.ap_rule, ApRule::HeardOnly);
        assert_within_a_fifth(&fit.kernel, &truth);
        // SPEC 2's rule is still the one used whenever it keeps an access point.
        for f in pilot.iter_mut().take(n / 2) {
            f.rss.insert("wide".into(), -80.0 + f.x / 10.0);
        }
        let d = PilotData::from_fingerprints(&pilot).expect("data");
        assert_eq!(
            (d.rule, d.aps.clone()),
            (ApRule::HalfOfLocations, vec!["wide".to_string()])
        );
    }

    /// Random pilot sets (3 to 30 locations, some at the same spot or on another floor,
    /// 1 to 10 access points each heard at a random subset): the data is never a panic,
    /// SPEC 2's rule is used exactly when an access point is heard at half the locations,
    /// the heard-only rule's groups are the locations that hear each access point, and a
    /// fit, when there is one, is finite and within the bounds.
    #[test]
    fn any_pilot_set_gets_the_rule_it_should_or_a_clear_error() {
        use rand::RngExt;
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (mut half, mut heard_only, mut refused) = (0, 0, 0);
        for case in 0..300 {
            let n = rng.random_range(3..=30usize);
            let aps = rng.random_range(1..=10usize);
            let mut pilot: Vec<Fingerprint> = (0..n)
                .map(|_| {
                    let mut f = fp(
                        rng.random_range(0.0..200.0f64).round(),
                        rng.random_range(0.0..20.0f64).round(),
                        &[],
                    );
                    f.floor = rng.random_range(0..2);
                    f
                })
                .collect();
            let mut counts = vec![0usize; aps];
            for (a, count) in counts.iter_mut().enumerate() {
                let p_heard = rng.random_range(0.0..1.0f64).powi(2);
                for f in pilot.iter_mut() {
                    if rng.random_bool(p_heard) {
                        f.rss
                            .insert(format!("ap{a}"), rng.random_range(-100.0..-30.0));
                        *count += 1;
                    }
                }
            }
            let spec = counts.iter().any(|&c| 2 * c >= n);
            let usable = counts.iter().any(|&c| c >= HEARD_ONLY_MIN);
            match PilotData::from_fingerprints(&pilot) {
                Ok(d) => {
                    let want = if spec {
                        ApRule::HalfOfLocations
                    } else {
                        ApRule::HeardOnly
                    };
                    assert_eq!(d.rule, want, "case {case}: {counts:?} of {n}");
                    let mut sorted = d.aps.clone();
                    sorted.sort();
                    assert_eq!(sorted, d.aps, "case {case}");
                    if d.rule == ApRule::HeardOnly {
                        heard_only += 1;
                        assert_eq!(d.groups.len(), d.aps.len());
                        for (g, ap) in d.groups.iter().zip(&d.aps) {
                            let hears = pilot.iter().filter(|f| f.rss.contains_key(ap)).count();
                            assert!(hears >= HEARD_ONLY_MIN && g.points.len() == hears);
                        }
                    } else {
                        half += 1;
                    }
                    let ll = d.log_likelihood(&Kernel::new(50.0, 8.0, 4.0));
                    assert!(ll.is_some_and(f64::is_finite), "case {case}: {ll:?}");
                    if case % 10 == 0 {
                        let fit = fit_pilot_data(&d).expect("a fit on usable data");
                        let k = fit.kernel;
                        assert!(fit.log_likelihood.is_finite(), "case {case}");
                        assert!(
                            k.sn2 >= SN2_BOUNDS.0 && k.ell >= ELL_BOUNDS.0 && k.ell <= ELL_BOUNDS.1
                        );
                    }
                }
                Err(e) => {
                    refused += 1;
                    let m = e.to_string();
                    assert!(
                        !usable || m.contains("no spatial variation"),
                        "case {case}: {counts:?} of {n} refused: {m}"
                    );
                    assert!(
                        m.contains("no access point is heard")
                            || m.contains("no spatial variation"),
                        "{m}"
                    );
                }
            }
        }
        // Every branch was taken.
        assert!(
            half > 20 && heard_only > 20 && refused > 5,
            "{half} {heard_only} {refused}"
        );
    }

    #[test]
    fn fit_respects_the_noise_floor() {
        // Noise-free smooth data would drive sn2 to 0; the fit stops at 1 dB².
        let pilot: Vec<Fingerprint> = (0..12)
            .map(|i| {
                let x = i as f64 * 2.0;
                fp(x, 0.0, &[("a", -40.0 - 2.0 * x), ("b", -90.0 + 1.5 * x)])
            })
            .collect();
        let fit = fit_kernel(&pilot).expect("fit");
        assert!(
            fit.kernel.sn2 >= 1.0 && fit.kernel.sn2 < 1.0 + 1e-6,
            "{:?}",
            fit.kernel
        );
        assert!(fit.kernel.ell >= 0.5 && fit.kernel.ell <= 1000.0);
    }

    /// Every hyperparameter of `fit` within 20% of `truth`'s.
    fn assert_within_a_fifth(fit: &Kernel, truth: &Kernel) {
        let rel = |a: f64, b: f64| (a - b).abs() / b;
        for (a, b) in [
            (fit.sf2, truth.sf2),
            (fit.ell, truth.ell),
            (fit.sn2, truth.sn2),
        ] {
            assert!(rel(a, b) < 0.2, "{fit:?} against {truth:?}");
        }
    }

    /// Draws of noisy readings at `pts` from a GP with kernel `truth` (zero mean).
    fn gp_draws(truth: &Kernel, pts: &[Point]) -> impl Fn(&mut ChaCha8Rng) -> DVector<f64> {
        let n = pts.len();
        let k = DMatrix::from_fn(n, n, |i, j| {
            truth.k(&pts[i], &pts[j]) + if i == j { truth.sn2 } else { 0.0 }
        });
        let l = k.cholesky().expect("pd").unpack();
        move |rng| &l * DVector::from_iterator(n, (0..n).map(|_| standard_normal(rng)))
    }

    pub(crate) fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
        use rand::RngExt;
        let u1: f64 = rng.random_range(f64::EPSILON..1.0);
        let u2: f64 = rng.random_range(0.0..1.0);
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}
