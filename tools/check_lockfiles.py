#!/usr/bin/env python3
"""Checks that every Cargo.lock of the repository resolves a shared package to one version.

The root workspace and the sub-crates built on their own (ffi/, python/, fuzz/, firmware/,
nostd-check/, footprint/) each have a lockfile. A package that two of them lock at different
versions of one semver line (postcard 1.2.0 in one, 1.1.3 in another) means the layer is
tested with one dependency and shipped with another. Two lines of one package (bitflags 1 and
2, pulled in by different dependents) are allowed. Exit 1 names every package locked at two
versions of one line and where each version is locked.

    python3 tools/check_lockfiles.py            # from the repository root
"""
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def lockfiles(root):
    skip = {"target", ".git"}
    for path in sorted(root.rglob("Cargo.lock")):
        if not skip.intersection(path.relative_to(root).parts):
            yield path


def semver_line(version):
    """The part of a version that semver-compatible versions share: `1` for 1.2.0, `0.4`
    for 0.4.8, `0.0.3` for 0.0.3."""
    parts = version.split("+")[0].split("-")[0].split(".")
    for i, part in enumerate(parts):
        if part != "0" or i == len(parts) - 1:
            return ".".join(parts[: i + 1])
    return version


def main():
    seen = {}  # name -> {version: [lockfile, ...]}
    files = list(lockfiles(ROOT))
    for path in files:
        with open(path, "rb") as fh:
            lock = tomllib.load(fh)
        for pkg in lock.get("package", []):
            if "source" not in pkg:
                continue  # the project's own crates
            seen.setdefault((pkg["name"], semver_line(pkg["version"])), {}).setdefault(pkg["version"], []).append(
                str(path.relative_to(ROOT)))
    bad = {name: vs for name, vs in seen.items() if len(vs) > 1}
    for (name, _), versions in sorted(bad.items()):
        where = "; ".join(f"{v} in {', '.join(fs)}" for v, fs in sorted(versions.items()))
        print(f"{name}: {where}", file=sys.stderr)
    if bad:
        print(f"{len(bad)} packages locked at more than one version across {len(files)} "
              "lockfiles: run `cargo update -p NAME --precise VERSION` in the sub-crate",
              file=sys.stderr)
        return 1
    print(f"{len(files)} lockfiles, {len(seen)} registry packages (by semver line), "
          "one version each")
    return 0


if __name__ == "__main__":
    sys.exit(main())
