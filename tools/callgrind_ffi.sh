#!/usr/bin/env bash
# Instructions per detection of the C API against the Rust call, counted by valgrind's
# callgrind: ffi/tests/instr_count.c (mlmap_ml, mlmap_map, mlmap_bayes, mlmap_open through
# a function pointer, on the x86-64 static library), examples/instr_count.rs (Table::ml,
# Table::map, Table::bayes, Table::open) and ffi/examples/bounded_count.rs (the same heads
# on the C API's run-time shaped table, from Rust), same table, same 4096 rows of
# examples/data/test.csv. Each runs N and 2N detections; (I(2N) - I(N)) / N removes
# start-up and reading the rows. The Bayes and open heads use FastMath everywhere, MAP
# libm.
#
#   tools/callgrind_ffi.sh          # N = 16384
set -euo pipefail
cd "$(dirname "$0")/.."

n="${N:-16384}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cargo rustc -p mlmap-ffi --quiet --profile release-abort --crate-type staticlib
cc -std=c11 -O2 -Iinclude ffi/tests/instr_count.c -Wl,--gc-sections \
    target/release-abort/libmlmap_ffi.a -lm -o "$out/c_count"
cargo build --quiet --release --features micromath,std --example instr_count
rust="target/release/examples/instr_count"
cargo build -p mlmap-ffi --quiet --profile release-abort --features std --example bounded_count
bounded="target/release-abort/examples/bounded_count"

count() { # command...
    valgrind --tool=callgrind --callgrind-out-file="$out/cg" "$@" >/dev/null 2>&1
    awk '/^totals:/ { print $2 }' "$out/cg"
}
per() { # command prefix (kind and N are appended)
    local a b
    a="$(count "$@" "$n")"
    b="$(count "$@" "$((2 * n))")"
    python3 -c "print(f'{($b - $a) / $n:.1f}')"
}

kinds=(noop ml map bayes open)
declare -A c r b
for kind in "${kinds[@]}"; do
    c[$kind]="$(per "$out/c_count" tables/default.mlmap examples/data/test.csv "$kind")"
    b[$kind]="$(per "$bounded" "$kind")"
    r[$kind]="$(per "$rust" "$kind")"
done
echo "Instructions per detection (N = $n); Table = Table<3, 22, 17, 22, 4> (shape fixed at"
echo "compile time), BoundedTable = the C API's run-time shaped table, from Rust"
printf '%-6s %10s %10s %13s %10s %14s\n' kind "C API" "Table" "BoundedTable" "C / Table" "C / Bounded"
for kind in "${kinds[@]}"; do
    python3 -c "print('%-6s %10.1f %10.1f %13.1f %10.3f %14.3f' % ('$kind', ${c[$kind]}, ${r[$kind]}, ${b[$kind]}, ${c[$kind]} / ${r[$kind]}, ${c[$kind]} / ${b[$kind]}))"
done
