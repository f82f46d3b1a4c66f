//! Every integration test of `trailprint-core`, in one test binary.
//!
//! Each file beside this one is a module of it (one topic a file, as before). One binary
//! instead of one per file: on a 2-core machine, compiling and linking ~25 test binaries
//! (each with its own copy of the generic code it instantiates) was most of CI's time.
//! The tests that measure time (time limits, cancellation lag, kills mid-write) are in
//! the second binary, `timing.rs`, where they run one at a time: in one process the tests
//! share rayon's thread pool, and another test's work would count in their timings.
//! `autotests = false` in `core/Cargo.toml` means a file declared in neither would not
//! run; [`every_test_file_is_a_module_of_a_test_binary`] fails when one is missing.

mod plan_common;
mod store_common;

mod cli_fit;
mod cli_part;
mod cli_pipe;
mod cli_store;
mod cli_surveyor;
mod cli_synth;
mod experiment_csv;
mod floorplan_cli;
mod floorplan_import;
mod fuzz_regressions;
mod localize;
mod plan_exact;
mod plan_props;
mod readme_examples;
mod session_api;
mod session_budget_cli;
mod session_cli;
mod store_api;
mod store_bad_inputs;
mod store_bundles;
mod store_migrations;
mod store_planning;
mod store_readers;
mod store_schema;
mod utility_props;

/// A test file added beside this one must be declared here or in `timing.rs`, or it would
/// silently not run.
#[test]
fn every_test_file_is_a_module_of_a_test_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let main = std::fs::read_to_string(dir.join("main.rs")).expect("main.rs")
        + &std::fs::read_to_string(dir.join("timing.rs")).expect("timing.rs");
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("tests dir") {
        let path = entry.expect("entry").path();
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("")
            .to_string();
        let is_module =
            (path.extension().is_some_and(|e| e == "rs") && name != "main" && name != "timing")
                || path.join("mod.rs").is_file();
        if is_module && !main.lines().any(|l| l.trim() == format!("mod {name};")) {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "declare in core/tests/main.rs: {missing:?}"
    );
}
