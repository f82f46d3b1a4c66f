//! The OpenStreetMap indoor (Simple Indoor Tagging) GeoJSON importer.
//!
//! Invariants: a refused plan is an `Err`, never a panic; an accepted one is a building that
//! passes validation and re-exports to an equal building; memory and time stay bounded
//! (libFuzzer's `-rss_limit_mb`, `-malloc_limit_mb` and `-timeout`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use trailprint::floorplan::{ImportOptions, import_osm_text};
use trailprint_fuzz::check_floorplan;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    check_floorplan(
        import_osm_text(text, "fuzz.geojson", &ImportOptions::default()),
        "osm",
    );
});
