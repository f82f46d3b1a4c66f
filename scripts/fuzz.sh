#!/usr/bin/env bash
# Runs every fuzz target (fuzz/fuzz_targets/*.rs, libFuzzer through cargo-fuzz) for DURATION
# each, one after the other, and prints per target the executions, the coverage (cov and ft,
# libFuzzer's final figures) and the crashes, out-of-memory and timeout inputs found.
#
#   scripts/fuzz.sh DURATION [TARGET...]     DURATION: 90s, 10m, 1h (or plain seconds)
#   scripts/fuzz.sh replay TARGET FILE...    runs TARGET once on each FILE (a crash prints
#                                            the panic; nothing is written outside artifacts/)
#
# Needs the nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`). CI does not run it.
# Each target runs in libFuzzer's fork mode with one worker, so a crash does not end the run:
# every crashing input goes to fuzz/artifacts/TARGET/ and the run goes on (the fuzzer runs
# in that directory, so no input file can land anywhere else). Memory is capped
# (an input that makes a parser allocate hugely is reported as an OOM), so is time per input.
# New corpus entries go to fuzz/target/corpus-work/TARGET (seeded from the committed
# fuzz/corpus/TARGET, which this script never changes; see docs/fuzzing.md to merge them).
#
# Environment: FUZZ_NICE (default 10) niceness; FUZZ_RSS_MB (2048) and FUZZ_MALLOC_MB (1024)
# the memory caps; FUZZ_TIMEOUT_S (10) seconds per input; FUZZ_MAX_LEN (65536) input bytes.
# Exit status: 1 if any target found a crash, OOM or timeout, else 0.
set -euo pipefail
caller_dir=$(pwd)
cd "$(dirname "$0")/../fuzz"

if [ $# -lt 1 ]; then
  sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
nice_n=${FUZZ_NICE:-10}
rss=${FUZZ_RSS_MB:-2048}
malloc=${FUZZ_MALLOC_MB:-1024}
timeout=${FUZZ_TIMEOUT_S:-10}
max_len=${FUZZ_MAX_LEN:-65536}
fuzz_dir=$(pwd)

build() {
  echo "== building the fuzz targets (cargo +nightly fuzz build)"
  nice -n "$nice_n" cargo +nightly fuzz build -O --debug-assertions
  bin_dir=$fuzz_dir/target/$(rustc +nightly -vV | sed -n 's/^host: //p')/release
}

if [ "$1" = replay ]; then
  if [ $# -lt 3 ]; then
    echo "usage: scripts/fuzz.sh replay TARGET FILE..." >&2
    exit 2
  fi
  t=$2
  shift 2
  files=()
  for f in "$@"; do files+=("$(cd "$caller_dir" && realpath -e "$f")"); done
  build
  mkdir -p "artifacts/$t"
  # Run in artifacts/TARGET: libFuzzer writes a crashing input again as crash-SHA1 (there).
  cd "artifacts/$t"
  status=0
  for f in "${files[@]}"; do
    echo "== $t < $f"
    "$bin_dir/$t" -rss_limit_mb="$rss" -malloc_limit_mb="$malloc" -timeout="$timeout" \
      -artifact_prefix="$fuzz_dir/artifacts/$t/" "$f" || status=1
  done
  exit "$status"
fi

duration=$1
shift
case "$duration" in
  *h) secs=$(( ${duration%h} * 3600 )) ;;
  *m) secs=$(( ${duration%m} * 60 )) ;;
  *s) secs=${duration%s} ;;
  *) secs=$duration ;;
esac
if ! [[ "$secs" =~ ^[0-9]+$ ]] || [ "$secs" -le 0 ]; then
  echo "fuzz.sh: DURATION must be like 90s, 10m or 1h, got '$duration'" >&2
  exit 2
fi

if [ $# -gt 0 ]; then
  targets=("$@")
else
  targets=()
  for f in fuzz_targets/*.rs; do targets+=("$(basename "$f" .rs)"); done
fi

for t in "${targets[@]}"; do
  if [ ! -f "fuzz_targets/$t.rs" ]; then
    echo "fuzz.sh: no target $t (fuzz/fuzz_targets/$t.rs)" >&2
    exit 2
  fi
done
build

found=0
summary=()
for t in "${targets[@]}"; do
  work=$fuzz_dir/target/corpus-work/$t
  art=$fuzz_dir/artifacts/$t
  mkdir -p "$work" "$art" corpus/"$t"
  log=$fuzz_dir/target/fuzz-$t.log
  before=$(find "$art" -type f | wc -l)
  echo "== $t: ${secs}s (log $log)"
  start=$(date +%s)
  # Fork mode: crashes, OOMs and timeouts are counted and kept, and fuzzing goes on. The
  # binary is run directly (after a crash `cargo fuzz run` rebuilds to print the input), in
  # the artifacts directory, so that whatever libFuzzer writes lands there.
  (cd "$art" && exec nice -n "$nice_n" "$bin_dir/$t" "$work" "$fuzz_dir/corpus/$t" \
    -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
    -max_total_time="$secs" -rss_limit_mb="$rss" -malloc_limit_mb="$malloc" \
    -timeout="$timeout" -max_len="$max_len" -print_final_stats=1 \
    -artifact_prefix="$art/") >"$log" 2>&1 || true
  wall=$(( $(date +%s) - start ))
  # The last status line of fork mode: "#EXECS: cov: C ft: F corp: N exec/s: R
  # oom/timeout/crash: O/T/X time: Ss job: J ...".
  last=$(grep -E '^#[0-9]+: cov: ' "$log" | tail -n 1 || true)
  if [ -z "$last" ]; then
    echo "   $t: no status line; the end of the log:"
    tail -n 20 "$log"
    summary+=("$(printf '%-16s %12s %7s %7s %8s %16s %6s' "$t" "-" "-" "-" "-" "did not run" "${wall}s")")
    found=1
    continue
  fi
  execs=$(sed -E 's/^#([0-9]+):.*/\1/' <<<"$last")
  cov=$(sed -E 's/.* cov: ([0-9]+).*/\1/' <<<"$last")
  ft=$(sed -E 's/.* ft: ([0-9]+).*/\1/' <<<"$last")
  corp=$(sed -E 's/.* corp: ([0-9]+).*/\1/' <<<"$last")
  oom_to_crash=$(sed -E 's/.* oom\/timeout\/crash: ([0-9]+\/[0-9]+\/[0-9]+).*/\1/' <<<"$last")
  after=$(find "$art" -type f | wc -l)
  new=$(( after - before ))
  if [ "$oom_to_crash" != "0/0/0" ] || [ "$new" -gt 0 ]; then found=1; fi
  summary+=("$(printf '%-16s %12s %7s %7s %8s %16s %6s' "$t" "$execs" "$cov" "$ft" "$corp" "$oom_to_crash ($new new)" "${wall}s")")
done

echo
echo "== summary (${secs}s per target; artifacts in fuzz/artifacts/TARGET/)"
printf '%-16s %12s %7s %7s %8s %16s %6s\n' target executions cov ft corpus oom/timeout/crash wall
for line in "${summary[@]}"; do echo "$line"; done
exit "$found"
