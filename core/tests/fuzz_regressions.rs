//! Inputs the fuzz targets of `fuzz/` (issue 20, `docs/fuzzing.md`) found wrongly accepted,
//! crashing, or taking unbounded time or memory, kept as ordinary tests. Each input is a file
//! of `fixtures/fuzz/`; each test says what went wrong before the fix.

#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use trailprint::floorplan::{ImportOptions, MAX_GRID_CELLS, import_osm_text};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/fuzz")
        .join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).expect(name)
}

/// Runs `f` on another thread and fails the test if it takes longer than `secs` (a hang
/// before the fix must fail the test, not stall the suite).
fn within<T: Send + 'static>(secs: u64, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(secs))
        .unwrap_or_else(|_| panic!("did not finish within {secs} s"))
}

/// Fails unless `msg` contains every one of `parts` (what a refusal must name).
fn assert_names(msg: &str, parts: &[&str]) {
    for part in parts {
        assert!(msg.contains(part), "{msg:?} should name {part:?}");
    }
}

/// Fails unless `result` is a refusal (`why`: what makes it one) naming every one of
/// `parts`.
fn assert_refused_naming<T: std::fmt::Debug>(
    result: trailprint::Result<T>,
    why: &str,
    parts: &[&str],
) {
    assert_names(&result.expect_err(why).to_string(), parts);
}

/// Checks that the validator accepts the building an import wrote and that the counts the
/// import reports are the building's.
fn valid_import(imp: &trailprint::floorplan::FloorplanImport, name: &str) {
    let b = trailprint::Building::from_file(imp.file.clone(), name).unwrap_or_else(|e| {
        panic!("{name}: the importer wrote a building the validator refuses: {e}")
    });
    assert_eq!(imp.stats.vertices, b.len(), "{name}: vertex count");
    assert_eq!(imp.stats.edges, b.edges.len(), "{name}: edge count");
}

/// A room half a degree of latitude and longitude across (37 km by 56 km): the network
/// laid a 2 m grid over it, half a billion cells, for hours and until memory ran out (seen
/// in the grid code while writing the `floorplan_osm` target; `trailprint import-floorplan`
/// on it was still running after 60 s). It is refused at once, naming the room and its size.
#[test]
fn a_room_kilometres_across_is_refused_before_its_grid_is_laid() {
    assert_refused_naming(
        replay_osm_as(&text("osm-room-half-a-degree.geojson"), "room.geojson", 30),
        "a 37 km room is not an indoor floor plan",
        &[
            "room.geojson",
            "grid cells",
            &MAX_GRID_CELLS.to_string(),
            "room way/1",
            "37313 m by 55595 m",
        ],
    );
}

/// A scan reading of -0 dBm (and a robot pose at x = -0): the live session kept the
/// negative zero, the SQLite log stores it as 0, so the session resumed from its log
/// differed from the live one (found by `session`: "replay differs", 3 inputs). Both logs
/// now replay to the live state.
#[test]
fn a_reading_of_minus_zero_dbm_replays_to_the_same_session() {
    use trailprint::session::{Event, Session, Surveyor};

    let events: std::collections::BTreeMap<String, Vec<Event>> =
        serde_json::from_str(&text("session-minus-zero-dbm.json")).unwrap();
    for (who, surveyor) in [("human", Surveyor::human()), ("robot", Surveyor::robot())] {
        for in_store in [false, true] {
            let (mut s, log, _) = fuzz_session(in_store, surveyor);
            for ev in &events[who] {
                s.record(ev.clone()).unwrap();
            }
            let replayed = Session::replay_to(log.clone(), s.id(), i64::MAX).unwrap();
            assert_eq!(
                replayed.digest(),
                s.digest(),
                "{who}, log in {}",
                if in_store { "the store" } else { "memory" }
            );
        }
    }
}

/// A session log in memory or in an in-memory store (kept, so that a test can read its
/// rows) holding the fuzz building (`session-building.json`, the building of the `session`
/// target) and a plan of `walk` on it (the plan's id), as the `session` target sets up.
fn fuzz_log_with_plan(
    in_store: bool,
    walk: &[&str],
) -> (
    std::sync::Arc<dyn trailprint::session::SessionLog>,
    i64,
    Option<std::sync::Arc<trailprint::store::Store>>,
) {
    use std::sync::Arc;
    use trailprint::Building;
    use trailprint::gp::Kernel;
    use trailprint::session::{MemoryLog, PlanData, SessionLog};
    use trailprint::store::{ImportOptions as StoreImport, Store};

    let building =
        Building::from_json(&text("session-building.json"), "session-building.json").unwrap();
    let (log, bid, store): (Arc<dyn SessionLog>, i64, Option<Arc<Store>>) = if in_store {
        let store = Arc::new(Store::open_in_memory().unwrap());
        let id = store
            .import_building(&building, None, &StoreImport::default())
            .unwrap()
            .id;
        (store.clone(), id, Some(store))
    } else {
        let log = Arc::new(MemoryLog::new());
        let id = log.add_building(Arc::new(building));
        (log, id, None)
    };
    let plan = PlanData::for_walk(bid, walk, 40.0, Kernel::new(20.0, 5.0, 2.0), 12.0);
    let plan_id = log.save_plan(&plan).unwrap();
    (log, plan_id, store)
}

/// A session on the fuzz building with the walk `a b c d` and no automatic replans (see
/// [`fuzz_log_with_plan`]).
fn fuzz_session(
    in_store: bool,
    surveyor: trailprint::session::Surveyor,
) -> (
    trailprint::session::Session,
    std::sync::Arc<dyn trailprint::session::SessionLog>,
    Option<std::sync::Arc<trailprint::store::Store>>,
) {
    use trailprint::session::{Session, SessionOptions};

    let (log, plan_id, store) = fuzz_log_with_plan(in_store, &["a", "b", "c", "d"]);
    let options = SessionOptions {
        auto_replan: false,
        ..SessionOptions::default()
    };
    let s = Session::start(log.clone(), plan_id, surveyor, options).unwrap();
    (s, log, store)
}

/// Event times at the ends of `i64` (the `session` target sends `i64::MIN` and `i64::MAX`):
/// a first event at `i64::MIN` was accepted, and the active time of any later event,
/// `last - first`, overflowed (a panic with overflow checks, a negative time without). Times are
/// now bounded by `MAX_EVENT_T_MS` (0 to early 2070): one outside is refused, naming the
/// field and the bound, and changes neither the session nor its log; the bound itself is
/// accepted, and the active time from 0 to it is exact.
#[test]
fn event_times_past_max_event_t_ms_are_refused_naming_the_field() {
    use trailprint::session::{Event, MAX_EVENT_T_MS, Surveyor};

    for in_store in [false, true] {
        for (who, surveyor) in [("human", Surveyor::human()), ("robot", Surveyor::robot())] {
            let (mut s, log, _) = fuzz_session(in_store, surveyor);
            let ev = |t_ms: i64| {
                if surveyor.is_human() {
                    Event::Step { t_ms, steps: 1 }
                } else {
                    Event::Pose {
                        t_ms,
                        x: 1.0,
                        y: 0.0,
                        floor: 0,
                    }
                }
            };
            for t in [i64::MIN, -1, MAX_EVENT_T_MS + 1, i64::MAX] {
                let before = s.digest();
                let err = s
                    .record(ev(t))
                    .expect_err(&format!("{who}: t_ms {t} accepted"));
                let msg = err.to_string();
                for part in ["t_ms", &MAX_EVENT_T_MS.to_string(), &t.to_string()] {
                    assert!(msg.contains(part), "{who}: {msg:?} should name {part:?}");
                }
                assert_eq!(
                    s.digest(),
                    before,
                    "{who}: refused t_ms {t} changed the session"
                );
                assert!(
                    log.events(s.id()).unwrap().is_empty(),
                    "{who}: t_ms {t} logged"
                );
            }
            s.record(ev(0)).unwrap();
            s.record(ev(MAX_EVENT_T_MS)).unwrap();
            assert_eq!(s.tracker().elapsed_ms(), MAX_EVENT_T_MS, "{who}");
            let p = s.progress().unwrap();
            assert!(p.elapsed_s.is_finite() && p.elapsed_s > 0.0, "{who}: {p:?}");
            let err = s.record(ev(i64::MAX)).expect_err("past the bound");
            assert!(err.to_string().contains("t_ms"), "{err}");
            assert_eq!(log.events(s.id()).unwrap().len(), 2, "{who}");
        }
    }
}

/// The store is the other door for event times (a bundle's events go through it): an
/// event outside 0 to `MAX_EVENT_T_MS` is refused naming `at_ms`, and the store is left
/// with the events it had.
#[test]
fn the_store_refuses_event_times_past_max_event_t_ms() {
    use trailprint::session::{MAX_EVENT_T_MS, Surveyor};
    use trailprint::store::SessionEvent;

    let (s, _, store) = fuzz_session(true, Surveyor::human());
    let store = store.unwrap();
    let id = s.id();
    store
        .append_event(id, MAX_EVENT_T_MS, &SessionEvent::Pause)
        .unwrap();
    for t in [i64::MIN, -1, MAX_EVENT_T_MS + 1, i64::MAX] {
        assert_refused_naming(
            store.append_event(id, t, &SessionEvent::Resume),
            &format!("at_ms {t} accepted"),
            &["at_ms", &MAX_EVENT_T_MS.to_string(), &t.to_string()],
        );
    }
    let events = store.list_events(id, 0).unwrap();
    assert_eq!(events.len(), 1);
    assert_eq!(events[0].at_ms, MAX_EVENT_T_MS);
}

/// Replays a `session` target input kept as JSON (the target's setup and its decoded ops:
/// events, and `"replan"` for an explicit replan) with the target's checks: a refused event
/// changes neither the session nor its log (nor the store's rows), an accepted one gets the
/// next seq and leaves finite figures, and the log replays to the live state.
fn replay_session_fixture(name: &str) {
    use trailprint::session::{Event, Session, SessionOptions, SessionStatus, Surveyor};

    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Op {
        Replan(String),
        Event(Event),
    }
    #[derive(serde::Deserialize)]
    struct Input {
        log: String,
        surveyor: String,
        auto_replan: bool,
        deviation_reserve: bool,
        walk: Vec<String>,
        ops: Vec<Op>,
    }
    let input: Input = serde_json::from_str(&text(name)).expect(name);
    let walk: Vec<&str> = input.walk.iter().map(String::as_str).collect();
    let (log, plan_id, _) = fuzz_log_with_plan(input.log == "store", &walk);
    let surveyor = if input.surveyor == "human" {
        Surveyor::human()
    } else {
        Surveyor::robot()
    };
    let options = SessionOptions {
        auto_replan: input.auto_replan,
        deviation_reserve: input.deviation_reserve,
        ..SessionOptions::default()
    };
    let mut s = Session::start(log.clone(), plan_id, surveyor, options).unwrap();
    let id = s.id();
    for (i, op) in input.ops.into_iter().enumerate() {
        let before = s.digest();
        let before_len = log.events(id).unwrap().len();
        let ended = matches!(s.status(), SessionStatus::Finished | SessionStatus::Aborted);
        match op {
            Op::Replan(word) => {
                assert_eq!(
                    word, "replan",
                    "{name}: op {i} is neither an event nor \"replan\""
                );
                if s.replan().is_err() {
                    assert_eq!(
                        before,
                        s.digest(),
                        "op {i}: a failed replan changed the session"
                    );
                    assert_eq!(before_len, log.events(id).unwrap().len(), "op {i}");
                }
            }
            Op::Event(ev) => match s.record(ev.clone()) {
                Err(e) => {
                    assert!(!e.to_string().is_empty());
                    assert_eq!(
                        before,
                        s.digest(),
                        "op {i}: refused {ev:?} changed the session"
                    );
                    assert_eq!(before_len, log.events(id).unwrap().len(), "op {i}: logged");
                }
                Ok(ack) => {
                    assert!(!ended, "op {i}: {ev:?} accepted after the end");
                    let t = s.tracker();
                    assert!(t.walked_m().is_finite() && t.walked_m() >= 0.0, "op {i}");
                    assert!(t.elapsed_ms() >= 0, "op {i}");
                    assert!(ack.position.x.is_finite() && ack.position.y.is_finite());
                    let g = s.guidance();
                    assert!(
                        g.distance_m.is_finite() && g.distance_m >= 0.0,
                        "op {i}: {g:?}"
                    );
                    if let Ok(p) = s.progress() {
                        assert!((0.0..=1.0).contains(&p.fraction_done), "op {i}: {p:?}");
                        assert!(p.remaining_m.is_finite() && p.remaining_m >= 0.0, "op {i}");
                        assert!(p.elapsed_s.is_finite() && p.elapsed_s >= 0.0, "op {i}");
                    }
                }
            },
        }
    }
    let again = Session::replay_to(log.clone(), id, i64::MAX).unwrap();
    assert_eq!(again.digest(), s.digest(), "replay differs");
}

#[test]
fn session_seed_once_committed_as_crash_209ed65f_replays_cleanly() {
    replay_session_fixture("session-209ed65f.json");
}

#[test]
fn session_seed_once_committed_as_crash_32c3a55e_replays_cleanly() {
    replay_session_fixture("session-32c3a55e.json");
}

/// An IMDF input of the `floorplan_imdf` target (the files NUL-separated, in the target's
/// order) as the importer's file map.
fn imdf_files(name: &str) -> std::collections::HashMap<String, String> {
    let bytes = std::fs::read(fixture(name)).expect(name);
    trailprint::floorplan::imdf::LAYERS
        .iter()
        .zip(bytes.split(|&b| b == 0))
        .filter(|(_, part)| !part.is_empty())
        .map(|(f, part)| (f.to_string(), String::from_utf8(part.to_vec()).expect(name)))
        .collect()
}

/// The mall fixture with one unit's corner moved two degrees of longitude east (146 km) by
/// a mutation (found by `floorplan_imdf`, 14 timeouts in 20 minutes: over 120 s for `-a`,
/// 23 s for `-b`, under the sanitizer). The unit became a sliver whose grid fell into
/// thousands of parts, and joining them read every edge of the floor again for each join.
/// Now the parts are tracked as they are joined, the 400 closest pairs kept in a heap, and
/// the pairs measured per space bounded (`BRIDGE_MAX_PAIRS`). With `MAX_GRID_CELLS` at
/// 100,000, `-a` (a unit 73 km by 8 m, 146,800 cells) is refused at once naming the unit
/// and its size; `-b` imports in seconds, a valid building of its largest connected part,
/// with the parts left apart reported.
#[test]
fn a_unit_stretched_two_degrees_is_refused_or_imports_in_bounded_time() {
    assert_refused_naming(
        replay_imdf("imdf-unit-two-degrees-long-a.bin"),
        "a unit 73 km long is over the grid limit",
        &[
            "fuzz-imdf",
            "grid cells",
            "room \"Shoes\"",
            "73363 m by 8 m",
        ],
    );

    let name = "imdf-unit-two-degrees-long-b.bin";
    let imp = replay_imdf(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    valid_import(&imp, name);
    assert!(
        !imp.dropped.is_empty(),
        "{name}: the rooms cut off by the sliver are reported"
    );
    for part in &imp.dropped {
        assert!(
            part.vertices > 0 && !part.spaces.is_empty(),
            "{name}: {part}"
        );
    }
}

/// Imports the OSM fixture `name` as `fuzz.geojson`, failing the test after 60 s.
fn replay_osm(name: &str) -> trailprint::Result<trailprint::floorplan::FloorplanImport> {
    replay_osm_as(&text(name), "fuzz.geojson", 60)
}

/// Imports OSM GeoJSON text as `origin`, failing the test after `secs` seconds.
fn replay_osm_as(
    input: &str,
    origin: &'static str,
    secs: u64,
) -> trailprint::Result<trailprint::floorplan::FloorplanImport> {
    let input = input.to_string();
    within(secs, move || {
        import_osm_text(&input, origin, &ImportOptions::default())
    })
}

/// Imports the IMDF fixture `name` (NUL-separated files) as `fuzz-imdf`, failing the test
/// after 60 s.
fn replay_imdf(name: &str) -> trailprint::Result<trailprint::floorplan::FloorplanImport> {
    replay_imdf_as(imdf_files(name), "fuzz-imdf", 60)
}

/// Imports IMDF files as `origin`, failing the test after `secs` seconds.
fn replay_imdf_as(
    files: std::collections::HashMap<String, String>,
    origin: &'static str,
    secs: u64,
) -> trailprint::Result<trailprint::floorplan::FloorplanImport> {
    within(secs, move || {
        trailprint::floorplan::import_imdf_files(&files, origin, &ImportOptions::default())
    })
}

/// An accepted import is a building the validator takes; a refusal names `origin`.
fn valid_or_refused(
    result: trailprint::Result<trailprint::floorplan::FloorplanImport>,
    name: &str,
    origin: &str,
) {
    match result {
        Ok(imp) => valid_import(&imp, name),
        Err(e) => assert!(e.to_string().contains(origin), "{name}: {e}"),
    }
}

/// An OSM input of `floorplan_osm` that timed out in the same place (`bridge`, over 100 s
/// under the sanitizer): it is imported or refused within the same bound, and an accepted
/// plan is a building the validator takes.
#[test]
fn an_osm_plan_that_timed_out_in_bridging_imports_in_bounded_time() {
    let name = "osm-timeout-f58c5975.geojson";
    valid_or_refused(replay_osm(name), name, "fuzz.geojson");
}

/// An 11 KB OSM plan (a `floorplan_osm` timeout of 3 December: over 10 s under the
/// sanitizer) with a room mutated into a sliver 20 m by 111 km: at 2 m it grew a network
/// of 261,506 vertices, 8.3 s and 490 MB to import into the store, far beyond what anyone
/// can plan. With `MAX_GRID_CELLS` at 100,000 it is refused before any grid is laid,
/// naming the room and its size.
#[test]
fn an_osm_room_a_degree_long_is_refused_naming_the_room() {
    assert_refused_naming(
        replay_osm_as(&text("osm-room-a-degree-long.geojson"), "big.geojson", 30),
        "a room 111 km long is over the grid limit",
        &[
            "big.geojson",
            "grid cells",
            &MAX_GRID_CELLS.to_string(),
            "room \"Lab\" (way/1011)",
            "20 m by 111212 m",
            "larger spacing",
        ],
    );
}

/// An OSM plan (a `floorplan_osm` timeout of 3 December, over 60 s in release) whose space
/// of 30,000 grid points had a few cut off: each join in `bridge` filtered the whole space
/// for every vertex inside, `n_in * n` steps however few the pairs. Now the two sides are
/// listed once per join and pairs compared by squared distance: 2.3 s in release.
#[test]
fn an_osm_space_with_a_few_vertices_cut_off_bridges_in_bounded_time() {
    let name = "osm-bridge-scan-65aa4573.geojson";
    let imp = replay_osm(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    valid_import(&imp, name);
}

/// An OSM plan with a corridor moved 2,769 km away by a mutated coordinate (a
/// `floorplan_osm` timeout of 3 December): the importer gridded it for 12 s and then the
/// validator refused the building, naming a vertex the user never wrote. It is now
/// refused before any grid is laid, naming the corridor.
#[test]
fn an_osm_space_thousands_of_kilometres_away_is_refused_naming_it() {
    assert_refused_naming(
        replay_osm_as(
            &text("osm-space-beyond-range-bf79aaf7.geojson"),
            "far.geojson",
            30,
        ),
        "a corridor 2,769 km away is beyond the building format's range",
        &[
            "far.geojson",
            "corridor \"Corridor 0\" (way/1002)",
            "2.769e6 m",
            "1e6 m",
        ],
    );
}

/// IMDF files (a `floorplan_imdf` out-of-memory of 3 December: a 1 GiB allocation) with a
/// unit whose outline a mutated coordinate made thousands of kilometres long: the search
/// for shared boundaries sampled it every 0.1 m. It now takes at most about 20,000
/// samples an outline. This replays the input (imported as a valid building, or refused);
/// a test process allows the 1 GiB the fuzzer refused, so the bound itself is checked by
/// `geom::tests::shared_runs_takes_bounded_samples_on_a_huge_outline`.
#[test]
fn an_imdf_unit_outline_thousands_of_kilometres_long_is_sampled_in_bounded_memory() {
    let name = "imdf-outline-thousands-of-km-636e9ccc.bin";
    valid_or_refused(replay_imdf(name), name, "fuzz-imdf");
}

/// Two `floorplan_osm` and `floorplan_imdf` timeouts of 3 December (20 to 37 s under the
/// sanitizer): an OSM plan whose rooms became slivers in many parts, where each space spent
/// its own `BRIDGE_MAX_PAIRS` (0.70 s in release), and an IMDF level stretched 2 km that
/// grows a 28,619-vertex network (0.81 s). The pair budget became one for the whole import
/// (0.18 s and 0.33 s), but it still ran out: the OSM import dropped 133 parts (332
/// vertices, 132 of them alone) and the IMDF one 158 single vertices, each a grid point
/// that a wall or the outline cut off from its neighbours but within a few metres in sight
/// of them. Since 3 December `bridge` first joins the parts by their short bridges
/// (`join_near`): both import as valid buildings and drop nothing.
#[test]
fn plans_that_timed_out_in_bridging_on_3_december_import_whole_as_valid_buildings() {
    for (name, imp) in [
        (
            "osm-slivers-c60bdf9c.geojson",
            replay_osm("osm-slivers-c60bdf9c.geojson"),
        ),
        (
            "imdf-level-stretched-5cf1f027.bin",
            replay_imdf("imdf-level-stretched-5cf1f027.bin"),
        ),
    ] {
        let imp = imp.unwrap_or_else(|e| panic!("{name}: refused: {e}"));
        valid_import(&imp, name);
        let dropped: Vec<String> = imp.dropped.iter().map(ToString::to_string).collect();
        assert!(dropped.is_empty(), "{name}: parts dropped: {dropped:?}");
    }
}

/// IMDF files of one level holding one walkable square hall `side_m` metres across.
fn imdf_square_hall(side_m: f64) -> std::collections::HashMap<String, String> {
    let (lat0, lon0) = (48.8763_f64, 2.3591_f64);
    let dlat = side_m / 111_320.0;
    let dlon = side_m / (111_320.0 * lat0.to_radians().cos());
    let ring = format!(
        "[[[{lon0},{lat0}],[{e},{lat0}],[{e},{n}],[{lon0},{n}],[{lon0},{lat0}]]]",
        e = lon0 + dlon,
        n = lat0 + dlat
    );
    let level = "00000000-0000-4000-8000-000000000003";
    let fc = |name: &str, feature: String| {
        format!(r#"{{"type":"FeatureCollection","name":"{name}","features":[{feature}]}}"#)
    };
    let mut files = std::collections::HashMap::new();
    files.insert(
        "level.geojson".to_string(),
        fc(
            "level",
            format!(
                r#"{{"id":"{level}","type":"Feature","feature_type":"level",
                "geometry":{{"type":"Polygon","coordinates":{ring}}},
                "properties":{{"category":"unspecified","outdoor":false,"ordinal":0,
                "name":{{"en":"G"}},"short_name":{{"en":"0"}}}}}}"#
            ),
        ),
    );
    files.insert(
        "unit.geojson".to_string(),
        fc(
            "unit",
            format!(
                r#"{{"id":"00000000-0000-4000-8000-000000000100","type":"Feature",
                "feature_type":"unit","geometry":{{"type":"Polygon","coordinates":{ring}}},
                "properties":{{"category":"walkway","name":{{"en":"Hall"}},
                "level_id":"{level}"}}}}"#
            ),
        ),
    );
    files
}

/// A hall 300 m square (a mutated unit of the mall fixture grew like this): its gap filling
/// measured every candidate point against every vertex of the space, quadratic in the
/// hall's area (51 s for 400 m in a release build, 3.2 s for 200 m; the `floorplan_imdf`
/// target's timeouts, up to 28 s for 63,909 vertices under the sanitizer). With buckets the
/// 300 m hall is about a second: its 22,500 grid vertices, every one joined to the grid.
#[test]
fn a_hall_hundreds_of_metres_square_imports_in_bounded_time() {
    use trailprint::Building;

    let files = imdf_square_hall(300.0);
    let imp = replay_imdf_as(files, "hall-300m", 20).expect("a 300 m hall is a valid floor plan");
    // A 2 m grid over 300 m: 150 x 150 points, 2 x 150 x 149 grid edges.
    assert_eq!(imp.stats.vertices, 150 * 150);
    assert_eq!(imp.stats.edges, 2 * 150 * 149);
    assert!(imp.dropped.is_empty(), "{:?}", imp.dropped);
    let b = Building::from_file(imp.file.clone(), "hall-300m").expect("valid building");
    assert_eq!(b.len(), 150 * 150);
}
