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
# `q8_bayes`, `q8_open`; `q8_noop` is their loop; `q8_decode` reads the section), and
# runtime safety (DESIGN §7, §8): the drift monitor's push (`monitor_push`, W = 50, the
# window ends amortised; `monitor_push_nowin`, a window that never ends; their difference
# times W is the cost of one window end), the open head's scores and the push in one pass
# (`monitor_push_open`), and the open head's scores with their conformal class set
# (`conformal_set`; net of `open`, the cost of the set on top of the head; `open_set_of`:
# the open head's scores, then `set_of` on them).
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
for kind in noop sigmoid sigmoid_fast softmax ml map map_fast map_micromath bayes bayes_fast open open_eps open_map decode q8_noop q8_ml q8_map q8_bayes q8_open q8_decode monitor_push monitor_push_nowin monitor_push_open conformal_set open_set_of; do
    a="$(count "$kind" "$n")"
    b="$(count "$kind" "$((2 * n))")"
    per[$kind]="$(python3 -c "print(f'{($b - $a) / $n:.1f}')")"
    printf '%-14s %14s %14s %12s\n' "$kind" "$a" "$b" "${per[$kind]}"
done
echo
for kind in sigmoid_fast softmax ml map map_fast map_micromath bayes bayes_fast open open_eps open_map q8_ml q8_map q8_bayes q8_open monitor_push monitor_push_nowin monitor_push_open conformal_set open_set_of; do
    loop=noop
    [[ $kind == q8_* ]] && loop=q8_noop
    python3 -c "
g, s, n, m = ${per[$kind]}, ${per[sigmoid]}, ${per[$loop]}, ${per[noop]}
print(f'$kind / sigmoid = {g / s:.3f} (net of the loop: {(g - n) / (s - m):.3f})')"
done
# Runtime safety against the goals of DESIGN §7 and §8: the window end in units of K B
# (K = 3 logits, B = 22 bins), the set and the pass-through push on top of the open head.
python3 -c "
p, nw, po, cs, so, op, s = ${per[monitor_push]}, ${per[monitor_push_nowin]}, ${per[monitor_push_open]}, ${per[conformal_set]}, ${per[open_set_of]}, ${per[open]}, ${per[sigmoid]}
end = (p - nw) * 50
print(f'monitor window end = {end:.0f} Ir = {end / 66:.1f} K B (W = 50, K B = 66)')
print(f'conformal_set - open = {cs - op:.1f} Ir = {(cs - op) / s:.3f} x sigmoid')
print(f'open_set_of - open = {so - op:.1f} Ir = {(so - op) / s:.3f} x sigmoid')
print(f'monitor_push_open - open = {po - op:.1f} Ir = {(po - op) / s:.3f} x sigmoid')"
