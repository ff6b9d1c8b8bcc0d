#!/usr/bin/env bash
# The C API (ffi/), run from the repository root:
#   1. include/mlmap.h equals a fresh cbindgen generation (pinned cbindgen version);
#   2. the x86-64 static library links into C programs with no panic path (its panic
#      handler references a symbol defined nowhere; a canary build must fail the link)
#      and references no allocator;
#   3. the Rust test of the entry points, and the host C test ffi/tests/host.c: every
#      function and status, NULL and short buffers, every single-byte corruption,
#      every aliasing rule, scores of every head equal bit for bit to `mlmap apply`, the
#      open head within 1e-6 of the float64 reference (tests/golden/layer); the quantized
#      C test ffi/tests/quantized.c: int8 and int16 sections, every call and status, the
#      scores of every head equal bit for bit to `mlmap apply --quantized`; then both again
#      under -fsanitize=address,undefined, with the release library and with one built
#      with nightly's -Zsanitizer=address (a canary read past a buffer must be caught);
#   4. the C example ffi/firmware/ on an emulated Cortex-M4F (arm-none-eabi-gcc, the
#      thumbv7em-none-eabihf static library, QEMU mps2-an386): scores of every head, and
#      the open head of a table with T = 1.75 and epsilon = 0.05, equal bit for bit to
#      the host library's; a canary build with perturbed values must fail.
# Installs cbindgen (cargo install), gcc-arm-none-eabi, libnewlib-arm-none-eabi and
# qemu-system-arm (apt-get) when missing, and uses the pinned nightly (.ci/nightly.sh);
# without a cross compiler or Cortex-M4F Rust target, step 4 fails (MLMAP_ALLOW_SKIP=1
# skips it outside CI).
set -euo pipefail

section() { printf '\n==== ffi: %s ====\n' "$*"; }
fail() {
    printf 'ffi: FAILED: %s\n' "$*" >&2
    exit 1
}
[[ -f Cargo.toml && -d ffi ]] || fail "run from the repository root"
start=$SECONDS
CBINDGEN_VERSION=0.29.4
root=$PWD
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
unset MLMAP_TABLE MLMAP_MAX_CLASSES MLMAP_MAX_BINS MLMAP_MAX_BINS_BAYES

apt_install() { # packages...
    echo "apt-get install -y --no-install-recommends $*"
    { apt-get update -qq &&
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@" \
            >/dev/null; } || echo "ffi: could not install $*"
}

section "header: include/mlmap.h equals a fresh cbindgen $CBINDGEN_VERSION generation"
if [[ "$(cbindgen --version 2>/dev/null)" != "cbindgen $CBINDGEN_VERSION" ]]; then
    echo "cargo install cbindgen --version $CBINDGEN_VERSION --locked"
    cargo install cbindgen --version "$CBINDGEN_VERSION" --locked --quiet
fi
cbindgen --config ffi/cbindgen.toml --output "$work/mlmap.h" ffi 2>"$work/cbindgen.log" ||
    { cat "$work/cbindgen.log" >&2; fail "cbindgen failed"; }
if ! diff -u include/mlmap.h "$work/mlmap.h"; then
    fail "include/mlmap.h is stale: run \`cbindgen --config ffi/cbindgen.toml --output include/mlmap.h ffi\` and commit it"
fi
echo "ok: include/mlmap.h is up to date"

section "x86-64 static library (cargo rustc --profile release-abort --crate-type staticlib: LTO)"
cargo rustc -p mlmap-ffi --profile release-abort --crate-type staticlib --quiet
lib=target/release-abort/libmlmap_ffi.a
ls -l "$lib"
for tool in cc readelf; do
    command -v "$tool" >/dev/null || fail "\`$tool\` not found"
done
CFLAGS=(-std=c11 -O2 -Wall -Wextra -Werror -Iinclude)

section "no allocator: no undefined malloc/free/__rust_alloc in the library"
undefined=$(readelf -sW "$lib" | awk '$7 == "UND" { print $8 }' | sort -u)
grep -qx memcpy <<<"$undefined" || fail "readelf lists no undefined memcpy: the check is blind"
if grep -xE 'malloc|calloc|realloc|free|aligned_alloc|posix_memalign|__rust_alloc|__rust_dealloc|__rust_realloc|__rust_alloc_zeroed' <<<"$undefined"; then
    fail "the static library needs an allocator"
fi
echo "ok: $(wc -l <<<"$undefined") undefined symbols, none an allocator"

section "no panic path: the host test links; a canary library must not"
cc "${CFLAGS[@]}" ffi/tests/host.c -Wl,--gc-sections "$lib" -lm -o "$work/host"
echo "ok: ffi/tests/host.c (every entry point) links without mlmap_panic_path_reachable"
# Its own target directory: the library of the step above stays in place.
cargo rustc -p mlmap-ffi --profile release-abort --crate-type staticlib --features canary \
    --quiet --target-dir target/ffi-canary
if cc "${CFLAGS[@]}" ffi/tests/host.c -Wl,--gc-sections target/ffi-canary/release-abort/libmlmap_ffi.a \
    -lm -o "$work/canary" 2>"$work/canary.log"; then
    fail "the canary library linked: a reachable panic would not fail the link"
fi
grep -q mlmap_panic_path_reachable "$work/canary.log" ||
    { cat "$work/canary.log" >&2; fail "the canary link failed, but not on the panic symbol"; }
echo "ok: the canary build fails to link on mlmap_panic_path_reachable"

section "Rust test of the C entry points (cargo test --profile release-abort --features std)"
cargo test -p mlmap-ffi --profile release-abort --features std --quiet

section "host C test against \`mlmap apply\`"
cargo build --release --features cli --bin mlmap --quiet
mlmap=target/release/mlmap
"$mlmap" apply --table tables/default.mlmap --input examples/data/test.csv --output "$work/apply.csv"
"$work/host" tables/default.mlmap tests/golden/layer/small.mlmap examples/data/test.csv \
    "$work/apply.csv" tests/golden/layer | tee "$work/host.log"
grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/host.log" || fail "the host C test did not pass"

section "quantized C test against \`mlmap apply --quantized\`"
# Codes of the test rows: the shipped int8 section (scale 0.08, zero point 0), and a
# 16-bit section with a scale and zero point per class, written here.
python3 - examples/data/test.csv "$work/codes8.csv" "$work/codes16.csv" <<'CODES'
import csv, sys
src, out8, out16 = sys.argv[1:]
scales16, zeros16 = [0.002, 0.003, 0.0025], [10, -5, 0]
with open(src) as f, open(out8, "w") as f8, open(out16, "w") as f16:
    rows = csv.DictReader(f)
    names = ["car", "cyclist", "pedestrian"]
    head = "id,label,objectness," + ",".join(names) + "\n"
    f8.write(head)
    f16.write(head)
    for r in rows:
        x = [float(r[n]) for n in names]
        q8 = [max(-128, min(127, round(v / 0.08))) for v in x]
        q16 = [max(-32768, min(32767, round(v / s) + z)) for v, s, z in zip(x, scales16, zeros16)]
        pre = f"{r['id']},{r['label']},{r['objectness']},"
        f8.write(pre + ",".join(map(str, q8)) + "\n")
        f16.write(pre + ",".join(map(str, q16)) + "\n")
CODES
"$mlmap" quantize --table tables/default.mlmap --bits 16 --scale 0.002,0.003,0.0025 \
    --zero-point 10,-5,0 --output "$work/q16.mlmap"
"$mlmap" apply --quantized --table tables/default_q8.mlmap --input "$work/codes8.csv" \
    --output "$work/apply8.csv"
"$mlmap" apply --quantized --table "$work/q16.mlmap" --input "$work/codes16.csv" \
    --output "$work/apply16.csv"
QARGS=(tables/default_q8.mlmap "$work/codes8.csv" "$work/apply8.csv" "$work/q16.mlmap"
    "$work/codes16.csv" "$work/apply16.csv")
cc "${CFLAGS[@]}" ffi/tests/quantized.c -Wl,--gc-sections "$lib" -lm -o "$work/quantized"
"$work/quantized" "${QARGS[@]}" | tee "$work/quantized.log"
grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/quantized.log" ||
    fail "the quantized C test did not pass"

section "host C test under AddressSanitizer and UndefinedBehaviorSanitizer"
# Two libraries: the release one (fat LTO, panic abort), as a C program links it, which
# shows that it links into a sanitized program and that nothing host.c does through it
# is caught; and one built with nightly's `-Zsanitizer=address`, so that the library's
# own loads and stores are checked too (the release one's are not instrumented). A
# canary that promises more bytes than it passes must be caught inside the library.
SAN=(-std=c11 -O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined
    -fno-sanitize-recover=all -Wall -Wextra -Werror -Iinclude)
export ASAN_OPTIONS=abort_on_error=0:detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1
# shellcheck source=.ci/nightly.sh
source .ci/nightly.sh
nightly_acquire || fail "no pinned nightly toolchain: the library cannot be built with -Zsanitizer=address"
host_triple=$(rustc -vV | awk '/^host:/ { print $2 }')
# `--target`: the sanitizer flags reach the library, not the build scripts, and the
# library lands in target/$host_triple/, apart from the release one.
RUSTFLAGS="-Zsanitizer=address" cargo +"$NIGHTLY" rustc -p mlmap-ffi --profile release-abort \
    --crate-type staticlib --target "$host_triple" --quiet
asan_lib="target/$host_triple/release-abort/libmlmap_ffi.a"
for which in release asan; do
    if [[ $which == release ]]; then l=$lib; else l=$asan_lib; fi
    cc "${SAN[@]}" ffi/tests/host.c -Wl,--gc-sections "$l" -lm -o "$work/host-san-$which"
    "$work/host-san-$which" tables/default.mlmap tests/golden/layer/small.mlmap \
        examples/data/test.csv "$work/apply.csv" tests/golden/layer 2>"$work/host-san-$which.err" |
        tee "$work/host-san-$which.log" || { tail -n 40 "$work/host-san-$which.err" >&2; fail "the sanitized host C test ($which library) failed"; }
    grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/host-san-$which.log" ||
        fail "the sanitized host C test ($which library) did not pass"
    echo "ok: host.c under ASan and UBSan with the $which library"
    cc "${SAN[@]}" ffi/tests/quantized.c -Wl,--gc-sections "$l" -lm -o "$work/quantized-san-$which"
    "$work/quantized-san-$which" "${QARGS[@]}" 2>"$work/quantized-san-$which.err" |
        tee "$work/quantized-san-$which.log" || { tail -n 40 "$work/quantized-san-$which.err" >&2; fail "the sanitized quantized C test ($which library) failed"; }
    grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/quantized-san-$which.log" ||
        fail "the sanitized quantized C test ($which library) did not pass"
    echo "ok: quantized.c under ASan and UBSan with the $which library"
done
cat >"$work/san-canary.c" <<'CANARY'
#include <stdlib.h>
#include <string.h>
#include "mlmap.h"
int main(void) {
    static mlmap_table_t t;
    uint8_t *b = calloc(16, 1);
    memcpy(b, "MLMP", 4);
    mlmap_status_t s = mlmap_table_decode(&t, sizeof t, b, 64); /* 16 bytes, 64 promised */
    free(b);
    return (int)s;
}
CANARY
cc "${SAN[@]}" "$work/san-canary.c" "$asan_lib" -lm -o "$work/san-canary"
if "$work/san-canary" 2>"$work/san-canary.log"; then
    fail "the sanitizer canary ran to the end: the library's reads are not checked"
fi
grep -q 'heap-buffer-overflow' "$work/san-canary.log" && grep -q 'mlmap_table_decode' "$work/san-canary.log" ||
    { cat "$work/san-canary.log" >&2; fail "the sanitizer canary failed, but not on the library's read"; }
echo "ok: an out-of-bounds read inside the library is caught (canary)"

section "Cortex-M4F C example"
# shellcheck source=.ci/thumb-toolchain.sh
source .ci/thumb-toolchain.sh
command -v arm-none-eabi-gcc >/dev/null && [[ -d /usr/lib/arm-none-eabi/newlib ]] ||
    apt_install gcc-arm-none-eabi libnewlib-arm-none-eabi
command -v qemu-system-arm >/dev/null || apt_install qemu-system-arm
thumb_acquire
if ! command -v arm-none-eabi-gcc >/dev/null || ! command -v qemu-system-arm >/dev/null ||
    [[ "$THUMB_VIA" == none ]]; then
    proof_not_run "the C example on the emulated Cortex-M4F" \
        "arm-none-eabi-gcc: $(command -v arm-none-eabi-gcc || echo missing)" \
        "qemu-system-arm:   $(command -v qemu-system-arm || echo missing)" \
        "Rust target $THUMB_TARGET: $THUMB_VIA"
fi
arm-none-eabi-gcc --version | head -n 1
thumb_cargo rustc -p mlmap-ffi --profile release-size --crate-type staticlib --quiet
thumb_lib="$(thumb_out_dir release-size)/libmlmap_ffi.a"
ls -l "$thumb_lib"

fw=ffi/firmware
"$mlmap" export-c --table tables/default.mlmap --output "$work/table.h"
"$mlmap" export-c --table tests/golden/layer/small_open.mlmap --output "$work/table_open.h" \
    --name mlmap_open_table_bytes
cc "${CFLAGS[@]}" -I"$fw" "$fw/gen_expected.c" -Wl,--gc-sections "$lib" -lm -o "$work/gen_expected"
"$work/gen_expected" tables/default.mlmap tests/golden/layer/small_open.mlmap >"$work/expected.h"
ARM=(-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -std=c11 -Os -g -Wall -Wextra
    -Werror -ffunction-sections -fdata-sections -Iinclude -I"$fw" -I"$work")
link_fw() { # $1 = output ELF, rest = extra flags
    local out=$1
    shift
    arm-none-eabi-gcc "${ARM[@]}" "$@" -nostartfiles -T "$fw/link.ld" -Wl,--gc-sections \
        -Wl,--no-warn-rwx-segments "$fw/startup.c" "$fw/main.c" "$thumb_lib" \
        --specs=nano.specs -lc -lgcc -o "$out" 2> >(grep -v 'GNU-stack\|deprecated' >&2)
}
run_qemu() { # $1 = ELF
    timeout 120 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
        -semihosting-config enable=on,target=native -kernel "$1" </dev/null
}
link_fw "$work/fw.elf"
link_fw "$work/canary.elf" -DMLMAP_CANARY
if arm-none-eabi-nm "$work/fw.elf" | grep -wE '_?(malloc|calloc|realloc|free|_sbrk|_malloc_r)$'; then
    fail "the firmware image contains an allocator"
fi
echo "ok: no allocator symbol in the firmware image"
arm-none-eabi-size -A "$work/fw.elf" | grep -E '^\.(vectors|text|rodata|data|bss) '

status=0
run_qemu "$work/canary.elf" >"$work/canary-run.log" 2>&1 || status=$?
sed 's/^/canary| /' "$work/canary-run.log"
[[ $status -ne 0 && $status -ne 124 ]] || fail "the canary firmware did not fail (status $status)"
grep -qE '^[0-9]+ passed, [1-9][0-9]* failed$' "$work/canary-run.log" ||
    fail "the canary firmware did not report its failure"
echo "ok: the canary firmware failed as it must (exit status $status)"

status=0
run_qemu "$work/fw.elf" 2>&1 | tee "$work/run.log" || status=$?
[[ $status -eq 0 ]] || fail "the C example exited with status $status"
grep -qE '^[1-9][0-9]* passed, 0 failed$' "$work/run.log" ||
    fail "the C example did not report 'N passed, 0 failed'"

section "passed in $((SECONDS - start)) s (root: $root)"
