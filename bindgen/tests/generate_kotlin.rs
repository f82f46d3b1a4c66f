//! The generator, run as the Kotlin build runs it (library mode, `--no-format`), on the
//! native library this very test build produced: the Kotlin the app compiles against must
//! expose the planning and progress API it calls. Building this test also leaves the
//! generator at `target/<profile>/uniffi-bindgen` and the library in `target/<profile>/deps`,
//! which is what `scripts/test-all.sh` hands to the Kotlin tests without a second build.

use std::path::PathBuf;
use std::process::Command;

/// The cdylib of `trailprint-bindings` built for this test (a dev-dependency).
fn native_library() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let deps = exe.parent().expect("deps directory");
    let name = if cfg!(target_os = "macos") {
        "libtrailprint_ffi.dylib"
    } else {
        "libtrailprint_ffi.so"
    };
    deps.join(name)
}

#[test]
fn the_generated_kotlin_exposes_the_plan_and_progress_api_the_app_calls() {
    let lib = native_library();
    assert!(lib.is_file(), "no native library at {}", lib.display());
    let out = tempfile::tempdir().expect("tempdir");
    let status = Command::new(env!("CARGO_BIN_EXE_uniffi-bindgen"))
        .args(["generate", "--library"])
        .arg(&lib)
        .args(["--language", "kotlin", "--no-format", "--out-dir"])
        .arg(out.path())
        .output()
        .expect("run uniffi-bindgen");
    assert!(
        status.status.success(),
        "uniffi-bindgen failed: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    let kt = out.path().join("dev/trailprint/ffi/trailprint_ffi.kt");
    let text = std::fs::read_to_string(&kt)
        .unwrap_or_else(|e| panic!("no generated Kotlin at {}: {e}", kt.display()));
    // What android-demo/core-jvm calls (Trailprint.kt, PlanModel.kt, SurveyController.kt).
    for needle in [
        "open class TrailprintStore",
        "fun `newPlan`(`request`: PlanRequest): PlanJob",
        "open class PlanJob",
        "fun `cancel`()",
        "data class PlanProgress",
        "var `bestUtilityNats`: kotlin.Double?",
        "var `bestLengthM`: kotlin.Double?",
        "fun `startSession`(",
        "fun `defaultHumanProfile`()",
    ] {
        assert!(text.contains(needle), "generated Kotlin lacks {needle:?}");
    }
}
