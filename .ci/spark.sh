#!/usr/bin/env bash
# examples/spark_fit.py on a local Spark (local[2]), run from the repository root after
# .ci/python.sh (its venv, target/python-venv, holds the mlmap package): pyspark and
# pyarrow from the package registry into that venv, Java from Debian when `java` is
# missing; then the table the example writes must be byte for byte `mlmap fit`'s on the
# same file: the shipped training data on 7 partitions, and 40 rows on 64 partitions
# (empty ones among them) with other fit settings. A label that names no class must stop
# the example with an error naming it.
set -euo pipefail

fail() {
    printf 'spark: FAILED: %s\n' "$*" >&2
    exit 1
}
[[ -f Cargo.toml && -f examples/spark_fit.py ]] || fail "run from the repository root"
start=$SECONDS
venv=target/python-venv
py="$venv/bin/python"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_CACHE_DIR="${PIP_CACHE_DIR:-$HOME/.cache/pip}"
"$py" -c 'import mlmap' 2>/dev/null || fail "$venv has no mlmap package: run .ci/python.sh first"
"$py" -m pip install -q "pyspark>=3.5,<5" "pyarrow>=14"
if ! command -v java >/dev/null; then
    echo "apt-get install -y openjdk-17-jre-headless"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq openjdk-17-jre-headless >/dev/null
fi
java -version 2>&1 | head -1
"$py" -c 'import pyspark; print("pyspark", pyspark.__version__)'

cargo build --release --features cli --bin mlmap --quiet
mlmap=target/release/mlmap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

same() {  # same TABLE_A TABLE_B WHAT
    cmp "$1" "$2" || fail "$3: the Spark table differs from mlmap fit's"
    echo "ok: $3: $(wc -c <"$1") bytes, the same as mlmap fit's"
}

"$mlmap" fit --train examples/data/train.csv --output "$tmp/cli.mlmap" >/dev/null
"$py" examples/spark_fit.py --output "$tmp/spark.mlmap" --partitions 7
same "$tmp/spark.mlmap" "$tmp/cli.mlmap" "examples/data/train.csv, 7 partitions"

# 40 rows (all three classes and background) on 64 partitions: 24 or more are empty.
head -n 41 examples/data/train.csv >"$tmp/small.csv"
settings=(--edges matlab --upper-tail clamp --bins-ml 9 --lambda-ml 0.01 --bins-map 5
    --bins-bayes 6 --lambda-bayes 0.01)
"$mlmap" fit --train "$tmp/small.csv" "${settings[@]}" --output "$tmp/cli-small.mlmap" >/dev/null
"$py" examples/spark_fit.py "$tmp/small.csv" "${settings[@]}" --partitions 64 \
    --output "$tmp/spark-small.mlmap"
same "$tmp/spark-small.mlmap" "$tmp/cli-small.mlmap" "40 rows, 64 partitions, other settings"

# A label that names no class: refused, nothing written.
sed '0,/,car,/s//,truck,/' "$tmp/small.csv" >"$tmp/truck.csv"
grep -q ',truck,' "$tmp/truck.csv" || fail "the test file has no truck label"
if "$py" examples/spark_fit.py "$tmp/truck.csv" --output "$tmp/truck.mlmap" 2>"$tmp/err"; then
    fail "a label that names no class was accepted"
fi
grep -q "label that names no class" "$tmp/err" || fail "unclear error: $(tail -3 "$tmp/err")"
[[ ! -e "$tmp/truck.mlmap" ]] || fail "a table was written for refused data"
echo "ok: a label that names no class is refused"
echo "spark: passed in $((SECONDS - start)) s"
