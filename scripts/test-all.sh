#!/usr/bin/env bash
# Runs every test of the project: the Rust workspace (unit, property, end-to-end) and the
# Kotlin host tests against the real native library. Installs what it needs (Kotlin
# compiler from npm, JNA and JUnit from Debian) when missing. Exit status: non-zero if
# anything failed.
set -euo pipefail
cd "$(dirname "$0")/.."

LOG="${TMPDIR:-/tmp}/trailprint-cargo-test.$$.log"
: >"$LOG"
failed=()
# Each step runs to its end (--no-fail-fast: one failing test binary does not hide the
# others) and the script reports every step that failed.
step() {
  local name="$1"; shift
  echo "== $name"
  if ! "$@" 2>&1 | tee -a "$LOG"; then failed+=("$name"); fi
}
# Formatting first (a second): unformatted code fails the run, as a reviewer would. Skipped
# with a message where the toolchain has no rustfmt component.
if cargo fmt --version >/dev/null 2>&1; then
  step "Rust: cargo fmt --all -- --check" cargo fmt --all -- --check
else
  echo "== Rust: formatting not checked (no rustfmt; rustup component add rustfmt)"
fi
# Examples are compiled with the tests (they hold no tests, so nothing runs): they must
# keep compiling, and running them is the benchmarks' job, not CI's.
step "Rust: cargo test --workspace (unit, integration, binaries, examples compile)" \
  cargo test --workspace --no-fail-fast --lib --bins --tests --examples
# The core's own tests as the phone builds it (no features: no research modules, no clap),
# so that the phone configuration keeps compiling and passing, not only the default one.
step "Rust: core unit tests without features (the phone's configuration)" \
  cargo test -p trailprint-core --no-default-features --no-fail-fast --lib
# Doc tests run separately (the target selection above skips them).
step "Rust: doc tests" cargo test --workspace --no-fail-fast --doc
# Benchmarks must keep compiling: built in the same profile and with the same features as
# the tests (a separate `cargo check` re-checked every dependency: 7 minutes), not run.
step "Rust: benchmarks compile" cargo test --workspace --benches --no-run

if [ -x android-demo/scripts/kotlin-test.sh ]; then
  # The Kotlin tests take the library and generator the Rust tests just built.
  step "Kotlin: host JVM tests against the native library" \
    env TRAILPRINT_PREBUILT=1 android-demo/scripts/kotlin-test.sh
fi

if [ "${#failed[@]}" -gt 0 ]; then
  echo "test-all: FAILED steps:"; printf '  - %s\n' "${failed[@]}"
  exit 1
fi
echo "test-all: every step passed"
