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
step "Rust: cargo test --workspace (unit, integration, binaries)" \
  cargo test --workspace --no-fail-fast --lib --bins --tests
# Doc tests run separately (the target selection above skips them).
step "Rust: doc tests" cargo test --workspace --no-fail-fast --doc
# Examples and benchmarks must keep compiling; running them is the benchmarks' job, not
# CI's (a type check is a fraction of an optimised build and link of six binaries).
step "Rust: examples and benchmarks compile" \
  cargo check --workspace --examples --benches --profile test

if [ -x android-demo/scripts/kotlin-test.sh ]; then
  step "Kotlin: host JVM tests against the native library" android-demo/scripts/kotlin-test.sh
fi

if [ "${#failed[@]}" -gt 0 ]; then
  echo "test-all: FAILED steps:"; printf '  - %s\n' "${failed[@]}"
  exit 1
fi
echo "test-all: every step passed"
