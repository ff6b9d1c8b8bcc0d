#!/usr/bin/env python3
"""Checks two promises of the core crate (core/src) that the compiler cannot:

* every public struct and enum the crate exports has a `defmt::Format` impl (feature
  `defmt`), as the README says;
* every exported error enum (`...Error`) has one `message()` per variant, from which its
  `Display` and `defmt` output start.

Exits 1 naming what is missing. Run from the repository root: `python3 tools/check_defmt.py`.
"""
import pathlib
import re
import sys

SRC = pathlib.Path("core/src")


def exported_names(lib: str) -> set:
    """Names in the crate root's `pub use` lines, outside the hidden `__embed` module."""
    lib = re.sub(r"pub mod __embed \{.*?\n\}", "", lib, flags=re.S)
    names = set()
    for block in re.findall(r"pub use [\w:]+::\{([^}]*)\}|pub use [\w:]+::(\w+);", lib):
        for part in block:
            names.update(n.strip() for n in part.split(",") if n.strip())
    return names


def public_modules(lib: str) -> list:
    """`x` for every `pub mod x;` and every `pub use group::x;` (a module re-export:
    a lowercase name) at the crate root."""
    declared = re.findall(r"^pub mod (\w+);", lib, flags=re.M)
    reexported = re.findall(r"^pub use (?:\w+::)+([a-z_][a-z0-9_]*);", lib, flags=re.M)
    return declared + reexported


def main() -> int:
    files = {p: p.read_text() for p in SRC.rglob("*.rs")}
    text = "\n".join(files.values())
    types = set(re.findall(r"^pub (?:struct|enum) (\w+)", text, flags=re.M))
    exported = exported_names(files[SRC / "lib.rs"]) & types
    # The public modules, declared at the root (`pub mod x;`) or re-exported from a
    # group directory (`pub use group::x;`): every public type in them is public too.
    for module in public_modules(files[SRC / "lib.rs"]):
        for path, body in files.items():
            rel = path.relative_to(SRC).with_suffix("")
            if module in rel.parts:
                exported |= set(re.findall(r"^pub (?:struct|enum) (\w+)", body, flags=re.M))
    formatted = set(re.findall(r"Format for (?:crate::)?(\w+)", text))
    derived = set(
        re.findall(r'derive\(defmt::Format\)\]\s*(?:#\[[^\]]*\]\s*)*pub (?:struct|enum) (\w+)', text)
    )
    missing = sorted(exported - formatted - derived)
    errors = sorted(n for n in exported if n.endswith("Error"))
    no_message = []
    for name in errors:
        if not re.search(r"impl %s \{[^}]*?pub const fn message\(&?self\)" % name, text, flags=re.S):
            no_message.append(name)
    for name in missing:
        print(f"check_defmt: {name} is exported by mlmap-core and has no defmt::Format impl")
    for name in no_message:
        print(f"check_defmt: {name} has no `pub const fn message(self)`")
    if missing or no_message:
        return 1
    print(f"check_defmt: {len(exported)} exported types have defmt::Format; "
          f"{len(errors)} error enums have message()")
    return 0


if __name__ == "__main__":
    sys.exit(main())
