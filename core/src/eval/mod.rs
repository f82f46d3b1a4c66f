//! Localization evaluation, exactly as SPEC section 5: how well would a fingerprint map
//! built from a walk's samples locate the building's test fingerprints?
//!
//! 1. A world model gives the RSS of every access point anywhere: the per-access-point GP
//!    posterior mean fitted on the building's `dense_survey` ([`WorldModel::from_dense_survey`])
//!    or a synthetic propagation model ([`WorldModel::Synthetic`]). A missing reading is
//!    -100 dBm.
//! 2. Fingerprints are drawn at the sample positions: world mean plus `N(0, sn2)`. Test
//!    fingerprints are the measured `rss` of `test_points` (missing access point: -100 dBm),
//!    drawn the same way where a test point has no `rss`.
//! 3. One GP per access point (one shared Cholesky) on samples plus pilot data predicts
//!    mean and variance on a reference grid ([`reference_grid`]).
//! 4. A test fingerprint is located at the grid point of highest likelihood (sum over
//!    access points of the Gaussian log density with variance = predictive variance +
//!    `sn2`); the error is the planar distance plus 4 m per floor of difference.
//!
//! [`Evaluator`] holds everything that depends on the building only (world model, grid,
//! test fingerprints) so that an experiment loop pays for it once; [`evaluate`] is the
//! one-shot form.

use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;

use crate::building::{Building, Fingerprint};
use crate::gp::predict::GpModel;
use crate::gp::{Extent, Kernel, Point};
use crate::samples::Sample;
use crate::synth::PropagationModel;
use crate::synth::random::{normal, stream_rng};
use crate::{Error, Result};

/// RSS that stands for "not heard", dBm (SPEC section 2 and 5).
pub const MISSING_DBM: f64 = -100.0;

// ChaCha streams of the evaluation seed.
const STREAM_TEST: u64 = 11;
const STREAM_SAMPLES: u64 = 12;

/// Options of the evaluation; the defaults are those of SPEC section 5.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EvalOptions {
    /// Spacing of the reference grid, metres.
    pub grid_step_m: f64,
    /// Grid points farther than this from every edge of their floor are dropped, metres.
    pub grid_margin_m: f64,
    /// Error added per floor of difference, metres.
    pub floor_penalty_m: f64,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            grid_step_m: 0.5,
            grid_margin_m: 1.5,
            floor_penalty_m: 4.0,
        }
    }
}

impl EvalOptions {
    fn validate(&self) -> Result<()> {
        if let Some((name, v)) = crate::error::first_negative([
            ("grid step", self.grid_step_m),
            ("grid margin", self.grid_margin_m),
            ("floor penalty", self.floor_penalty_m),
        ]) {
            return Err(Error::InvalidRequest(format!(
                "evaluation {name} must be a finite number >= 0, got {v}"
            )));
        }
        if self.grid_step_m < 0.01 {
            return Err(Error::InvalidRequest(format!(
                "evaluation grid step must be at least 0.01 m, got {}",
                self.grid_step_m
            )));
        }
        Ok(())
    }
}

/// How a test fingerprint is located on the fingerprint map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Localizer {
    /// The paper's method (SPEC section 5): one GP per access point predicts mean and
    /// variance on the reference grid; the grid point of highest likelihood wins.
    Gp,
    /// Weighted k nearest neighbours in signal space, as most deployed engines do: the
    /// `k` training fingerprints (samples and pilot data) nearest to the test fingerprint
    /// (Euclidean distance over all access points, a missing reading = -100 dBm), weighted
    /// by `1 / (distance + 1 dB)`. The floor is the one of largest total weight (the lower
    /// on a tie) and the position the weighted mean of the neighbours on that floor.
    Knn { k: usize },
}

impl Localizer {
    /// Parses `gp`, `knn` (k = 3) or `knn:K`.
    pub fn parse(s: &str) -> Result<Self> {
        let bad = || {
            Error::InvalidRequest(format!(
                "localizer must be gp, knn or knn:K (K a whole number >= 1), got {s:?}"
            ))
        };
        match s.trim() {
            "gp" => Ok(Localizer::Gp),
            "knn" => Ok(Localizer::Knn { k: 3 }),
            t => {
                let k = t.strip_prefix("knn:").ok_or_else(bad)?;
                let k: usize = k.parse().map_err(|_| bad())?;
                if k == 0 {
                    return Err(bad());
                }
                Ok(Localizer::Knn { k })
            }
        }
    }

    /// `gp` or `knn:K`.
    pub fn name(&self) -> String {
        match self {
            Localizer::Gp => "gp".into(),
            Localizer::Knn { k } => format!("knn:{k}"),
        }
    }
}

/// Softening of the kNN weights, dB: a neighbour at distance 0 weighs 1, not infinity.
const KNN_SOFTENING_DB: f64 = 1.0;

/// Where weighted kNN puts the fingerprint `z` (see [`Localizer::Knn`]); `values` has one
/// row per training fingerprint at `points`.
pub fn knn_locate(z: &[f64], points: &[Point], values: &DMatrix<f64>, k: usize) -> Point {
    let mut d: Vec<(f64, usize)> = (0..points.len())
        .map(|i| {
            let sq: f64 = z
                .iter()
                .enumerate()
                .map(|(a, za)| (za - values[(i, a)]) * (za - values[(i, a)]))
                .sum();
            (sq.sqrt(), i)
        })
        .collect();
    d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    d.truncate(k.max(1));
    let mut floors: Vec<(i64, f64)> = Vec::new();
    for &(dist, i) in &d {
        let w = 1.0 / (dist + KNN_SOFTENING_DB);
        match floors.iter_mut().find(|(f, _)| *f == points[i].floor) {
            Some(e) => e.1 += w,
            None => floors.push((points[i].floor, w)),
        }
    }
    floors.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let floor = floors.first().map_or(0, |f| f.0);
    let (mut x, mut y, mut wsum) = (0.0, 0.0, 0.0);
    for &(dist, i) in d.iter().filter(|(_, i)| points[*i].floor == floor) {
        let w = 1.0 / (dist + KNN_SOFTENING_DB);
        x += w * points[i].x;
        y += w * points[i].y;
        wsum += w;
    }
    Point::new(x / wsum, y / wsum, floor)
}

/// The outcome of one evaluation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LocalizationReport {
    /// Mean localization error over the test points, metres.
    pub mean_error_m: f64,
    /// Median error (mean of the two middle values for an even count), metres.
    pub median_error_m: f64,
    /// 90th percentile (linear interpolation between order statistics), metres.
    pub p90_error_m: f64,
    /// Error per test point, in the building's test-point order, metres.
    pub errors_m: Vec<f64>,
    /// Number of sample positions used (pilot points not included).
    pub samples: usize,
    /// Number of access points.
    pub access_points: usize,
    /// Number of reference grid points.
    pub grid_points: usize,
}

/// Where the "true" RSS comes from.
#[derive(Debug, Clone)]
pub enum WorldModel {
    /// Per-access-point GP posterior mean fitted on a dense survey.
    Survey {
        /// Access-point ids, sorted; columns of the model.
        aps: Vec<String>,
        gp: GpModel,
    },
    /// A synthetic propagation model; means below -100 dBm count as -100 dBm.
    Synthetic(PropagationModel),
}

impl WorldModel {
    /// The GP world model of the building's dense survey: the access points are all
    /// those heard anywhere in it, a missing reading is -100 dBm.
    pub fn from_dense_survey(building: &Building, kernel: &Kernel) -> Result<Self> {
        if building.dense_survey.is_empty() {
            return Err(Error::InvalidRequest(format!(
                "building {:?} has no dense_survey to build the world model from \
                 (use a synthetic propagation model instead)",
                building.name
            )));
        }
        let aps = heard_aps(&building.dense_survey);
        let (points, values) = fingerprint_matrix(&building.dense_survey, &aps);
        let gp = GpModel::fit(kernel, &points, &values).map_err(|e| {
            Error::InvalidRequest(format!(
                "building {:?}: the world model is a GP on its {} dense_survey points: {e} \
                 (`trailprint generate --dense-spacing` sets how dense a generated survey is)",
                building.name,
                points.len()
            ))
        })?;
        Ok(WorldModel::Survey { aps, gp })
    }

    /// Access-point ids, in column order.
    pub fn ap_ids(&self) -> Vec<String> {
        match self {
            WorldModel::Survey { aps, .. } => aps.clone(),
            WorldModel::Synthetic(m) => m.access_points().iter().map(|a| a.id.clone()).collect(),
        }
    }

    /// Mean RSS at the points, one row per point, one column per access point.
    pub fn mean(&self, points: &[Point]) -> DMatrix<f64> {
        match self {
            WorldModel::Survey { gp, .. } => gp.mean(points),
            WorldModel::Synthetic(m) => {
                let rows: Vec<Vec<f64>> = points.par_iter().map(|p| m.mean_rss_all(p)).collect();
                let n_ap = m.access_points().len();
                DMatrix::from_fn(points.len(), n_ap, |i, a| rows[i][a].max(MISSING_DBM))
            }
        }
    }
}

/// Sorted ids of all access points heard in the fingerprints.
fn heard_aps(fps: &[Fingerprint]) -> Vec<String> {
    let set: std::collections::BTreeSet<&String> = fps.iter().flat_map(|f| f.rss.keys()).collect();
    set.into_iter().cloned().collect()
}

/// Positions and the RSS matrix (rows: fingerprints, columns: `aps`, missing = -100).
fn fingerprint_matrix(fps: &[Fingerprint], aps: &[String]) -> (Vec<Point>, DMatrix<f64>) {
    let points = fps.iter().map(Fingerprint::point).collect();
    let values = DMatrix::from_fn(fps.len(), aps.len(), |i, a| {
        fps[i].rss.get(&aps[a]).copied().unwrap_or(MISSING_DBM)
    });
    (points, values)
}

/// Distance from `p` to the segment `a b` (plan view).
fn segment_distance(p: &Point, a: &Point, b: &Point) -> f64 {
    p.segment_projection(a, b).1
}

/// The reference grid of SPEC section 5: for every floor, points `step` apart over the
/// bounding box of that floor's vertices, kept when within `margin` of an edge of the same
/// floor (or of a vertex, for a floor without edges). Floors in building order, points
/// row by row (y, then x).
pub fn reference_grid(building: &Building, step: f64, margin: f64) -> Vec<Point> {
    let mut out = Vec::new();
    for floor in &building.floors {
        let verts: Vec<Point> = building
            .vertices
            .iter()
            .map(|v| v.pos)
            .filter(|p| p.floor == floor.id)
            .collect();
        if verts.is_empty() {
            continue;
        }
        let segs: Vec<(Point, Point)> = building
            .edges
            .iter()
            .map(|e| (building.vertices[e.a].pos, building.vertices[e.b].pos))
            .filter(|(a, b)| a.floor == floor.id && b.floor == floor.id)
            .collect();
        let Extent { x0, y0, x1, y1 } = Extent::of(verts.iter().map(|p| (p.x, p.y)));
        let nx = ((x1 - x0) / step + 1e-9).floor() as usize + 1;
        let ny = ((y1 - y0) / step + 1e-9).floor() as usize + 1;
        for j in 0..ny {
            for i in 0..nx {
                let p = Point::new(x0 + i as f64 * step, y0 + j as f64 * step, floor.id);
                let near = segs
                    .iter()
                    .any(|(a, b)| segment_distance(&p, a, b) <= margin + 1e-9)
                    || verts.iter().any(|v| v.planar_distance(&p) <= margin + 1e-9);
                if near {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// Everything of an evaluation that depends on the building and kernel only.
#[derive(Debug, Clone)]
pub struct Evaluator {
    kernel: Kernel,
    options: EvalOptions,
    world: WorldModel,
    aps: Vec<String>,
    grid: Vec<Point>,
    pilot_points: Vec<Point>,
    /// Pilot RSS, rows: pilot points, columns: `aps`.
    pilot_values: DMatrix<f64>,
    test_points: Vec<Point>,
    /// Measured test fingerprints (`None`: drawn from the world model at each evaluation).
    test_measured: Vec<Option<Vec<f64>>>,
    /// World mean at the test points (used for the drawn ones).
    test_world: DMatrix<f64>,
}

impl Evaluator {
    /// Prepares an evaluation with the dense-survey world model.
    pub fn new(building: &Building, kernel: &Kernel, options: EvalOptions) -> Result<Self> {
        kernel.validate("evaluation kernel")?;
        let world = WorldModel::from_dense_survey(building, kernel)?;
        Self::with_world(building, kernel, world, options)
    }

    /// Prepares an evaluation against the given world model.
    pub fn with_world(
        building: &Building,
        kernel: &Kernel,
        world: WorldModel,
        options: EvalOptions,
    ) -> Result<Self> {
        kernel.validate("evaluation kernel")?;
        options.validate()?;
        if building.test_points.is_empty() {
            return Err(Error::InvalidRequest(format!(
                "building {:?} has no test_points to evaluate localization on",
                building.name
            )));
        }
        let aps = world.ap_ids();
        if aps.is_empty() {
            return Err(Error::InvalidRequest(format!(
                "building {:?}: the world model has no access points",
                building.name
            )));
        }
        let grid = reference_grid(building, options.grid_step_m, options.grid_margin_m);
        if grid.is_empty() {
            return Err(Error::InvalidRequest(format!(
                "building {:?}: the reference grid is empty",
                building.name
            )));
        }
        let (pilot_points, pilot_values) = fingerprint_matrix(&building.pilot, &aps);
        let test_points: Vec<Point> = building
            .test_points
            .iter()
            .map(Fingerprint::point)
            .collect();
        let test_measured = building
            .test_points
            .iter()
            .map(|t| {
                (!t.rss.is_empty()).then(|| {
                    aps.iter()
                        .map(|a| t.rss.get(a).copied().unwrap_or(MISSING_DBM))
                        .collect()
                })
            })
            .collect();
        let test_world = world.mean(&test_points);
        Ok(Evaluator {
            kernel: *kernel,
            options,
            world,
            aps,
            grid,
            pilot_points,
            pilot_values,
            test_points,
            test_measured,
            test_world,
        })
    }

    /// The access points, in column order.
    pub fn access_points(&self) -> &[String] {
        &self.aps
    }

    /// The reference grid.
    pub fn grid(&self) -> &[Point] {
        &self.grid
    }

    /// The world model.
    pub fn world(&self) -> &WorldModel {
        &self.world
    }

    /// Localization error when the fingerprint map is built from samples at
    /// `sample_points` (plus the pilot data), every observation with noise `sn2`. `seed`
    /// drives the noise of the drawn fingerprints: test fingerprints and sample
    /// fingerprints use separate streams, so the drawn test fingerprints do not depend on
    /// the samples.
    pub fn evaluate(&self, sample_points: &[Point], seed: u64) -> Result<LocalizationReport> {
        self.evaluate_inner(sample_points, None, seed, Localizer::Gp)
    }

    /// As [`Evaluator::evaluate`] with another localizer.
    pub fn evaluate_with(
        &self,
        sample_points: &[Point],
        seed: u64,
        localizer: Localizer,
    ) -> Result<LocalizationReport> {
        self.evaluate_inner(sample_points, None, seed, localizer)
    }

    /// As [`Evaluator::evaluate`] for the samples of [`crate::samples::sample_walk`]: a
    /// human sample's label noise (SPEC section 4) is added to `sn2` in the map's GP, as
    /// the planner assumes. The fingerprint itself is drawn at the sample's true position.
    pub fn evaluate_samples(&self, samples: &[Sample], seed: u64) -> Result<LocalizationReport> {
        self.evaluate_samples_with(samples, seed, Localizer::Gp)
    }

    /// As [`Evaluator::evaluate_samples`] with another localizer.
    pub fn evaluate_samples_with(
        &self,
        samples: &[Sample],
        seed: u64,
        localizer: Localizer,
    ) -> Result<LocalizationReport> {
        let points: Vec<Point> = samples.iter().map(|s| s.pos).collect();
        let extra: Vec<f64> = samples.iter().map(|s| s.extra_noise).collect();
        self.evaluate_inner(&points, Some(&extra), seed, localizer)
    }

    fn evaluate_inner(
        &self,
        sample_points: &[Point],
        extra_noise: Option<&[f64]>,
        seed: u64,
        localizer: Localizer,
    ) -> Result<LocalizationReport> {
        let m = self.aps.len();
        let sd = self.kernel.sn2.sqrt();

        // Test fingerprints.
        let mut rng = stream_rng(seed, STREAM_TEST);
        let tests: Vec<Vec<f64>> = self
            .test_measured
            .iter()
            .enumerate()
            .map(|(t, measured)| match measured {
                Some(v) => v.clone(),
                None => (0..m)
                    .map(|a| self.test_world[(t, a)] + sd * normal(&mut rng))
                    .collect(),
            })
            .collect();

        // Training data: drawn samples, then the pilot data.
        let mut rng = stream_rng(seed, STREAM_SAMPLES);
        let world = self.world.mean(sample_points);
        let ns = sample_points.len();
        let np = self.pilot_points.len();
        let mut values = DMatrix::zeros(ns + np, m);
        for i in 0..ns {
            for a in 0..m {
                values[(i, a)] = world[(i, a)] + sd * normal(&mut rng);
            }
        }
        values.rows_mut(ns, np).copy_from(&self.pilot_values);
        let mut train = sample_points.to_vec();
        train.extend_from_slice(&self.pilot_points);
        if train.is_empty() {
            return Err(Error::InvalidRequest(
                "nothing to build a fingerprint map from: no samples and no pilot data".into(),
            ));
        }
        let mut noise = vec![self.kernel.sn2; train.len()];
        if let Some(extra) = extra_noise {
            for (n, x) in noise.iter_mut().zip(extra) {
                *n += x;
            }
        }
        let errors = locate_all(
            &self.kernel,
            &self.options,
            &self.grid,
            &train,
            &noise,
            &values,
            &tests,
            &self.test_points,
            localizer,
        )?;

        let (mean, median, p90) = summary(&errors);
        Ok(LocalizationReport {
            mean_error_m: mean,
            median_error_m: median,
            p90_error_m: p90,
            errors_m: errors,
            samples: ns,
            access_points: m,
            grid_points: self.grid.len(),
        })
    }
}

/// The localization error of every test fingerprint `tests[t]` (true position
/// `truths[t]`) on the map built from `values` (rows: training fingerprints at `train`
/// with noise `noise`; columns: access points).
#[allow(clippy::too_many_arguments)]
fn locate_all(
    kernel: &Kernel,
    options: &EvalOptions,
    grid: &[Point],
    train: &[Point],
    noise: &[f64],
    values: &DMatrix<f64>,
    tests: &[Vec<f64>],
    truths: &[Point],
    localizer: Localizer,
) -> Result<Vec<f64>> {
    let error = |at: &Point, truth: &Point| {
        at.planar_distance(truth)
            + options.floor_penalty_m * (at.floor - truth.floor).unsigned_abs() as f64
    };
    let k = match localizer {
        Localizer::Knn { k } => k,
        Localizer::Gp => {
            let m = values.ncols();
            let gp = GpModel::fit_with_noise(kernel, train, noise, values)?;
            let pred = gp.predict(grid);
            // Localize every test fingerprint at the most likely grid point.
            let total_var: Vec<f64> = pred.variance.iter().map(|v| v + kernel.sn2).collect();
            let log_norm: Vec<f64> = total_var.iter().map(|v| -0.5 * m as f64 * v.ln()).collect();
            // Row-major copy of the means: one contiguous slice of m values per grid point.
            let mu: Vec<f64> = pred.mean.transpose().as_slice().to_vec();
            return Ok(tests
                .par_iter()
                .zip(truths.par_iter())
                .map(|(z, truth)| {
                    let mut best = (f64::NEG_INFINITY, 0usize);
                    for (g, mu_g) in mu.chunks_exact(m).enumerate() {
                        let sq: f64 = z
                            .iter()
                            .zip(mu_g)
                            .map(|(za, ma)| (za - ma) * (za - ma))
                            .sum();
                        let ll = log_norm[g] - 0.5 * sq / total_var[g];
                        if ll > best.0 {
                            best = (ll, g);
                        }
                    }
                    error(&grid[best.1], truth)
                })
                .collect());
        }
    };
    Ok(tests
        .par_iter()
        .zip(truths.par_iter())
        .map(|(z, truth)| error(&knn_locate(z, train, values, k), truth))
        .collect())
}

/// What the fingerprints a session collected are worth (see [`evaluate_collected`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CollectedReport {
    /// Localization error on the building's test points (`None` when it has none, or
    /// they carry no measured fingerprint and there is no dense survey to draw them from).
    pub localization: Option<LocalizationReport>,
    /// Why there is no localization error, when there is none.
    pub localization_note: Option<String>,
    pub localizer: Localizer,
    /// Fingerprints used: collected ones, and pilot ones.
    pub collected: usize,
    pub pilot: usize,
    pub access_points: usize,
    /// Posterior standard deviation of the latent RSS on the reference grid, given the
    /// pilot and collected positions (with their label noise): mean, median, 90th
    /// percentile and largest, dB.
    pub std_mean_db: f64,
    pub std_median_db: f64,
    pub std_p90_db: f64,
    pub std_max_db: f64,
    pub grid_points: usize,
}

/// One collected fingerprint: its labelled position, the extra noise of its label (dB²,
/// `Kernel::label_noise` of its position error) and its readings.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledFingerprint {
    pub pos: Point,
    pub extra_noise: f64,
    pub rss: std::collections::BTreeMap<String, f64>,
}

/// Judges fingerprints actually collected (for example by a survey session), not a walk
/// re-sampled from a world model: the map is built from their measured readings plus the
/// pilot data; test fingerprints are the measured `rss` of the building's `test_points`,
/// drawn from the dense-survey world model (seed `seed`) where a test point has none. The
/// access points are those heard in the collected and pilot fingerprints.
pub fn evaluate_collected(
    building: &Building,
    kernel: &Kernel,
    collected: &[LabelledFingerprint],
    options: &EvalOptions,
    localizer: Localizer,
    seed: u64,
) -> Result<CollectedReport> {
    kernel.validate("evaluation kernel")?;
    options.validate()?;
    let set: std::collections::BTreeSet<&String> = collected
        .iter()
        .flat_map(|c| c.rss.keys())
        .chain(building.pilot.iter().flat_map(|f| f.rss.keys()))
        .collect();
    let aps: Vec<String> = set.into_iter().cloned().collect();
    let mut train: Vec<Point> = collected.iter().map(|c| c.pos).collect();
    train.extend(building.pilot_points());
    if train.is_empty() {
        return Err(Error::InvalidRequest(format!(
            "building {:?}: nothing to build a fingerprint map from (no collected \
             fingerprints and no pilot data)",
            building.name
        )));
    }
    let mut noise: Vec<f64> = collected
        .iter()
        .map(|c| kernel.sn2 + c.extra_noise)
        .collect();
    noise.resize(train.len(), kernel.sn2);
    let nc = collected.len();
    let values = DMatrix::from_fn(train.len(), aps.len(), |i, a| {
        let rss = if i < nc {
            &collected[i].rss
        } else {
            &building.pilot[i - nc].rss
        };
        rss.get(&aps[a]).copied().unwrap_or(MISSING_DBM)
    });
    let grid = reference_grid(building, options.grid_step_m, options.grid_margin_m);
    if grid.is_empty() {
        return Err(Error::InvalidRequest(format!(
            "building {:?}: the reference grid is empty",
            building.name
        )));
    }
    // Coverage: latent posterior standard deviation on the grid.
    let gp0 = GpModel::fit_with_noise(kernel, &train, &noise, &DMatrix::zeros(train.len(), 1))?;
    let std: Vec<f64> = gp0
        .variance(&grid)
        .into_iter()
        .map(|v| v.max(0.0).sqrt())
        .collect();
    let (std_mean, std_median, std_p90) = summary(&std);
    let std_max = std.iter().copied().fold(0.0, f64::max);

    let mut note = None;
    let localization = if building.test_points.is_empty() {
        note = Some("the building has no test_points".to_string());
        None
    } else if aps.is_empty() {
        note = Some("no access point was heard in the collected or pilot fingerprints".into());
        None
    } else {
        let needs_world = building.test_points.iter().any(|t| t.rss.is_empty());
        let world = if needs_world && !building.dense_survey.is_empty() {
            Some(WorldModel::from_dense_survey(building, kernel)?)
        } else {
            None
        };
        if needs_world && world.is_none() {
            note = Some(
                "test points without measured rss and no dense_survey to draw them from"
                    .to_string(),
            );
            None
        } else {
            let truths: Vec<Point> = building
                .test_points
                .iter()
                .map(Fingerprint::point)
                .collect();
            let world_aps = world.as_ref().map(WorldModel::ap_ids).unwrap_or_default();
            let world_mean = world.as_ref().map(|w| w.mean(&truths));
            let mut rng = stream_rng(seed, STREAM_TEST);
            let sd = kernel.sn2.sqrt();
            let tests: Vec<Vec<f64>> = building
                .test_points
                .iter()
                .enumerate()
                .map(|(t, tp)| {
                    aps.iter()
                        .map(|a| {
                            if !tp.rss.is_empty() {
                                return tp.rss.get(a).copied().unwrap_or(MISSING_DBM);
                            }
                            match (world_aps.iter().position(|w| w == a), &world_mean) {
                                (Some(c), Some(m)) => m[(t, c)] + sd * normal(&mut rng),
                                _ => MISSING_DBM,
                            }
                        })
                        .collect()
                })
                .collect();
            let errors = locate_all(
                kernel, options, &grid, &train, &noise, &values, &tests, &truths, localizer,
            )?;
            let (mean, median, p90) = summary(&errors);
            Some(LocalizationReport {
                mean_error_m: mean,
                median_error_m: median,
                p90_error_m: p90,
                errors_m: errors,
                samples: nc,
                access_points: aps.len(),
                grid_points: grid.len(),
            })
        }
    };
    Ok(CollectedReport {
        localization,
        localization_note: note,
        localizer,
        collected: nc,
        pilot: building.pilot.len(),
        access_points: aps.len(),
        std_mean_db: std_mean,
        std_median_db: std_median,
        std_p90_db: std_p90,
        std_max_db: std_max,
        grid_points: grid.len(),
    })
}

/// Mean, median and 90th percentile (linear interpolation between order statistics).
fn summary(values: &[f64]) -> (f64, f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let pos = p * (v.len() - 1) as f64;
        let lo = pos.floor() as usize;
        let hi = pos.ceil() as usize;
        v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
    };
    (v.iter().sum::<f64>() / v.len() as f64, q(0.5), q(0.9))
}

/// One-shot evaluation with the dense-survey world model (see [`Evaluator`] to reuse the
/// world model across many walks).
pub fn evaluate(
    building: &Building,
    kernel: &Kernel,
    sample_points: &[Point],
    seed: u64,
    options: &EvalOptions,
) -> Result<LocalizationReport> {
    Evaluator::new(building, kernel, *options)?.evaluate(sample_points, seed)
}

#[cfg(test)]
#[path = "eval_tests.rs"]
mod tests;
