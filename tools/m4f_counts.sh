#!/usr/bin/env bash
# Instructions per detection of every head on the Cortex-M4F, through Rust and through C,
# counted in QEMU (`-machine mps2-an386 -icount shift=0`: the virtual clock advances 1 ns
# per executed instruction, SysTick ticks once per 40 ns of its 25 MHz clock, so 40
# instructions per tick, read before and after a batch of 4096 detections), with the
# stack per call and the code per head. Builds and runs:
#   * firmware/src/bin/bench.rs (feature `bench`): the Rust API (`Table`, `QTable`) at
#     the firmware's profile (`firmware`: opt-level "s", fat LTO);
#   * ffi/firmware/bench.c: the C API, arm-none-eabi-gcc -Os against the thumbv7em static
#     library at its Cortex-M4F profile (`release-size`: opt-level "s", fat LTO);
# each twice (the counts must repeat exactly), then prints the table of
# tools/m4f_report.py. Run from anywhere:
#
#   tools/m4f_counts.sh            # the table
#   tools/m4f_counts.sh --check    # and fail on a bad counter check, a C checksum other
#                                  # than Rust's, or a C / Rust ratio above its bound
#   M4F_OUT=DIR tools/m4f_counts.sh   # also keeps the logs and the two images in DIR
#
# Needs qemu-system-arm, arm-none-eabi-gcc (newlib), the thumbv7em-none-eabihf Rust
# target (.ci/thumb-toolchain.sh) and python3; without them it fails
# (MLMAP_ALLOW_SKIP=1 skips outside CI). Installing them is .ci/ffi.sh's job.
set -euo pipefail
cd "$(dirname "$0")/.."
check=()
[[ "${1:-}" == --check ]] && check=(--check)
unset MLMAP_TABLE MLMAP_MAX_CLASSES MLMAP_MAX_BINS MLMAP_MAX_BINS_BAYES MLMAP_FAST_CLASSES
# shellcheck source=.ci/thumb-toolchain.sh
source .ci/thumb-toolchain.sh

thumb_acquire >/dev/null
if ! command -v qemu-system-arm >/dev/null || ! command -v arm-none-eabi-gcc >/dev/null ||
    [[ "$THUMB_VIA" == none ]] || ! command -v python3 >/dev/null; then
    proof_not_run "the Cortex-M4F instruction counts" \
        "qemu-system-arm:   $(command -v qemu-system-arm || echo missing)" \
        "arm-none-eabi-gcc: $(command -v arm-none-eabi-gcc || echo missing)" \
        "Rust target $THUMB_TARGET: $THUMB_VIA" \
        "python3: $(command -v python3 || echo missing)"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "== builds"
(cd firmware && thumb_cargo build --profile firmware --quiet --features bench --bin bench)
rust_elf="$(thumb_out_dir firmware)/bench"
thumb_cargo rustc -p mlmap-ffi --profile release-size --crate-type staticlib --quiet
thumb_lib="$(thumb_out_dir release-size)/libmlmap_ffi.a"
cargo build --release --quiet --features cli --bin mlmap
mlmap=target/release/mlmap
"$mlmap" export-c --table tables/default.mlmap --output "$work/table.h" >/dev/null
"$mlmap" export-c --table tests/golden/layer/small_open.mlmap --output "$work/table_small_open.h" \
    --name mlmap_small_open_bytes >/dev/null
"$mlmap" export-c --table tests/golden/layer/small_maps.mlmap --output "$work/table_small_maps.h" \
    --name mlmap_small_maps_bytes >/dev/null
"$mlmap" export-c --table tables/default_q8.mlmap --output "$work/table_q8.h" \
    --name mlmap_q8_bytes >/dev/null
# The first 4096 rows of the test file, as the Rust bench parses them (the literals round
# to the same floats as Rust's `str::parse::<f32>`).
awk -F, 'NR == 1 { next } NR <= 4097 {
        x = x sprintf("    {%sf, %sf, %sf},\n", $4, $5, $6); o = o sprintf("    %sf,\n", $3) }
    END { print "#define ROWS 4096u"
          print "static const float rows_x[ROWS][3] = {\n" x "};"
          print "static const float rows_os[ROWS] = {\n" o "};" }' \
    examples/data/test.csv >"$work/rows.h"
fw=ffi/firmware
c_elf="$work/bench_c.elf"
arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -std=c11 -Os \
    -Wall -Wextra -Werror -ffunction-sections -fdata-sections -Iinclude -I"$fw" -I"$work" \
    -nostartfiles -T "$fw/link.ld" -Wl,--gc-sections -Wl,--no-warn-rwx-segments \
    "$fw/startup.c" "$fw/bench.c" "$thumb_lib" --specs=nano.specs -lc -lm -lgcc -o "$c_elf" \
    2> >(grep -v 'GNU-stack\|deprecated' >&2)

run_qemu() { # $1 = ELF, $2 = log
    timeout 300 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
        -icount shift=0,align=off,sleep=off \
        -semihosting-config enable=on,target=native -kernel "$1" </dev/null >"$2" 2>&1 || {
        cat "$2" >&2
        echo "m4f_counts: $1 failed under QEMU" >&2
        exit 1
    }
    grep -q '^done$' "$2" || { cat "$2" >&2; echo "m4f_counts: $1 did not finish" >&2; exit 1; }
}
echo "== runs: $(qemu-system-arm --version | head -n 1)"
for lang in rust c; do
    elf_var="${lang}_elf"
    run_qemu "${!elf_var}" "$work/$lang.log"
    run_qemu "${!elf_var}" "$work/$lang.again.log"
    cmp -s "$work/$lang.log" "$work/$lang.again.log" || {
        diff "$work/$lang.log" "$work/$lang.again.log" >&2 || true
        echo "m4f_counts: two runs of the $lang bench counted differently" >&2
        exit 1
    }
done
echo "ok: each bench counted the same twice"
if [[ -n "${M4F_OUT:-}" ]]; then # keep the logs and images
    mkdir -p "$M4F_OUT"
    cp "$work/rust.log" "$work/c.log" "$rust_elf" "$c_elf" "$M4F_OUT/"
fi
echo
python3 tools/m4f_report.py "$work/rust.log" "$work/c.log" "$rust_elf" "$c_elf" \
    arm-none-eabi-objdump arm-none-eabi-nm \
    "${check[@]}"
