//! The survey bundle parser and merge (`trailprint-bundle/1`), against a store holding the
//! bundle's building and a session.
//!
//! Each input is imported twice into the base store (rebuilt after any accepted bundle): as
//! given (where the checksum almost always refuses it), and with its checksum recomputed, so
//! that the fuzzer reaches the parser of the body and the merge. Invariants: a refused
//! bundle leaves the store row for row unchanged; an accepted one imports again as a no-op
//! (merging is idempotent), every building in the store then re-exports to an equal
//! building, and a building the bundle brought is the bundle's building as the validator
//! reads it; every error is an `Err`, never a panic; memory and time stay bounded
//! (libFuzzer's `-rss_limit_mb`, `-malloc_limit_mb` and `-timeout`).
//!
//! `TRAILPRINT_FUZZ_SEEDS=DIR` writes the seed bundles to DIR and exits (how
//! `fuzz/corpus/bundle` was made).
#![no_main]

use std::cell::RefCell;

use libfuzzer_sys::fuzz_target;
use trailprint::Building;
use trailprint::store::{Store, parse_bundle};
use trailprint_fuzz::{bundle_base, bundle_checksum, bundle_seeds, check_reexport, snapshot};

thread_local! {
    /// The base store and its snapshot, kept while bundles are refused (a refusal must leave
    /// it unchanged, which is checked); rebuilt after an accepted bundle changed it.
    static BASE: RefCell<Option<(Store, Vec<String>)>> = const { RefCell::new(None) };
}

fn import_checked(text: &str) {
    BASE.with(|cell| {
        let mut cell = cell.borrow_mut();
        let (store, before) = cell.get_or_insert_with(|| {
            let s = bundle_base();
            let snap = snapshot(&s);
            (s, snap)
        });
        let names_before = match store.list_buildings() {
            Ok(v) => v.into_iter().map(|b| b.name).collect::<Vec<_>>(),
            Err(e) => panic!("list buildings: {e}"),
        };
        match store.import_bundle(text, "fuzz") {
            Err(e) => {
                assert!(!e.to_string().is_empty());
                assert_eq!(
                    *before,
                    snapshot(store),
                    "a refused bundle changed the store: {e}"
                );
            }
            Ok(first) => {
                let after = snapshot(store);
                let again = match store.import_bundle(text, "fuzz") {
                    Ok(r) => r,
                    Err(e) => {
                        panic!("an accepted bundle ({first:?}) is refused the second time: {e}")
                    }
                };
                assert_eq!(
                    (
                        again.sessions_added,
                        again.sessions_extended,
                        again.events_added
                    ),
                    (0, 0, 0),
                    "importing the same bundle twice changed something: {again:?}"
                );
                assert_eq!(
                    after,
                    snapshot(store),
                    "the second import changed the store"
                );
                check_buildings(store, text, &names_before);
                *cell = None;
            }
        }
    });
}

/// After an accepted bundle: every building of the store re-exports to an equal building,
/// and the bundle's building, if it was new to the store, is stored as the validator reads
/// it from the bundle.
fn check_buildings(store: &Store, text: &str, names_before: &[String]) {
    let body = match parse_bundle(text, "fuzz") {
        Ok((_, body)) => body,
        Err(e) => panic!("an accepted bundle does not parse again: {e}"),
    };
    let given = match Building::from_file(body.building.clone(), "bundle building") {
        Ok(b) => b,
        Err(e) => panic!("a bundle was accepted with a building the validator refuses: {e}"),
    };
    let infos = match store.list_buildings() {
        Ok(v) => v,
        Err(e) => panic!("list buildings: {e}"),
    };
    assert!(
        infos.iter().any(|i| i.name == given.name),
        "the bundle's building {:?} is not in the store",
        given.name
    );
    for info in infos {
        let b = match store.get_building(info.id) {
            Ok(b) => b,
            Err(e) => panic!("building {:?} cannot be read back: {e}", info.name),
        };
        check_reexport(&b, None, "bundle: stored building");
        if info.name == given.name && !names_before.contains(&info.name) {
            assert_eq!(
                b.to_file(),
                given.to_file(),
                "the store changed the bundle's building"
            );
        }
    }
}

fuzz_target!(
    init: {
        if let Some(dir) = std::env::var_os("TRAILPRINT_FUZZ_SEEDS") {
            let dir = std::path::PathBuf::from(dir);
            for (name, text) in bundle_seeds() {
                if let Err(e) = std::fs::write(dir.join(format!("{name}.json")), text) {
                    panic!("{}: {e}", dir.display());
                }
            }
            std::process::exit(0);
        }
    },
    |data: &[u8]| {
        let Ok(text) = std::str::from_utf8(data) else {
            return;
        };
        import_checked(text);
        // The same document with a correct checksum.
        let Ok(serde_json::Value::Object(mut doc)) = serde_json::from_str(text) else {
            return;
        };
        let Some(body) = doc.get("body") else {
            return;
        };
        let sha = bundle_checksum(body);
        if doc.get("sha256").and_then(|s| s.as_str()) == Some(sha.as_str()) {
            return;
        }
        doc.insert("sha256".into(), serde_json::Value::String(sha));
        import_checked(&serde_json::Value::Object(doc).to_string());
    }
);
