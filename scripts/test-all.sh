#!/usr/bin/env bash
# Runs every test of the project: the Rust workspace (unit, property, end-to-end) and the
# Kotlin host tests against the real native library. Installs what it needs (Kotlin
# compiler from npm, JNA and JUnit from Debian) when missing. Exit status: non-zero if
# anything failed.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== Rust: cargo test --workspace"
cargo test --workspace --all-targets 2>&1 | tee /tmp/trailprint-cargo-test.log
# Doc tests run separately (--all-targets skips them).
cargo test --workspace --doc 2>&1 | tee -a /tmp/trailprint-cargo-test.log

if [ -x android-demo/scripts/kotlin-test.sh ]; then
  echo "== Kotlin: host JVM tests against the native library"
  android-demo/scripts/kotlin-test.sh
fi
