#!/usr/bin/env bash
# Builds every fuzz target and runs each for a bounded time; fails on the first crash,
# invariant violation, timeout or out-of-memory.
#
#   .ci/fuzz.sh                 # 20 s per target
#   FUZZ_SECONDS=600 .ci/fuzz.sh
#
# Each target starts from its committed seeds (fuzz/corpus/seed_<target>/) and writes
# what it discovers to a scratch corpus, so the repository stays clean. A crash leaves
# its input in fuzz/artifacts/<target>/; reproduce with
# `cargo +nightly fuzz run <target> fuzz/artifacts/<target>/<file>`.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${FUZZ_SECONDS:-20}"

if ! rustup run nightly rustc --version >/dev/null 2>&1; then
    rustup toolchain install nightly --profile minimal
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi

cargo +nightly fuzz build

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

for target in $(cargo +nightly fuzz list); do
    echo "--- fuzz: $target (${seconds} s)"
    mkdir -p "$scratch/$target"
    seeds="fuzz/corpus/seed_$target"
    dirs=("$scratch/$target")
    if [ -d "$seeds" ]; then
        dirs+=("$seeds")
    fi
    cargo +nightly fuzz run "$target" "${dirs[@]}" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
done
echo "--- fuzz: every target ran ${seconds} s without a crash"
