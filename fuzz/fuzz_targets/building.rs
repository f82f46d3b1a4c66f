//! The building JSON parser and validator (`survey-building/1`, SPEC 7), and the store's
//! import of it.
//!
//! Invariants: a refused file is an `Err` of the parse or building kind (never a panic, never
//! another kind), and the store refuses it too and is left unchanged; an accepted file means
//! what it says (validation changes nothing but the spelling of the default floor), its export
//! is accepted again and exports to the same text, and the store keeps it unchanged; memory
//! and time stay bounded (libFuzzer's `-rss_limit_mb`, `-malloc_limit_mb` and `-timeout`).
#![no_main]

use std::cell::RefCell;

use libfuzzer_sys::fuzz_target;
use trailprint::building::BuildingFile;
use trailprint::store::{ImportOptions, Store};
use trailprint::{Building, Error};
use trailprint_fuzz::{check_reexport, snapshot, without_counters};

thread_local! {
    static STORE: RefCell<Option<Store>> = const { RefCell::new(None) };
}

fuzz_target!(|data: &[u8]| {
    // Files are read as UTF-8 text (`read_to_string`); other bytes never reach the parser.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let parsed = BuildingFile::parse(text, "fuzz");
    let result = Building::from_json(text, "fuzz");
    STORE.with(|cell| {
        let mut cell = cell.borrow_mut();
        let store = cell.get_or_insert_with(|| match Store::open_in_memory() {
            Ok(s) => s,
            Err(e) => panic!("in-memory store: {e}"),
        });
        let before = snapshot(store);
        let imported = store.import_json(text, "fuzz", &ImportOptions::default());
        match result {
            Err(e) => {
                assert!(
                    matches!(e, Error::Parse { .. } | Error::InvalidBuilding { .. }),
                    "refused with an error of the wrong kind: {e:?}"
                );
                assert!(!e.to_string().is_empty());
                assert!(
                    imported.is_err(),
                    "the store accepts what the validator refuses"
                );
                assert_eq!(
                    before,
                    snapshot(store),
                    "a refused import changed the store"
                );
            }
            Ok(b) => {
                let file = match parsed {
                    Ok(f) => f,
                    Err(e) => panic!("validated but does not parse: {e}"),
                };
                check_reexport(&b, Some(&file), "building");
                let report = match imported {
                    Ok(r) => r,
                    Err(e) => panic!("the store refuses a valid building: {e}"),
                };
                let back = match store.export_building(report.id) {
                    Ok(f) => f,
                    Err(e) => panic!("the store cannot give back what it took: {e}"),
                };
                assert_eq!(back, b.to_file(), "the store changed the building");
                if let Err(e) = store.delete_building(report.id) {
                    panic!("delete: {e}");
                }
                // Deleting it leaves the store as it was (autoincrement counters aside).
                assert_eq!(
                    without_counters(before),
                    without_counters(snapshot(store)),
                    "delete left rows behind"
                );
            }
        }
    });
});
