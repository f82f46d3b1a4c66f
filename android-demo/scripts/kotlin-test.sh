#!/usr/bin/env bash
# Host JVM tests of the Kotlin side, against the real native library.
#
#   bash android-demo/scripts/kotlin-test.sh            # build, generate, compile, test
#   bash android-demo/scripts/kotlin-test.sh --demo     # ... then run the host demo
#   bash android-demo/scripts/kotlin-test.sh --demo-only
#
# Installs what is missing: the Kotlin compiler (npm package kotlin-compiler, into
# $TRAILPRINT_TOOLS, default ~/.cache/trailprint) and JNA + JUnit 4 (Debian packages).
# Builds the cdylib with cargo (CARGO_TARGET_DIR is respected), generates the uniffi Kotlin
# bindings into android-demo/core-jvm/build/generated/uniffi (gitignored), compiles the
# Android-free module core-jvm (main + test sources + bindings) in one kotlinc run, and runs
# every *Test class with JUnit 4. Prints one line `kotlin: N passed, N failed`; exits 1 on
# any failure.
set -euo pipefail

KOTLIN_VERSION=2.4.20
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
demo_dir="$(dirname "$here")"
repo="$(dirname "$demo_dir")"
module="$demo_dir/core-jvm"
build="$module/build"
gen="$build/generated/uniffi"
classes="$build/kotlin-classes"
# Cargo profile of the native library. `test` (the default) is the profile `cargo test`
# builds with, so after the Rust tests the library costs one crate's compile, not a second
# build of every dependency; `release` for the demo at full speed.
profile="${TRAILPRINT_PROFILE:-test}"
[[ "$profile" == debug ]] && profile=dev # cargo's name for target/debug's own profile

run_tests=1
run_demo=0
for arg in "$@"; do
  case "$arg" in
    --demo) run_demo=1 ;;
    --demo-only) run_demo=1; run_tests=0 ;;
    -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
    *) echo "kotlin-test.sh: unknown argument $arg (try --help)" >&2; exit 2 ;;
  esac
done

log() { echo "kotlin-test: $*" >&2; }

# --- tools -----------------------------------------------------------------------------
tools="${TRAILPRINT_TOOLS:-$HOME/.cache/trailprint}/kotlin"
kotlin_home="$tools/node_modules/kotlin-compiler"
if [[ ! -x "$kotlin_home/bin/kotlinc" || "$(cat "$kotlin_home/build.txt" 2>/dev/null)" != "$KOTLIN_VERSION" ]]; then
  log "installing kotlin-compiler@$KOTLIN_VERSION into $tools"
  mkdir -p "$tools"
  npm install --prefix "$tools" --no-audit --no-fund --loglevel=error "kotlin-compiler@$KOTLIN_VERSION" >&2
fi
kotlinc="$kotlin_home/bin/kotlinc"
klib="$kotlin_home/lib"

find_jar() { # first existing jar among the arguments
  for j in "$@"; do [[ -f "$j" ]] && { echo "$j"; return 0; }; done
  return 1
}
jars_present() {
  find_jar /usr/share/java/jna.jar /usr/share/java/jna-5.13.0.jar >/dev/null &&
    find_jar /usr/share/java/junit4.jar >/dev/null &&
    find_jar /usr/share/java/hamcrest-core.jar /usr/share/java/hamcrest.jar >/dev/null
}
if ! jars_present; then
  log "installing Debian packages libjna-java junit4"
  sudo_=""
  [[ "$(id -u)" != 0 ]] && sudo_="sudo"
  $sudo_ apt-get update -qq >&2
  DEBIAN_FRONTEND=noninteractive $sudo_ apt-get install -y -qq libjna-java junit4 >&2
fi
jna="$(find_jar /usr/share/java/jna.jar /usr/share/java/jna-5.13.0.jar)"
junit="$(find_jar /usr/share/java/junit4.jar)"
hamcrest="$(find_jar /usr/share/java/hamcrest-core.jar /usr/share/java/hamcrest.jar)"

# --- native library and bindings ---------------------------------------------------------
cd "$repo"
target_dir="${CARGO_TARGET_DIR:-}"
if [[ -z "$target_dir" ]]; then
  target_dir="$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')"
fi
case "$profile" in # the output folder: dev and test share target/debug
  dev | test) outdir="$target_dir/debug" ;;
  *) outdir="$target_dir/$profile" ;;
esac
case "$(uname -s)" in
  Darwin) libname="libtrailprint_ffi.dylib" ;;
  *) libname="libtrailprint_ffi.so" ;;
esac
bindgen="$outdir/uniffi-bindgen"
if [[ -n "${TRAILPRINT_PREBUILT:-}" ]]; then
  # scripts/test-all.sh: `cargo test --workspace` has just built the library (as a
  # dependency of the bindgen test, into deps/) and the generator (for that test). A
  # `cargo build -p trailprint-bindings` would resolve features without the workspace's
  # dev-dependencies and compile the core a second time (minutes on two cores).
  libdir="$outdir/deps"
  log "using the library and generator the Rust tests built ($libdir)"
else
  cargo_flags=(-p trailprint-bindings -p trailprint-uniffi-bindgen --profile "$profile")
  log "cargo build ${cargo_flags[*]} (target $target_dir)"
  cargo build -q "${cargo_flags[@]}" >&2
  libdir="$outdir"
fi
lib="$libdir/$libname"
[[ -f "$lib" ]] || { log "no native library at $lib"; exit 1; }
[[ -x "$bindgen" ]] || { log "no uniffi-bindgen at $bindgen"; exit 1; }

# Regenerate the bindings only when the library changed.
stamp="$gen/.library.sha256"
lib_hash="$(sha256sum "$lib" | cut -d' ' -f1)"
if [[ "$(cat "$stamp" 2>/dev/null)" != "$lib_hash" ]]; then
  log "generating Kotlin bindings into ${gen#"$repo"/}"
  rm -rf "$gen"
  mkdir -p "$gen"
  "$bindgen" generate --library "$lib" --language kotlin --out-dir "$gen" --no-format >&2
  echo "$lib_hash" >"$stamp"
fi

# --- compile (one kotlinc run, skipped when no input changed) ------------------------------
cp_compile="$klib/kotlin-stdlib.jar:$klib/kotlinx-coroutines-core-jvm.jar:$klib/kotlin-test.jar:$klib/kotlin-test-junit.jar:$jna:$junit:$hamcrest"
mapfile -t sources < <(find "$module/src/main/kotlin" "$module/src/test/kotlin" "$gen" -name '*.kt' | LC_ALL=C sort)
src_hash="$( (echo "$KOTLIN_VERSION"; sha256sum "${sources[@]}") | sha256sum | cut -d' ' -f1)"
if [[ "$(cat "$classes/.sources.sha256" 2>/dev/null)" != "$src_hash" ]]; then
  log "kotlinc: ${#sources[@]} files"
  rm -rf "$classes"
  mkdir -p "$classes"
  JAVA_OPTS="${JAVA_OPTS:--Xmx2g}" "$kotlinc" -jvm-target 17 -no-stdlib -no-reflect \
    -cp "$cp_compile" -d "$classes" -nowarn "${sources[@]}" >&2
  echo "$src_hash" >"$classes/.sources.sha256"
else
  log "kotlinc: sources unchanged, reusing ${classes#"$repo"/}"
fi

cp_run="$classes:$cp_compile"
java_flags=(-Djna.library.path="$libdir" -Dtrailprint.repo="$repo" -cp "$cp_run")

status=0
if (( run_tests )); then
  java "${java_flags[@]}" dev.trailprint.testing.RunTestsKt "$classes" || status=$?
fi
if (( run_demo )); then
  java "${java_flags[@]}" dev.trailprint.demo.HostDemoKt ${TRAILPRINT_DEMO_BUILDING:+"$TRAILPRINT_DEMO_BUILDING"} || status=$?
fi
exit "$status"
