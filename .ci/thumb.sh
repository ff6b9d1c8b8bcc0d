#!/usr/bin/env bash
# Proof (c): the library builds for thumbv7em-none-eabihf (Cortex-M4F), without default
# features and with `micromath,defmt`. The target comes from rustup, or else from Debian's
# Rust packages with `-Zbuild-std=core`; if neither can be had, the proof fails
# (MLMAP_ALLOW_SKIP=1 skips it outside CI). Run from the repository root.
set -euo pipefail

section() { printf '\n==== thumb: %s ====\n' "$*"; }
[[ -f Cargo.toml && -d src ]] || {
    echo "thumb: run from the repository root" >&2
    exit 1
}
start=$SECONDS
# shellcheck source=.ci/thumb-toolchain.sh
source .ci/thumb-toolchain.sh

section "toolchain for $THUMB_TARGET"
thumb_acquire
if [[ "$THUMB_VIA" == none ]]; then
    thumb_skipped_banner "the thumbv7em-none-eabihf builds of the library"
fi
echo "toolchain: $THUMB_VIA"

for features in "" "micromath,defmt"; do
    args=(build --lib --no-default-features ${features:+--features "$features"})
    section "cargo ${args[*]} --target $THUMB_TARGET (via $THUMB_VIA)"
    thumb_cargo "${args[@]}"
done

section "passed in $((SECONDS - start)) s: the library builds for $THUMB_TARGET (via $THUMB_VIA)"
