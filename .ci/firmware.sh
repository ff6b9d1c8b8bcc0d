#!/usr/bin/env bash
# Proof (d): the firmware example `firmware/` runs on an emulated Cortex-M4F (QEMU
# `-machine mps2-an386`), with the table decoded from a calibration sector and the one
# embedded at build time, and every score matches the host's float64 values
# (`tools/firmware_expected.py`). Also shows the run can fail: a canary build with one
# perturbed expected ML score, one perturbed open-head score, one perturbed score after
# a recalibration map, one perturbed window PSI of the drift monitor's replay and one
# flipped conformal set must exit non-zero and report all five. Installs qemu-system-arm if
# missing; without a Cortex-M4F toolchain the proof fails (MLMAP_ALLOW_SKIP=1 skips it outside CI).
# Run from the repository root.
set -euo pipefail

section() { printf '\n==== firmware: %s ====\n' "$*"; }
fail() {
    printf 'firmware: FAILED: %s\n' "$*" >&2
    exit 1
}
[[ -f Cargo.toml && -d firmware ]] || fail "run from the repository root"
start=$SECONDS
# shellcheck source=.ci/thumb-toolchain.sh
source .ci/thumb-toolchain.sh

section "qemu-system-arm"
if ! command -v qemu-system-arm >/dev/null; then
    echo "apt-get install -y --no-install-recommends qemu-system-arm"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        qemu-system-arm >/dev/null
fi
qemu-system-arm --version | head -n 1
qemu-system-arm -machine help | grep -q '^mps2-an386 ' ||
    fail "this qemu-system-arm has no mps2-an386 machine"

section "expected values: firmware/src/expected.rs matches the table and the generator"
if ! python3 -c 'import numpy' 2>/dev/null; then
    echo "python3 -m pip install numpy"
    python3 -m pip install --quiet numpy
fi
python3 tools/firmware_expected.py --check
python3 tools/lidar_goldens.py --check

section "toolchain for $THUMB_TARGET"
thumb_acquire
if [[ "$THUMB_VIA" == none ]]; then
    thumb_skipped_banner "the firmware run on the emulated Cortex-M4F"
fi
echo "toolchain: $THUMB_VIA"

# The firmware compares the build-time table with the default file.
unset MLMAP_TABLE
# From its directory: its .cargo/config.toml selects the target and the linker script.
cd firmware
elf="$(thumb_out_dir firmware)/mlmap-firmware"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run_qemu() { # $1 = ELF; prints the firmware's output, returns QEMU's exit status
    timeout 120 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
        -semihosting-config enable=on,target=native -kernel "$1" </dev/null
}

section "canary: perturbed expected values must fail the run"
thumb_cargo build --profile firmware --features canary
cp "$elf" "$work/canary.elf"
status=0
run_qemu "$work/canary.elf" >"$work/canary.log" 2>&1 || status=$?
sed 's/^/canary| /' "$work/canary.log"
[[ $status -ne 0 ]] || fail "the canary firmware exited 0: a wrong score would not fail the run"
[[ $status -ne 124 ]] || fail "the canary firmware timed out"
grep -qE '^[0-9]+ passed, [1-9][0-9]* failed$' "$work/canary.log" ||
    fail "the canary firmware did not report its failures"
grep -qE '^FAIL .*: [a-z ]+ ML: got' "$work/canary.log" ||
    fail "the canary firmware did not fail on its perturbed ML score"
grep -qE '^FAIL .*: [a-z ]+ open: got' "$work/canary.log" ||
    fail "the canary firmware did not fail on its perturbed open-head score"
grep -qE '^FAIL .*: small table with maps open: got' "$work/canary.log" ||
    fail "the canary firmware did not fail on its perturbed score after a map"
grep -qE '^FAIL monitor window: .* monitor: got' "$work/canary.log" ||
    fail "the canary firmware did not fail on its perturbed monitor window"
grep -qE '^FAIL .*: .* set: got mask' "$work/canary.log" ||
    fail "the canary firmware did not fail on its flipped conformal set"
echo "ok: the canary firmware failed as it must (exit status $status)"

section "build: cargo build --profile firmware --target $THUMB_TARGET (via $THUMB_VIA)"
thumb_cargo build --profile firmware
size -A "$elf" | grep -E '^\.(vector_table|text|rodata|calib|data|bss) ' || true

section "run on qemu-system-arm -cpu cortex-m4 -machine mps2-an386"
status=0
run_qemu "$elf" | tee "$work/run.log" || status=$?
[[ $status -ne 124 ]] || fail "the firmware timed out (120 s)"
[[ $status -eq 0 ]] || fail "the firmware exited with status $status"
grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/run.log" ||
    fail "the firmware exited 0 but did not report 'N passed, 0 failed'"

section "passed in $((SECONDS - start)) s: the firmware ran on the emulated Cortex-M4F"
