//! The localizer of SPEC section 5 on a case small enough to check by hand: which
//! reference point wins the arg-max of the likelihood, and the floor penalty.

use std::collections::BTreeMap;

use trailprint::Building;
use trailprint::eval::{EvalOptions, LabelledFingerprint, Localizer, evaluate_collected};
use trailprint::gp::{Kernel, Point};

/// Two floors, each one 4 m corridor along y = 0, joined by 5 m stairs at x = 0. The
/// reference grid (0.5 m) is x = 0, 0.5, ..., 4 on each floor: 18 points. Four test points
/// with measured readings of one access point.
const BUILDING: &str = r#"{"format":"survey-building/1","name":"two corridors",
  "floors":[{"id":0},{"id":1}],
  "vertices":[{"id":"a0","x":0,"y":0,"floor":0},{"id":"b0","x":4,"y":0,"floor":0},
              {"id":"a1","x":0,"y":0,"floor":1},{"id":"b1","x":4,"y":0,"floor":1}],
  "edges":[{"a":"a0","b":"b0"},{"a":"a1","b":"b1"},{"a":"a0","b":"a1","length":5}],
  "test_points":[{"x":1,"y":0,"floor":0,"rss":{"ap":-40}},
                 {"x":0,"y":0,"floor":1,"rss":{"ap":-80}},
                 {"x":2,"y":0,"floor":0,"rss":{"ap":-43}},
                 {"x":0,"y":0,"floor":0,"rss":{"ap":-51}}]}"#;

fn fingerprint(x: f64, floor: i64, rss: f64, extra_noise: f64) -> LabelledFingerprint {
    LabelledFingerprint {
        pos: Point::new(x, 0.0, floor),
        extra_noise,
        rss: BTreeMap::from([("ap".to_string(), rss)]),
    }
}

/// With `ell` = 0.01 m, grid points 0.5 m apart are independent (`k` = 100 e^-50), so the
/// GP's prediction is closed-form per point. The access point's values are centred on
/// their mean `mu0 = (-40 - 40 - 80) / 3 = -53.33`. Collected:
/// - A: floor 1, x = 1, -40 dBm, noise 1: mean -53.33 + (100/101) 13.33 = -40.13,
///   variance 100/101 = 0.99, so the test variance (plus `sn2`) is 1.99;
/// - B: floor 0, x = 2, -40 dBm, label noise 99 (noise 100): mean -53.33 + 0.5 * 13.33
///   = -46.67, variance 50, test variance 51;
/// - C: floor 0, x = 3, -80 dBm, noise 1: mean -79.74, test variance 1.99.
///
/// Every other grid point: mean -53.33, test variance 101.
/// Log-likelihood `ll = -ln(v) / 2 - (z - mean)^2 / (2 v)`:
/// 1. truth floor 0, x = 1, z = -40: A -0.348, B -2.40, others -3.19: located at A,
///    the same place on the wrong floor: error 0 + 4 m.
/// 2. truth floor 1, x = 0, z = -80: C (-0.34) wins: 3 m away, one floor off: 7 m.
/// 3. truth floor 0, x = 2, z = -43: A -2.41, B -2.10, others -2.84: B, error 0. A's
///    mean is nearer (2.87 dB against 3.67), so a localizer that ignored the predictive
///    variance would answer A, 5 m off.
/// 4. truth floor 0, x = 0, z = -51: B -2.15, others -2.34: B, error 2 m. Without the
///    `ln v` term the unsampled points would win (-0.027 against -0.184).
#[test]
fn arg_max_and_floor_penalty_by_hand() {
    let b = Building::from_json(BUILDING, "two corridors").expect("building");
    let kernel = Kernel::new(100.0, 0.01, 1.0);
    let collected = [
        fingerprint(1.0, 1, -40.0, 0.0),
        fingerprint(2.0, 0, -40.0, 99.0),
        fingerprint(3.0, 0, -80.0, 0.0),
    ];
    let report = |penalty: f64| {
        let opts = EvalOptions {
            floor_penalty_m: penalty,
            ..EvalOptions::default()
        };
        evaluate_collected(&b, &kernel, &collected, &opts, Localizer::Gp, 1)
            .expect("evaluate")
            .localization
            .expect("test points with rss")
    };
    let r = report(4.0);
    assert_eq!(r.grid_points, 18);
    assert_eq!(r.access_points, 1);
    let want = [4.0, 7.0, 0.0, 2.0];
    for (i, (&got, &w)) in r.errors_m.iter().zip(&want).enumerate() {
        assert!(
            (got - w).abs() < 1e-9,
            "test point {i}: {got} m, want {w} m"
        );
    }
    assert_eq!(r.errors_m.len(), 4);
    assert!((r.mean_error_m - 3.25).abs() < 1e-9, "{}", r.mean_error_m);
    // The penalty is per floor of difference and only where the floor is wrong.
    let r = report(10.0);
    let want = [10.0, 13.0, 0.0, 2.0];
    for (i, (&got, &w)) in r.errors_m.iter().zip(&want).enumerate() {
        assert!(
            (got - w).abs() < 1e-9,
            "penalty 10, test point {i}: {got} m, want {w} m"
        );
    }
}
