#!/usr/bin/env bash
# The Python package (python/), run from the repository root: build the abi3 wheel once
# with maturin (target/python-build, a venv with maturin), install it into a fresh
# virtual environment (target/python-venv, recreated each run) with no Rust toolchain
# on the PATH, as a user without one would, check the stubs against the installed
# package (mypy's stubtest), build the `mlmap` tool (the golden values of the tests),
# and run pytest on python/tests against the wheel.
set -euo pipefail
# Tools are run as `python -m ...`, so a venv moved with its cache directory still works
# (its scripts' `#!` lines name the old path).

fail() {
    printf 'python: FAILED: %s\n' "$*" >&2
    exit 1
}
[[ -f Cargo.toml && -d python ]] || fail "run from the repository root"
start=$SECONDS
build_venv=target/python-build
venv=target/python-venv
wheels=target/wheels
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_CACHE_DIR="${PIP_CACHE_DIR:-$HOME/.cache/pip}"

if ! python3 -m venv "$build_venv" 2>/dev/null; then
    echo "apt-get install -y python3-venv"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
    python3 -m venv "$build_venv"
fi
echo "cargo fmt --check and clippy of python/ (the workspace member mlmap-python)"
cargo fmt -p mlmap-python --check
cargo clippy -p mlmap-python --quiet -- -D warnings

echo "maturin build --profile python (the abi3 wheel)"
"$build_venv/bin/python" -m pip install -q "maturin>=1.9,<2"
rm -rf "$wheels"
"$build_venv/bin/python" -m maturin build --profile python --quiet -m python/Cargo.toml -o "$wheels"
wheel=$(ls "$wheels"/mlmap-*.whl)
[[ $(wc -w <<<"$wheel") -eq 1 ]] || fail "expected one wheel in $wheels, found: $wheel"
[[ $wheel == *-abi3-* ]] || fail "$wheel is not an abi3 wheel"
echo "built $wheel"

# A fresh venv, and nothing of Rust on the PATH while the wheel and the test
# requirements are installed: pip must not find a toolchain to build anything with.
rm -rf "$venv"
python3 -m venv "$venv"
bare_path=/usr/local/bin:/usr/bin:/bin
for tool in cargo rustc; do
    if PATH=$bare_path command -v "$tool" >/dev/null; then
        fail "$tool is on $bare_path: the install would not show that no toolchain is needed"
    fi
done
echo "pip install $wheel (PATH=$bare_path: no cargo, no rustc)"
env PATH="$bare_path" "$venv/bin/python" -m pip install -q --only-binary=:all: \
    "$wheel" -r python/requirements-test.txt mypy
"$venv/bin/python" -c 'import mlmap; print("mlmap", mlmap.__version__, "from", mlmap.__file__)'

echo "stubtest: the stubs against the installed package"
# From target/, so that `mlmap` is the installed package and not the sources in python/.
(cd target && env PATH="$bare_path" ../"$venv"/bin/python -m mypy.stubtest mlmap \
    --allowlist ../python/stubtest-allowlist.txt) || fail "stubtest found errors"

cargo build --release --features cli --bin mlmap --quiet
# From the repository root, so that `import mlmap` finds the installed package and
# not the sources in python/mlmap.
MLMAP_CLI="$PWD/target/release/mlmap" env PATH="$bare_path" "$venv/bin/python" -m pytest -q \
    -p no:cacheprovider python/tests
echo "python: passed in $((SECONDS - start)) s"
