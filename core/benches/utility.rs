//! Utility engine benchmarks (issue 2): reference vs fast engine vs incremental extension,
//! on area-two with a 140 m walk and on a generated ~550-vertex building.
//!
//! Run: `cargo bench -p trailprint-core --bench utility`

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use trailprint::building::Building;
use trailprint::gp::Kernel;
use trailprint::samples::{Surveyor, sample_walk};
use trailprint::utility::reference::{Observation, pilot_observations};
use trailprint::utility::{UtilityEngine, reference_utility};

fn area_two() -> Arc<Building> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/area-two.json");
    Arc::new(Building::load(&path).expect("area-two"))
}

/// A lattice of `rows x cols` vertices 1.5 m apart with `pilot` pilot points on vertices;
/// seeded by construction (no randomness).
fn lattice(rows: usize, cols: usize, pilot: usize) -> Arc<Building> {
    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            vertices.push(serde_json::json!({"id": format!("r{r}c{c}"), "x": c as f64 * 1.5, "y": r as f64 * 1.5}));
            if c + 1 < cols {
                edges.push(
                    serde_json::json!({"a": format!("r{r}c{c}"), "b": format!("r{r}c{}", c + 1)}),
                );
            }
            if r + 1 < rows {
                edges.push(
                    serde_json::json!({"a": format!("r{r}c{c}"), "b": format!("r{}c{c}", r + 1)}),
                );
            }
        }
    }
    let pilot: Vec<_> = (0..pilot)
        .map(|i| {
            let (r, c) = ((i * 7) % rows, (i * 13) % cols);
            serde_json::json!({"x": c as f64 * 1.5, "y": r as f64 * 1.5, "rss": {"ap": -60.0}})
        })
        .collect();
    let doc = serde_json::json!({"format": "survey-building/1", "name": "lattice", "vertices": vertices, "edges": edges, "pilot": pilot});
    Arc::new(Building::from_json(&doc.to_string(), "lattice").expect("lattice"))
}

/// A deterministic serpentine walk of at most `budget` metres from vertex 0.
fn walk_of(b: &Building, budget: f64) -> Vec<usize> {
    let mut walk = vec![0usize];
    let mut len = 0.0;
    let mut i = 0usize;
    loop {
        let last = *walk.last().expect("nonempty");
        let nb = b.neighbours(last);
        // Prefer a neighbour not visited recently, cycling through choices.
        let next = nb
            .iter()
            .map(|&(n, _)| n)
            .find(|n| !walk[walk.len().saturating_sub(6)..].contains(n))
            .unwrap_or(nb[i % nb.len()].0);
        let l = b.walk_length(&[last, next]);
        if len + l > budget {
            break;
        }
        len += l;
        walk.push(next);
        i += 1;
    }
    walk
}

fn bench_building(c: &mut Criterion, name: &str, b: Arc<Building>, kernel: Kernel, budget: f64) {
    let model = Surveyor::robot();
    let walk = walk_of(&b, budget);
    let samples = sample_walk(&b, &walk, &model, &kernel).expect("samples");
    eprintln!(
        "{name}: {} vertices, walk {:.1} m, {} samples + {} pilot",
        b.len(),
        b.walk_length(&walk),
        samples.len(),
        b.pilot.len()
    );
    let engine = UtilityEngine::new(b.clone(), kernel, model).expect("engine");
    eprintln!("{name}: engine ISA {:?}", engine.isa());
    let mut obs = pilot_observations(&b.pilot_points());
    obs.extend(samples.iter().map(Observation::from));
    let vpts = b.vertex_points();
    let mut g = c.benchmark_group(name);
    g.sample_size(20);
    g.bench_function("reference_whole_walk", |bn| {
        bn.iter(|| reference_utility(black_box(&kernel), &vpts, &obs).expect("u"))
    });
    g.bench_function("engine_whole_walk", |bn| {
        bn.iter(|| engine.utility(black_box(&walk)).expect("u"))
    });
    // Extending a walk of (budget - one edge) by its last edge, then evaluating.
    let mut st = engine.start(walk[0]).expect("start");
    for &v in &walk[1..walk.len() - 1] {
        st.push(v).expect("push");
    }
    let mark = st.mark();
    let last = *walk.last().expect("nonempty");
    g.bench_function("engine_extend_one_edge_and_evaluate", |bn| {
        bn.iter(|| {
            st.rewind(&mark);
            st.push(black_box(last)).expect("push");
            st.utility().expect("u")
        })
    });
    let walks: Vec<Vec<usize>> = (0..64).map(|_| walk.clone()).collect();
    g.bench_function("engine_64_walks_parallel", |bn| {
        bn.iter(|| engine.utilities(black_box(&walks)))
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_building(
        c,
        "area-two-140m",
        area_two(),
        Kernel::new(103.22, 32.17, 3.3),
        140.0,
    );
    bench_building(
        c,
        "lattice-550-140m",
        lattice(25, 22, 30),
        Kernel::new(103.22, 32.17, 3.3),
        140.0,
    );
}

criterion_group!(utility, benches);
criterion_main!(utility);
