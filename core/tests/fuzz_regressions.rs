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

/// A room half a degree of latitude and longitude across (37 km by 56 km): the network
/// laid a 2 m grid over it, half a billion cells, for hours and until memory ran out (seen
/// in the grid code while writing the `floorplan_osm` target; `trailprint import-floorplan`
/// on it was still running after 60 s). It is refused at once, naming the room and its size.
#[test]
fn a_room_kilometres_across_is_refused_before_its_grid_is_laid() {
    let input = text("osm-room-half-a-degree.geojson");
    let err = within(30, move || {
        import_osm_text(&input, "room.geojson", &ImportOptions::default())
    })
    .expect_err("a 37 km room is not an indoor floor plan");
    let msg = err.to_string();
    for part in [
        "room.geojson",
        "grid cells",
        &MAX_GRID_CELLS.to_string(),
        "room way/1",
        "37313 m by 55595 m",
    ] {
        assert!(msg.contains(part), "{msg:?} should name {part:?}");
    }
}

/// A scan reading of -0 dBm (and a robot pose at x = -0): the live session kept the
/// negative zero, the SQLite log stores it as 0, so the session resumed from its log
/// differed from the live one (found by `session`: "replay differs", 3 inputs). Both logs
/// now replay to the live state.
#[test]
fn a_reading_of_minus_zero_dbm_replays_to_the_same_session() {
    use std::sync::Arc;
    use trailprint::Building;
    use trailprint::gp::Kernel;
    use trailprint::session::{
        Event, MemoryLog, PlanData, Session, SessionLog, SessionOptions, Surveyor,
    };
    use trailprint::store::{ImportOptions as StoreImport, Store};

    let building =
        Building::from_json(&text("session-building.json"), "session-building.json").unwrap();
    let events: std::collections::BTreeMap<String, Vec<Event>> =
        serde_json::from_str(&text("session-minus-zero-dbm.json")).unwrap();
    for (who, surveyor) in [("human", Surveyor::human()), ("robot", Surveyor::robot())] {
        for in_store in [false, true] {
            let (log, bid): (Arc<dyn SessionLog>, i64) = if in_store {
                let store = Store::open_in_memory().unwrap();
                let id = store
                    .import_building(&building, None, &StoreImport::default())
                    .unwrap()
                    .id;
                (Arc::new(store), id)
            } else {
                let log = Arc::new(MemoryLog::new());
                let id = log.add_building(Arc::new(building.clone()));
                (log, id)
            };
            let plan = PlanData::for_walk(
                bid,
                &["a", "b", "c", "d"],
                40.0,
                Kernel::new(20.0, 5.0, 2.0),
                12.0,
            );
            let plan_id = log.save_plan(&plan).unwrap();
            let options = SessionOptions {
                auto_replan: false,
                ..SessionOptions::default()
            };
            let mut s = Session::start(log.clone(), plan_id, surveyor, options).unwrap();
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
