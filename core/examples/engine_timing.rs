//! Quick timing of the utility engine on area-two (min and median of many runs, robust to
//! a busy machine): `cargo run --release -p trailprint-core --example engine_timing`.

use std::sync::Arc;
use std::time::Instant;

use trailprint::building::Building;
use trailprint::gp::Kernel;
use trailprint::samples::{Surveyor, sample_walk};
use trailprint::utility::reference::{Observation, pilot_observations};
use trailprint::utility::{UtilityEngine, reference_utility};

fn time<F: FnMut()>(name: &str, runs: usize, mut f: F) {
    let mut t = Vec::with_capacity(runs);
    for _ in 0..runs {
        let s = Instant::now();
        f();
        t.push(s.elapsed().as_secs_f64() * 1e6);
    }
    t.sort_by(f64::total_cmp);
    println!(
        "{name:40} min {:9.1} us   median {:9.1} us",
        t[0],
        t[runs / 2]
    );
}

fn main() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/area-two.json");
    let b = Arc::new(Building::load(&path).expect("area-two"));
    let k = Kernel::new(103.22, 32.17, 3.3);
    let model = Surveyor::robot();
    // Down the corridor and back: 140 m.
    let mut walk = vec![0usize];
    let mut len = 0.0;
    let mut dir_fwd = true;
    while len < 138.0 {
        let last = *walk.last().expect("x");
        let nb: Vec<usize> = b.neighbours(last).iter().map(|x| x.0).collect();
        let next = if dir_fwd {
            nb.iter().copied().find(|&n| n > last && !walk.contains(&n))
        } else {
            None
        }
        .or_else(|| nb.iter().copied().find(|n| !walk.contains(n)))
        .unwrap_or_else(|| {
            dir_fwd = false;
            nb[0]
        });
        let l = b.walk_length(&[last, next]);
        if len + l > 140.0 {
            break;
        }
        len += l;
        walk.push(next);
    }
    let samples = sample_walk(&b, &walk, &model, &k).expect("s");
    println!(
        "walk {:.1} m, {} samples + {} pilot, {} vertices",
        len,
        samples.len(),
        b.pilot.len(),
        b.len()
    );
    let e = UtilityEngine::new(b.clone(), k, model).expect("engine");
    println!("ISA {:?}", e.isa());
    let mut obs = pilot_observations(&b.pilot_points());
    obs.extend(samples.iter().map(Observation::from));
    let vp = b.vertex_points();
    if std::env::var("PROFILE_BATCH").is_ok() {
        for _ in 0..3000 {
            std::hint::black_box(e.utility(&walk).expect("u"));
        }
        return;
    }
    time("reference whole walk", 30, || {
        std::hint::black_box(reference_utility(&k, &vp, &obs).expect("u"));
    });
    time("engine whole walk (batch)", 300, || {
        std::hint::black_box(e.utility(&walk).expect("u"));
    });
    time("sample positions only", 300, || {
        std::hint::black_box(sample_walk(&b, &walk, &model, &k).expect("s"));
    });
    time("engine whole walk (edge by edge)", 100, || {
        let mut st = e.start(walk[0]).expect("s");
        for &v in &walk[1..] {
            st.push(v).expect("p");
        }
        std::hint::black_box(st.utility().expect("u"));
    });
    let mut st = e.start(walk[0]).expect("s");
    for &v in &walk[1..walk.len() - 1] {
        st.push(v).expect("p");
    }
    let mark = st.mark();
    let last = *walk.last().expect("x");
    time("extend by one edge + evaluate", 1000, || {
        st.rewind(&mark);
        st.push(last).expect("p");
        std::hint::black_box(st.utility().expect("u"));
    });
    time("evaluate only (sigma chol)", 1000, || {
        std::hint::black_box(st.utility().expect("u"));
    });
}
