//! The OpenStreetMap indoor (Simple Indoor Tagging) GeoJSON importer.
//!
//! Invariants (`trailprint_fuzz::check_floorplan`): a refused plan is an `Err`, never a
//! panic, and leaves the store row for row unchanged; an accepted one is a building that
//! passes validation and re-exports to an equal building, and, imported into a store in
//! memory as `trailprint import-floorplan` does, reads back equal and deletes without a
//! trace; memory and time stay bounded (libFuzzer's `-rss_limit_mb`, `-malloc_limit_mb` and
//! `-timeout`).
//!
//! Plans are imported with `trailprint_fuzz::floorplan_options()`: the grid is capped at
//! 5,000 cells (`FLOORPLAN_MAX_GRID_CELLS`) instead of the product's 100,000, so that a
//! legitimately large network does not count as a timeout.
#![no_main]

use libfuzzer_sys::fuzz_target;
use trailprint::floorplan::import_osm_text;
use trailprint_fuzz::{check_floorplan, floorplan_options};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    check_floorplan(
        import_osm_text(text, "fuzz.geojson", &floorplan_options()),
        "osm",
    );
});
