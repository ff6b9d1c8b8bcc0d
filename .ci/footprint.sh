#!/usr/bin/env bash
# Informational: the footprint of mlmap's decode + ML + MAP on a Cortex-M4F
# (thumbv7em-none-eabihf, opt-level "s", LTO, panic abort), measured on footprint/:
#   * flash: .text and .rodata of three builds of the same skeleton (no mlmap call,
#     decoding only, decoding + ML + MAP); the differences are the layer's;
#   * the encoded size of the shipped K = 3, 22/17-bin table;
#   * stack: the frame of every function (-Z emit-stack-sizes, read by
#     llvm-readobj --stack-sizes) and the deepest call chain of decoding and of scoring;
#   * heap: allocator symbols in the image (there must be none).
# The target comes from .ci/thumb-toolchain.sh (rustup, or Debian's packages); -Z flags
# are enabled on that same compiler with RUSTC_BOOTSTRAP=1, so that the frames are
# those of the very code whose size is reported. Goals are printed next to the figures;
# a missed goal does not fail the script. Run from the repository root.
set -euo pipefail

section() { printf '\n==== footprint: %s ====\n' "$*"; }
[[ -f Cargo.toml && -d footprint ]] || {
    echo "footprint: run from the repository root" >&2
    exit 1
}
start=$SECONDS
# shellcheck source=.ci/thumb-toolchain.sh
source .ci/thumb-toolchain.sh

section "toolchain for $THUMB_TARGET"
thumb_acquire
if [[ "$THUMB_VIA" == none ]]; then
    thumb_skipped_banner "the footprint measurement on $THUMB_TARGET"
fi
echo "toolchain: $THUMB_VIA"

# llvm-size, llvm-nm, llvm-readobj, llvm-objdump: on PATH (any version), from the
# toolchain's llvm-tools component, or from Debian's llvm-14.
llvm_tool() { # $1 = tool name without the llvm- prefix
    local t sysroot host
    for t in "llvm-$1" "llvm-$1-"{19,18,17,16,15,14}; do
        if command -v "$t" >/dev/null; then
            command -v "$t"
            return 0
        fi
    done
    if [[ "$THUMB_VIA" == rustup ]]; then
        sysroot=$(rustc --print sysroot)
        host=$(rustc -vV | sed -n 's/^host: //p')
        t="$sysroot/lib/rustlib/$host/bin/llvm-$1"
        [[ -x "$t" ]] || timeout 120 rustup component add llvm-tools >&2 || true
        if [[ -x "$t" ]]; then
            echo "$t"
            return 0
        fi
    fi
    return 1
}
if ! SIZE=$(llvm_tool size) || ! NM=$(llvm_tool nm) || ! READOBJ=$(llvm_tool readobj) ||
    ! OBJDUMP=$(llvm_tool objdump); then
    echo "footprint: apt-get install -y --no-install-recommends llvm-14"
    { apt-get update -qq &&
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            llvm-14 >/dev/null; } || true
    if ! SIZE=$(llvm_tool size) || ! NM=$(llvm_tool nm) || ! READOBJ=$(llvm_tool readobj) ||
        ! OBJDUMP=$(llvm_tool objdump); then
        proof_not_run "the Cortex-M4F footprint" \
            "no llvm-size/llvm-nm/llvm-readobj/llvm-objdump (rustup llvm-tools or Debian llvm-14)"
    fi
fi
echo "tools: $SIZE, $READOBJ"

unset MLMAP_TABLE
# From its directory: its .cargo/config.toml selects the target and the linker script.
cd footprint
elfs=$(mktemp -d)
frames=$(mktemp)
calls=$(mktemp)
trap 'rm -rf "$elfs" "$frames" "$calls" "$calls.names"' EXIT
# Every variant builds into the workspace's target directory (the library's artifacts
# are shared) and is copied out, as the next build replaces the image; the stack build,
# with other compiler flags, has a target directory of its own.
build() { # $1 = variant (full, decode-only, baseline, ...), rest = extra cargo arguments
    local variant=$1
    shift
    local features=()
    [[ "$variant" == full || "$variant" == stack ]] || features=(--features "$variant")
    thumb_cargo build --profile release-size --quiet "${features[@]}" "$@"
    cp "$(thumb_out_dir release-size)/mlmap-footprint" "$elfs/$variant"
    echo "$elfs/$variant"
}
section_size() { # $1 = ELF, $2 = section
    "$SIZE" -A "$1" | awk -v s="$2" '$1 == s { print $2; found = 1 } END { if (!found) print 0 }'
}

section "builds: opt-level \"s\", LTO, codegen-units 1, panic abort"
full=$(build full)
decode=$(build decode-only)
base=$(build baseline)
stack=$(RUSTC_BOOTSTRAP=1 CARGO_TARGET_DIR="$THUMB_TARGET_DIR/footprint-stack" build stack \
    --config "target.$THUMB_TARGET.rustflags = [\"-Zemit-stack-sizes\"]")
for elf in "$full" "$decode" "$base"; do
    echo "${elf##*/}:"
    "$SIZE" -A "$elf" | grep -E '^\.(vector_table|text|rodata|data|bss) '
done

section "flash"
declare -A text rodata
for v in full decode base; do
    elf=${!v}
    text[$v]=$(section_size "$elf" .text)
    rodata[$v]=$(section_size "$elf" .rodata)
done
code=$((text[full] - text[base]))
code_decode=$((text[decode] - text[base]))
code_infer=$((text[full] - text[decode]))
ro=$((rodata[full] - rodata[base]))
# compiler-builtins' memcpy/memset family: every firmware has it already.
mem=0
while read -r _ size _ name; do
    if [[ "$name" =~ ^(__aeabi_mem|memcpy$|memset$|memmove$|memcmp$|bcmp$|compiler_builtins::mem::) ]]; then
        mem=$((mem + 16#$size))
    fi
done < <("$NM" -S -C "$full")
verdict() { if (($1 <= $2)); then echo "met"; else echo "MISSED"; fi; }
printf '.text of decode + ML + MAP: %d B (decode %d B, ML + MAP %d B); goal <= 2048 B: %s\n' \
    "$code" "$code_decode" "$code_infer" "$(verdict "$code" 2048)"
printf '  of which %d B are compiler-builtins memcpy/memset/memcmp (in any firmware already)\n' "$mem"
printf '.rodata of the layer: %d B (without the %d-byte table file, which the baseline holds too)\n' \
    "$ro" "$(wc -c <../tables/default.mlmap)"
echo "largest symbols of the full image (bytes):"
"$NM" -S -C --size-sort "$full" | tail -n 12 | while read -r _ size kind name; do
    printf '  %6d %s %s\n' $((16#$size)) "$kind" "${name%%::h[0-9a-f]*}"
done

section "the quantized table (int8, tables/default_q8.mlmap's section)"
quant=$(build quantized)
quant_bayes=$(build quantized-bayes)
qcode=$(($(section_size "$quant" .text) - text[base]))
qbayes=$(($(section_size "$quant_bayes" .text) - text[base]))
qsec=$(python3 -c 'import struct,sys; b=open(sys.argv[1],"rb").read(); print(struct.unpack("<I", b[-8:-4])[0])' ../tables/default_q8.mlmap 2>/dev/null || echo 0)
printf '.text of QTable decode + ML + MAP: %d B; goal <= 4096 B: %s\n' "$qcode" "$(verdict "$qcode" 4096)"
printf '.text of QTable decode + ML + MAP + Bayes: %d B\n' "$qbayes"
printf 'quantized section (ML, MAP, Bayes): %d B\n' "$qsec"

section "the MAP head's exp backends (.text of decode + ML + MAP)"
for backend in map-fastmath map-micromath; do
    elf=$(build "$backend")
    printf '%s: %d B (libm: %d B)\n' "$backend" "$(($(section_size "$elf" .text) - text[base]))" "$code"
done

section "table file"
bytes=$(wc -c <../tables/default.mlmap)
printf 'tables/default.mlmap (K = 3; 22 ML, 17 MAP, 22 Bayes bins; 4 categories): %d B encoded; goal <= 800 B: %s\n' \
    "$bytes" "$(verdict "$bytes" 800)"

section "stack (frames from -Z emit-stack-sizes)"
# "<frame bytes> <mangled name>" for every function; mangled names are mapped to
# demangled ones through llvm-nm's two listings of the same symbols.
"$READOBJ" --stack-sizes "$stack" | awk '
    /Functions: \[/ { f = $0; sub(/.*Functions: \[/, "", f); sub(/\].*/, "", f) }
    /Size: 0x/ { print $2, f }' | while read -r size names; do
    for n in ${names//,/ }; do echo "$((size)) $n"; done
done | sort -k2 -u >"$frames"
paste -d' ' <("$NM" -p "$stack" | awk '{ print $NF }') \
    <("$NM" -p -C "$stack" | sed -E 's/^([0-9a-f]{8} )?. //') |
    sed -E 's/::h[0-9a-f]{16}$//' | sort -k1,1 -u >"$calls.names"
# Calls and tail calls to other functions (branches inside a function name `f+0x..`).
"$OBJDUMP" -d --no-show-raw-insn "$stack" | awk '
    /^[0-9a-f]+ <.*>:$/ { f = $2; gsub(/[<>:]/, "", f) }
    /\t(bl|b\.w|b)\t/ && match($0, /<[^>]+>/) {
        t = substr($0, RSTART + 1, RLENGTH - 2)
        if (t !~ /^\$/ && t !~ /\+0x/ && t != f) print f, t
    }' | sort -u >"$calls"
if ! command -v python3 >/dev/null; then
    proof_not_run "the stack call chains" "python3 not found"
fi
report=$(python3 - "$frames" "$calls" "$calls.names" <<'PY'
import sys
frames = {}
for line in open(sys.argv[1]):
    size, name = line.split(maxsplit=1)
    frames[name.strip()] = int(size)
calls = {}
for line in open(sys.argv[2]):
    a, b = line.split()
    calls.setdefault(a, set()).add(b)
names = {}
for line in open(sys.argv[3]):
    parts = line.rstrip("\n").split(" ", 1)
    if len(parts) == 2:
        names[parts[0]] = parts[1]
def name(f):
    return names.get(f, f)
def depth(f, seen=()):
    if f in seen:
        return 0, [f + " (recursion)"]
    best, chain = 0, []
    for g in calls.get(f, ()):
        d, c = depth(g, seen + (f,))
        if d > best:
            best, chain = d, c
    return frames.get(f, 0) + best, [f] + chain
by_demangled = {name(f): f for f in set(frames) | set(calls)}
print("frames (bytes), largest first:")
for f, s in sorted(frames.items(), key=lambda kv: -kv[1])[:10]:
    print("  %5d  %s" % (s, name(f)))
layer = [(s, f) for f, s in frames.items()
         if name(f).startswith(("mlmap", "libm", "postcard", "serde", "core::", "crc", "heapless"))
         or name(f) in ("mlmap_footprint::decode", "mlmap_footprint::score")]
s, f = max(layer)
print("largest frame of the layer: %d B (%s)" % (s, name(f)))
for entry in ("mlmap_footprint::decode", "mlmap_footprint::score"):
    f = by_demangled.get(entry)
    if f is None:
        continue
    d, chain = depth(f)
    print("deepest chain from %s: %d B: %s" % (
        entry, d, " -> ".join("%s (%d)" % (name(g), frames.get(g, 0)) for g in chain)))
print("LARGEST %d" % s)
PY
)
grep -v '^LARGEST' <<<"$report"
largest=$(sed -n 's/^LARGEST //p' <<<"$report")
printf 'goal: largest frame <= 256 B: %s\n' "$(verdict "$largest" 256)"
echo "(mlmap_footprint::decode is Table::from_bytes inlined; its frame holds the table"
echo " it returns. With rustup's precompiled core, compiler-builtins' memcpy & co."
echo " have no stack-size entry and count 0 in the chains; built from source (Debian's"
echo " packages, -Zbuild-std) memcpy measures 56 B.)"

section "heap"
if "$NM" -u "$full" | grep -qE '__rust_alloc|__rust_dealloc|malloc|free'; then
    echo "heap: an allocator symbol is referenced: MISSED"
else
    echo "heap: 0 B (no allocator symbol in the image; no global allocator is linked); goal 0: met"
fi

section "done in $((SECONDS - start)) s (via $THUMB_VIA)"
