#!/usr/bin/env bash
# Instructions per detection on the Cortex-M4F (QEMU mps2-an386 with -icount), every head,
# through Rust and through C: `tools/m4f_counts.sh --check`. Fails when the counter does
# not count a loop of known length right, when two runs count differently, when the C
# API's scores (a checksum per head and table) differ from the Rust API's, or when C
# costs more than its bound over Rust per detection (tools/m4f_report.py). Runs after
# .ci/ffi.sh, which installs qemu-system-arm and arm-none-eabi-gcc; without them, or
# without the Cortex-M4F Rust target, it fails (MLMAP_ALLOW_SKIP=1 skips outside CI).
# Run from the repository root.
set -euo pipefail
[[ -f Cargo.toml && -d firmware ]] || {
    echo "m4f: run from the repository root" >&2
    exit 1
}
start=$SECONDS
printf '\n==== m4f: tools/m4f_counts.sh --check ====\n'
bash tools/m4f_counts.sh --check
printf '\n==== m4f: passed in %d s ====\n' "$((SECONDS - start))"
