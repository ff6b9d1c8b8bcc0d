#!/usr/bin/env python3
"""Checks that the repository is one Cargo workspace with one lockfile.

Every crate of the repository (each directory with a Cargo.toml) must be a member of the
root workspace, and the only Cargo.lock must be the root one. Cargo does not guarantee
either: a crate that declares a `[workspace]` of its own is built on its own, with a
lockfile of its own, and cargo ignores a Cargo.lock left in a member's directory. Either
would let a crate build against other dependency versions than the rest. Exit 1 names
every crate outside the workspace and every extra lockfile.

    python3 tools/check_workspace.py            # from anywhere
"""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SKIP = {"target", ".git"}


def files(name):
    for path in sorted(ROOT.rglob(name)):
        rel = path.relative_to(ROOT)
        if not SKIP.intersection(rel.parts):
            yield rel


def main():
    metadata = json.loads(subprocess.run(
        ["cargo", "metadata", "--no-deps", "--format-version", "1",
         "--manifest-path", str(ROOT / "Cargo.toml")],
        check=True, capture_output=True, text=True).stdout)
    members = {Path(p["manifest_path"]).resolve().relative_to(ROOT)
               for p in metadata["packages"] if p["id"] in metadata["workspace_members"]}
    manifests = set(files("Cargo.toml"))
    locks = set(files("Cargo.lock"))
    failures = []
    for path in sorted(manifests - members):
        failures.append(f"{path}: a crate outside the workspace (add it to the root's members)")
    for path in sorted(locks - {Path("Cargo.lock")}):
        failures.append(f"{path}: a second lockfile (the workspace's is the root Cargo.lock)")
    if Path("Cargo.lock") not in locks:
        failures.append("Cargo.lock: missing at the root")
    for failure in failures:
        print(failure, file=sys.stderr)
    if failures:
        return 1
    print(f"ok: {len(members)} crates, all members of the root workspace; one Cargo.lock")
    return 0


if __name__ == "__main__":
    sys.exit(main())
