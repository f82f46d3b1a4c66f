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
