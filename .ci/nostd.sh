#!/usr/bin/env bash
# Proofs (a) and (b) of the embedded layer, on the x86_64 Linux host:
#   1. no dependency of the library enables a `std` or `alloc` feature;
#   2. the `#![no_std]` binary `nostd-check/` links, i.e. no panic path survives in
#      decode or inference (its panic handler calls an undefined symbol), once with the
#      default backend and once with `micromath`;
#   3. the canary build (one deliberate panic) does fail to link, so check 2 can fail;
#   4. `nm -u` of both binaries lists no allocator symbol, and both run and exit 0.
# Run from the repository root.
set -euo pipefail

section() { printf '\n==== nostd: %s ====\n' "$*"; }
fail() {
    printf 'nostd: FAILED: %s\n' "$*" >&2
    exit 1
}

[[ -f Cargo.toml && -d nostd-check ]] || fail "run from the repository root"
for tool in cargo cc nm; do
    command -v "$tool" >/dev/null || fail "\`$tool\` not found"
done
start=$SECONDS

section "dependency features: no std, no alloc (cargo tree -e features)"
# Normal dependencies only, proc-macros excluded: they run on the build machine.
for features in "" "micromath" "micromath,defmt"; do
    tree=$(cargo tree -e normal,features,no-proc-macro --no-default-features \
        ${features:+--features "$features"} --prefix none)
    grep -q '^mlmap v' <<<"$tree" || fail "cargo tree printed no tree for [$features]"
    if bad=$(grep -E 'feature "(std|alloc)"' <<<"$tree"); then
        printf '%s\n' "$bad" >&2
        fail "a dependency enables std/alloc with --no-default-features ${features:+--features $features}"
    fi
    echo "ok: --no-default-features${features:+ --features $features}: $(wc -l <<<"$tree") lines, no std/alloc feature"
done
# The grep must be able to see a std feature when there is one.
tree=$(cargo tree -e normal,features,no-proc-macro --no-default-features \
    --features std --prefix none)
grep -qE 'feature "std"' <<<"$tree" ||
    fail "the std/alloc grep found nothing even with --features std: the check is blind"
echo "ok: the same grep does flag --features std"

# The binary compares the build-time table with the default file.
unset MLMAP_TABLE
# From its directory: its .cargo/config.toml links the C library's startup files.
cd nostd-check
bin="${CARGO_TARGET_DIR:-../target}/release-abort/mlmap-nostd-check"

section "canary: a deliberate panic must fail the link"
log=$(mktemp)
if cargo build --profile release-abort --features canary >"$log" 2>&1; then
    cat "$log" >&2
    fail "the canary build linked: the panic handler does not make a reachable panic fail the link"
fi
grep -q 'mlmap_panic_path_reachable' "$log" || {
    cat "$log" >&2
    fail "the canary build failed, but not on the undefined panic symbol"
}
echo "ok: the canary build fails on the undefined symbol mlmap_panic_path_reachable"
rm -f "$log"

ALLOCATOR='malloc|calloc|realloc|free|aligned_alloc|posix_memalign|memalign|valloc|__rust_alloc|__rust_dealloc|__rust_realloc|__rust_alloc_zeroed'
# The grep must see an allocator where there is one.
nm -D -u "$(command -v nm)" | grep -qwE "$ALLOCATOR" ||
    fail "the allocator grep finds nothing even in nm itself: the check is blind"

check_binary() { # $1 = label, $2 = binary
    local undefined
    undefined=$(nm -u "$2")
    echo "undefined symbols of $1:"
    # shellcheck disable=SC2001
    sed 's/^/    /' <<<"$undefined"
    grep -qw __libc_start_main <<<"$undefined" ||
        fail "nm -u lists no __libc_start_main for $1: the listing is not trustworthy"
    if grep -wE "$ALLOCATOR" <<<"$undefined"; then
        fail "$1 needs an allocator"
    fi
    echo "ok: $1 needs no allocator"
    "$2" || fail "$1 ran and reported $? failed check(s)"
    echo "ok: $1 ran, every result checked"
}

section "link without panic paths: default backend (libm)"
cargo build --profile release-abort
check_binary "nostd-check (libm)" "$bin"

section "link without panic paths: --features micromath (Micromath)"
cargo build --profile release-abort --features micromath
check_binary "nostd-check (micromath)" "$bin"

section "passed in $((SECONDS - start)) s: no std, no alloc, no reachable panic"
