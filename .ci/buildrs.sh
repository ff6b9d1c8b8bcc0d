#!/usr/bin/env bash
# build.rs must refuse an invalid MLMAP_TABLE with a message naming the file and the
# broken invariant, and accept a valid one other than the default; the same for the
# quantized section of MLMAP_QUANTIZED.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

expect_failure() { # name, file, expected text[, variable]
    local name=$1 file=$2 want=$3 var=${4:-MLMAP_TABLE}
    if env "$var=$file" cargo check --lib --quiet 2>"$tmp/err"; then
        echo "FAIL: build accepted $name"; exit 1
    fi
    grep -q -- "$file" "$tmp/err" || { echo "FAIL: message does not name $file"; cat "$tmp/err"; exit 1; }
    grep -q -- "$want" "$tmp/err" || { echo "FAIL: message lacks '$want'"; cat "$tmp/err"; exit 1; }
    echo "ok: $name refused: $(grep -o "cannot embed.*" "$tmp/err" | head -1)"
}

# One flipped byte in the middle: the CRC no longer matches.
python3 - "$tmp/corrupt.mlmap" <<'PY'
import sys
b = bytearray(open("tables/default.mlmap", "rb").read())
b[len(b) // 2] ^= 0x40
open(sys.argv[1], "wb").write(b)
PY
expect_failure "a corrupted table" "$tmp/corrupt.mlmap" "checksum"

# A valid CRC over a broken invariant (a negative lambda).
python3 - "$tmp/lambda.mlmap" <<'PY'
import struct, sys, zlib
b = bytearray(open("tables/default.mlmap", "rb").read()[:-4])
# magic(4) version(1) K(1) B_ML(1) B_MAP(1), version 2: B_BAYES(1) C(1),
# then edge(1) tail(1) -> lambda ML at offset 10 (version 1) or 12 (version 2)
at = 10 if b[4] == 1 else 12
b[at:at + 4] = struct.pack("<f", -0.5)
b += struct.pack("<I", zlib.crc32(bytes(b)) & 0xFFFFFFFF)
open(sys.argv[1], "wb").write(b)
PY
expect_failure "a negative lambda" "$tmp/lambda.mlmap" "lambda"

expect_failure "a missing file" "$tmp/none.mlmap" "No such file"

# A valid version-1 table (no Bayes head) other than the default embeds.
MLMAP_TABLE=tests/golden/train_linspace.mlmap cargo check --lib --quiet
echo "ok: a version-1 table embeds"

# The quantized section: one flipped byte in it, a zero scale under a valid CRC, and a
# table without a section are refused; the section alone (no table before it) embeds.
python3 - "$tmp" <<'PY'
import struct, sys, zlib
b = open("tables/default_q8.mlmap", "rb").read()
n = struct.unpack("<I", b[-8:-4])[0]
section = bytearray(b[-n:])
open(sys.argv[1] + "/section.mlmq", "wb").write(section)
flipped = bytearray(section)
flipped[n // 2] ^= 0x40
open(sys.argv[1] + "/qcorrupt.mlmq", "wb").write(flipped)
zero = bytearray(section[:-4])
zero[32:36] = struct.pack("<f", 0.0)  # class 0's scale, after the 32-byte header
zero += struct.pack("<I", zlib.crc32(bytes(zero)) & 0xFFFFFFFF)
open(sys.argv[1] + "/qscale.mlmq", "wb").write(zero)
PY
expect_failure "a corrupted quantized section" "$tmp/qcorrupt.mlmq" "checksum" MLMAP_QUANTIZED
expect_failure "a quantized section with a zero scale" "$tmp/qscale.mlmq" "scale" MLMAP_QUANTIZED
expect_failure "a table without a quantized section" "$PWD/tables/default.mlmap" "no quantized section" MLMAP_QUANTIZED
MLMAP_QUANTIZED="$tmp/section.mlmq" cargo check --lib --quiet
echo "ok: a quantized section alone embeds"

# Back to the default table (also re-runs build.rs for the steps that follow).
cargo check --lib --quiet
echo "ok: default table embeds"
