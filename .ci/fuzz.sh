#!/usr/bin/env bash
# Builds every fuzz target and runs each for a bounded time; fails on the first crash,
# invariant violation, timeout or out-of-memory.
#
#   .ci/fuzz.sh                 # 20 s per target, AddressSanitizer on
#   FUZZ_SECONDS=600 .ci/fuzz.sh
#   FUZZ_RUNS=10000000 FUZZ_SECONDS=2400 FUZZ_SANITIZER=none .ci/fuzz.sh   # the long run
#
# FUZZ_RUNS stops each target after that many executions (FUZZ_SECONDS still caps the
# time); FUZZ_SANITIZER is passed to `cargo fuzz --sanitizer` (address by default).
# Each target starts from its committed seeds (fuzz/corpus/seed_<target>/) and writes
# what it discovers to a scratch corpus, so the repository stays clean. A crash leaves
# its input in fuzz/artifacts/<target>/; reproduce with
# `cargo +nightly fuzz run <target> fuzz/artifacts/<target>/<file>`.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${FUZZ_SECONDS:-20}"
sanitizer="${FUZZ_SANITIZER:-address}"
runs=()
if [ -n "${FUZZ_RUNS:-}" ]; then
    runs=(-runs="$FUZZ_RUNS")
fi

# shellcheck source=.ci/nightly.sh
source .ci/nightly.sh
nightly_acquire
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi

cargo +"$NIGHTLY" fuzz build --sanitizer "$sanitizer"

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

for target in $(cargo +"$NIGHTLY" fuzz list); do
    echo "--- fuzz: $target (${seconds} s)"
    mkdir -p "$scratch/$target"
    seeds="fuzz/corpus/seed_$target"
    dirs=("$scratch/$target")
    if [ -d "$seeds" ]; then
        dirs+=("$seeds")
    fi
    cargo +"$NIGHTLY" fuzz run --sanitizer "$sanitizer" "$target" "${dirs[@]}" -- \
        -max_total_time="$seconds" ${runs[@]+"${runs[@]}"} -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1
done
echo "--- fuzz: every target ran without a crash"
