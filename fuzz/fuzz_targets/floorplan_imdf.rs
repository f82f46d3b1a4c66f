//! The IMDF importer: a zip archive (input starting with `PK`), or the data set's files given
//! in memory, separated by NUL bytes, in the order `level`, `unit`, `opening`, `amenity`,
//! `relationship`, `venue`, `building` (a missing part is a missing file).
//!
//! Invariants: as for the OSM importer (`trailprint_fuzz::check_floorplan`: an `Err` and
//! never a panic for a refused plan, the store row for row unchanged; an accepted plan is a
//! valid building that re-exports to an equal one and that a store in memory takes and gives
//! back equal; bounded memory and time).
//!
//! Plans are imported with `trailprint_fuzz::floorplan_options()`: the grid is capped at
//! 5,000 cells (`FLOORPLAN_MAX_GRID_CELLS`) instead of the product's 100,000, so that a
//! legitimately large network does not count as a timeout.
#![no_main]

use std::collections::HashMap;

use libfuzzer_sys::fuzz_target;
use trailprint::floorplan::imdf::LAYERS;
use trailprint::floorplan::{import_imdf_files, import_imdf_zip};
use trailprint_fuzz::{check_floorplan, floorplan_options};

fuzz_target!(|data: &[u8]| {
    let options = floorplan_options();
    if data.starts_with(b"PK") {
        check_floorplan(import_imdf_zip(data, "fuzz.zip", &options), "imdf zip");
        return;
    }
    let mut files = HashMap::new();
    for (name, part) in LAYERS.iter().zip(data.split(|&b| b == 0)) {
        let Ok(text) = std::str::from_utf8(part) else {
            return;
        };
        if !text.is_empty() {
            files.insert(name.to_string(), text.to_string());
        }
    }
    check_floorplan(import_imdf_files(&files, "fuzz-imdf", &options), "imdf");
});
