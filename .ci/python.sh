#!/usr/bin/env bash
# The Python package (python/), run from the repository root: in a virtual environment
# (target/python-venv, kept between runs; pip's cache makes reinstalls cheap), install
# maturin and python/requirements-test.txt from the package registry, build and install
# the package with `pip install ./python` as a user would, build the `mlmap` tool (the
# golden values of the tests), and run pytest on python/tests.
set -euo pipefail
# Tools are run as `python -m ...`, so a venv moved with its cache directory still works
# (its scripts' `#!` lines name the old path).

fail() {
    printf 'python: FAILED: %s\n' "$*" >&2
    exit 1
}
[[ -f Cargo.toml && -d python ]] || fail "run from the repository root"
start=$SECONDS
venv=target/python-venv
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_CACHE_DIR="${PIP_CACHE_DIR:-$HOME/.cache/pip}"

if ! python3 -m venv "$venv" 2>/dev/null; then
    echo "apt-get install -y python3-venv"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
    python3 -m venv "$venv"
fi
echo "cargo fmt --check and clippy of python/ (its own workspace)"
cargo fmt --manifest-path python/Cargo.toml --check
cargo clippy --manifest-path python/Cargo.toml --quiet -- -D warnings
"$venv/bin/python" --version
"$venv/bin/python" -m pip install -q "maturin>=1.9,<2" -r python/requirements-test.txt

echo "pip install ./python"
"$venv/bin/python" -m pip install -q --force-reinstall --no-deps ./python
"$venv/bin/python" -c 'import mlmap; print("mlmap", mlmap.__version__, "from", mlmap.__file__)'

cargo build --release --features cli --bin mlmap --quiet
# From the repository root, so that `import mlmap` finds the installed package and
# not the sources in python/mlmap.
MLMAP_CLI="$PWD/target/release/mlmap" "$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests
echo "python: passed in $((SECONDS - start)) s"
