#!/usr/bin/env bash
# build.rs must refuse an invalid MLMAP_TABLE with a message naming the file and the
# broken invariant, and accept a valid one other than the default.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

expect_failure() { # name, file, expected text
    local name=$1 file=$2 want=$3
    if MLMAP_TABLE="$file" cargo check --lib --quiet 2>"$tmp/err"; then
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

# Back to the default table (also re-runs build.rs for the steps that follow).
cargo check --lib --quiet
echo "ok: default table embeds"
