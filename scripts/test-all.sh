#!/usr/bin/env bash
# Runs every test of the project: the Rust workspace (unit, property, end-to-end) and the
# Kotlin host tests against the real native library. Installs what it needs (Kotlin
# compiler from npm, JNA and JUnit from Debian) when missing. Exit status: non-zero if
# anything failed.
set -euo pipefail
cd "$(dirname "$0")/.."

LOG="${TMPDIR:-/tmp}/trailprint-cargo-test.$$.log"
echo "== Rust: cargo test --workspace (unit, integration, binaries)"
cargo test --workspace --lib --bins --tests 2>&1 | tee "$LOG"
# Doc tests run separately (the target selection above skips them).
cargo test --workspace --doc 2>&1 | tee -a "$LOG"
# Examples and benchmarks must keep compiling; running them is the benchmarks' job, not
# CI's (a type check is a fraction of an optimised build and link of six binaries).
cargo check --workspace --examples --benches --profile test 2>&1 | tee -a "$LOG"

if [ -x android-demo/scripts/kotlin-test.sh ]; then
  echo "== Kotlin: host JVM tests against the native library"
  android-demo/scripts/kotlin-test.sh
fi
