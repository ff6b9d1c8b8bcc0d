# shellcheck shell=bash
# Sourced by .ci/thumb.sh and .ci/firmware.sh: gets a Rust toolchain that can build for
# the Cortex-M4F target and defines `thumb_cargo`, which runs cargo with it.
#
#   thumb_acquire      sets THUMB_VIA to `rustup` or `debian`, or to `none` (never fails)
#   thumb_cargo ARGS   cargo ARGS --target thumbv7em-none-eabihf, with that toolchain
#
# 1. rustup: the precompiled `core` of the target (`rustup target add`, 120 s at most).
# 2. Debian: the packages rustc-web, cargo-web, rust-web-src and lld-14, building `core`
#    from source (`RUSTC_BOOTSTRAP=1 -Zbuild-std=core`) and linking with ld.lld-14.
# Set MLMAP_THUMB_VIA=debian to skip the first way (to test the second).

THUMB_TARGET=thumbv7em-none-eabihf
THUMB_VIA=none
# The workspace's target directory, where every member builds (absolute, so that it
# holds from a crate's directory too).
THUMB_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
THUMB_TARGET_DIR=${CARGO_TARGET_DIR:-$THUMB_ROOT/target}
DEBIAN_RUST_PACKAGES=(rustc-web cargo-web rust-web-src lld-14)

thumb_debian_ready() {
    [[ -x /usr/bin/cargo && -x /usr/bin/rustc && -d /usr/lib/rustlib/src/rust/library/core ]] &&
        command -v ld.lld-14 >/dev/null
}

thumb_acquire() {
    if [[ "${MLMAP_THUMB_VIA:-}" != debian ]] && command -v rustup >/dev/null; then
        if rustup target list --installed 2>/dev/null | grep -qx "$THUMB_TARGET"; then
            echo "thumb: $THUMB_TARGET already installed by rustup"
            THUMB_VIA=rustup
            return 0
        fi
        # One failed attempt per run of .ci/run (the steps share its process as parent):
        # an unreachable rustup server costs the timeout once, not once per step.
        local failed="${TMPDIR:-/tmp}/mlmap-rustup-target-add-failed.$PPID"
        if [[ ! -e "$failed" ]]; then
            echo "thumb: timeout 120 rustup target add $THUMB_TARGET"
            if timeout 120 rustup target add "$THUMB_TARGET"; then
                THUMB_VIA=rustup
                return 0
            fi
            : >"$failed"
        fi
        echo "thumb: rustup could not add $THUMB_TARGET; falling back to Debian's Rust packages"
    fi
    if ! thumb_debian_ready; then
        echo "thumb: apt-get install -y --no-install-recommends ${DEBIAN_RUST_PACKAGES[*]}"
        if ! { apt-get update -qq &&
            DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
                "${DEBIAN_RUST_PACKAGES[@]}" >/dev/null; }; then
            echo "thumb: could not install Debian's Rust packages"
        fi
    fi
    if thumb_debian_ready; then
        echo "thumb: using Debian's $(/usr/bin/rustc --version) with -Zbuild-std=core"
        THUMB_VIA=debian
        return 0
    fi
    THUMB_VIA=none
}

thumb_cargo() {
    case "$THUMB_VIA" in
    rustup)
        cargo "$@" --target "$THUMB_TARGET"
        ;;
    debian)
        # Own target directory: artifacts of another compiler, and a `core` built here.
        CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$THUMB_TARGET_DIR}/debian" \
            RUSTC_BOOTSTRAP=1 RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc \
            /usr/bin/cargo "$@" --target "$THUMB_TARGET" \
            -Zbuild-std=core -Zbuild-std-features=compiler-builtins-mem \
            --config "target.$THUMB_TARGET.linker = 'ld.lld-14'"
        ;;
    *)
        echo "thumb_cargo: no toolchain for $THUMB_TARGET" >&2
        return 1
        ;;
    esac
}

# The output directory of a `thumb_cargo build` (an absolute path unless CARGO_TARGET_DIR
# is a relative one).
thumb_out_dir() { # $1 = profile directory (firmware, release-size, debug)
    case "$THUMB_VIA" in
    debian) echo "${CARGO_TARGET_DIR:-$THUMB_TARGET_DIR}/debian/$THUMB_TARGET/$1" ;;
    *) echo "${CARGO_TARGET_DIR:-$THUMB_TARGET_DIR}/$THUMB_TARGET/$1" ;;
    esac
}

thumb_skipped_banner() { # $1 = what was skipped
    proof_not_run "$1" \
        "No toolchain for $THUMB_TARGET: \`rustup target add\` failed and" \
        "Debian's ${DEBIAN_RUST_PACKAGES[*]} could not be installed."
}

# A proof that cannot run fails: prints why and exits 1. Only outside CI, and only with
# MLMAP_ALLOW_SKIP=1 in the environment, does it exit 0 (for a machine that lacks a
# toolchain on purpose); CI=true ignores that variable.
proof_not_run() { # $1 = the proof, then lines saying why
    local what=$1 line
    shift
    printf '\n##########################################################################\n'
    printf '##  NOT RUN: %s\n' "$what"
    for line in "$@"; do printf '##  %s\n' "$line"; done
    if [[ "${MLMAP_ALLOW_SKIP:-}" == 1 && "${CI:-}" != true ]]; then
        printf '##  MLMAP_ALLOW_SKIP=1: skipped on this machine (never in CI).\n'
        printf '##########################################################################\n\n'
        exit 0
    fi
    printf '##  A proof that cannot run fails (MLMAP_ALLOW_SKIP=1 skips it outside CI).\n'
    printf '##########################################################################\n\n'
    exit 1
}
