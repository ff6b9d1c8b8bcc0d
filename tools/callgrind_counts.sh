#!/usr/bin/env bash
# Deterministic instructions per detection (and per table decoding) of every layer,
# counted by valgrind's callgrind on examples/instr_count.rs: each kind runs N and 2N
# times, and (I(2N) - I(N)) / N removes the fixed cost (start-up, reading the rows).
#
#   tools/callgrind_counts.sh            # N = 16384 (a multiple of the 4096 test rows)
#   N=4096 tools/callgrind_counts.sh
#
# Prints one line per kind, and the ratios to the Sigmoid layer (libm), both gross and net
# of the loop around the layer (kind `noop`: fetch a row, call through a function pointer,
# fold the result into a checksum). Kinds: the Sigmoid layer with libm and with FastMath,
# Softmax, ML, MAP with libm (`map`), FastMath (`map_fast`) and Micromath
# (`map_micromath`), the Bayes head with libm (`bayes`) and FastMath (`bayes_fast`), the
# open head as shipped (`open`: epsilon 0), with an unknown category (`open_eps`) and
# with a 32-knot recalibration map besides (`open_map`, DESIGN §1.9),
# decoding, and the quantized table on int8 codes of the same rows (`q8_ml`, `q8_map`,
# `q8_bayes`, `q8_open`; `q8_noop` is their loop; `q8_decode` reads the section).
set -euo pipefail
cd "$(dirname "$0")/.."

n="${N:-16384}"
cargo build --quiet --release --features micromath,std --example instr_count
bin="$(cargo metadata --format-version 1 --no-deps |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release/examples/instr_count"

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

# Total instructions (Ir) of one run.
count() {
    valgrind --tool=callgrind --callgrind-out-file="$out/cg" "$bin" "$1" "$2" >/dev/null 2>&1
    awk '/^totals:/ { print $2 }' "$out/cg"
}

declare -A per
printf '%-14s %14s %14s %12s\n' kind "Ir(N=$n)" "Ir(2N)" "Ir/detection"
for kind in noop sigmoid sigmoid_fast softmax ml map map_fast map_micromath bayes bayes_fast open open_eps open_map decode q8_noop q8_ml q8_map q8_bayes q8_open q8_decode; do
    a="$(count "$kind" "$n")"
    b="$(count "$kind" "$((2 * n))")"
    per[$kind]="$(python3 -c "print(f'{($b - $a) / $n:.1f}')")"
    printf '%-14s %14s %14s %12s\n' "$kind" "$a" "$b" "${per[$kind]}"
done
echo
for kind in sigmoid_fast softmax ml map map_fast map_micromath bayes bayes_fast open open_eps open_map q8_ml q8_map q8_bayes q8_open; do
    loop=noop
    [[ $kind == q8_* ]] && loop=q8_noop
    python3 -c "
g, s, n, m = ${per[$kind]}, ${per[sigmoid]}, ${per[$loop]}, ${per[noop]}
print(f'$kind / sigmoid = {g / s:.3f} (net of the loop: {(g - n) / (s - m):.3f})')"
done
