#!/usr/bin/env bash
# Sourced by the CI steps that need a nightly toolchain (docs with the docsrs cfg, cargo
# fuzz, -Z flags). The nightly is pinned: every step builds with the same compiler on
# every machine. Sets NIGHTLY to a toolchain name for `cargo +"$NIGHTLY"`, or fails.
#
# The pin is the rustup channel date; its rustc reports the commit date, one day earlier.
MLMAP_NIGHTLY_CHANNEL=nightly-2026-05-20
MLMAP_NIGHTLY_RUSTC='rustc 1.97.0-nightly (e50aa6fba 2026-05-19)'

nightly_acquire() {
    local have
    if have=$(rustc +"$MLMAP_NIGHTLY_CHANNEL" --version 2>/dev/null) &&
        [[ "$have" == "$MLMAP_NIGHTLY_RUSTC" ]]; then
        NIGHTLY=$MLMAP_NIGHTLY_CHANNEL
    elif have=$(rustc +nightly --version 2>/dev/null) && [[ "$have" == "$MLMAP_NIGHTLY_RUSTC" ]]; then
        # The machine's `nightly` is the pinned one under its floating name.
        NIGHTLY=nightly
    else
        echo "nightly: installing $MLMAP_NIGHTLY_CHANNEL (the machine has: ${have:-none})"
        if timeout 300 rustup toolchain install "$MLMAP_NIGHTLY_CHANNEL" --profile minimal \
            --component rust-src --component llvm-tools-preview >&2 &&
            have=$(rustc +"$MLMAP_NIGHTLY_CHANNEL" --version) &&
            [[ "$have" == "$MLMAP_NIGHTLY_RUSTC" ]]; then
            NIGHTLY=$MLMAP_NIGHTLY_CHANNEL
        else
            echo "nightly: FAILED: the pinned nightly ($MLMAP_NIGHTLY_RUSTC) is not available" >&2
            return 1
        fi
    fi
    export NIGHTLY
}
