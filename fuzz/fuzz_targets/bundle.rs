//! The survey bundle parser and merge (`trailprint-bundle/1`), against a store holding the
//! bundle's building and a session.
//!
//! Each input is imported twice into the base store (rebuilt after any accepted bundle): as
//! given (where the checksum almost always refuses it), and with its checksum recomputed, so
//! that the fuzzer reaches the parser of the body and the merge. Invariants: a refused bundle leaves the store
//! row for row unchanged; an accepted one imports again as a no-op (merging is idempotent);
//! every error is an `Err`, never a panic.
//!
//! `TRAILPRINT_FUZZ_SEEDS=DIR` writes the seed bundles to DIR and exits (how
//! `fuzz/corpus/bundle` was made).
#![no_main]

use std::cell::RefCell;

use libfuzzer_sys::fuzz_target;
use trailprint::store::Store;
use trailprint_fuzz::{bundle_base, bundle_checksum, bundle_seeds, snapshot};

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
                *cell = None;
            }
        }
    });
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
