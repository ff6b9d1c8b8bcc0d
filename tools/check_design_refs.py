#!/usr/bin/env python3
"""Checks that every citation of the design document resolves.

Code, tests, tools and docs cite docs/DESIGN.md as `DESIGN §1.2`, `DESIGN §1.4, §1.5,
§4`, `DESIGN.md §1.4-§1.5`, `DESIGN.md section 1.2`, and name an invariant of a section
as `DESIGN §1.3 (5)`, `DESIGN §1.3, invariant 5` or `DESIGN §1.3, invariants 1, 2 and
4`. This script finds every such citation in the repository and fails when
docs/DESIGN.md has no heading with that number (`### 1.2 ...`), or when the section has
no numbered item for a cited invariant (`5. ...`). Inside docs/DESIGN.md itself, the
cross-references `section 1.6` and `section 1.3 (5)` are checked the same way.

It also fails when a file points to a design document or paper outside the repository
(a path through `shared/`).

Usage: python3 tools/check_design_refs.py [REPO_ROOT]     (stdlib only)
       python3 tools/check_design_refs.py --self-test
Exit status: 0 when everything resolves, 1 otherwise (each problem printed as
`file:line: message`).
"""

import os
import re
import sys

DESIGN = os.path.join("docs", "DESIGN.md")

# Directories never scanned: build output, VCS data, fuzz inputs and outputs.
SKIP_DIRS = {".git", "target", "corpus", "artifacts", "node_modules", "__pycache__"}
# Files whose content is data, not prose or code.
SKIP_EXT = {".mlmap", ".npy", ".bin", ".svg", ".png", ".csv", ".json", ".lock"}

NUM = r"\d+(?:\.\d+)*"
# `DESIGN §1.2`, `DESIGN.md §1.4-§1.5`, `DESIGN §1.4, §1.5, §4`, `DESIGN.md section 1.2`.
CITATION = re.compile(
    r"DESIGN(?:\.md)?\s+(?:§\s*|sections?\s+)(" + NUM + r")"
    r"((?:\s*(?:,|-|–|and)\s*(?:§\s*)?" + NUM + r"(?!\s*invariant))*)"
)
# Cross-references inside docs/DESIGN.md: `section 1.6`, `sections 1.5 and 1.7`.
INTERNAL = re.compile(
    r"\bsections?\s+(" + NUM + r")((?:\s*(?:,|-|–|and)\s*" + NUM + r")*)"
)
MORE = re.compile(NUM)
# What may follow a section number to name its invariants (items).
ITEM_PAREN = re.compile(r"\s*\((\d+)\)")
ITEM_WORDS = re.compile(r",?\s*invariants?\s+(\d+(?:\s*(?:,|and)\s*\d+)*)")
# A pointer out of the repository.
OUTSIDE = re.compile(r"(?:\.\./)+shared/|/shared/(?:DESIGN\.md|seed/)")


def headings(text):
    """Section number -> set of its numbered items, from the design document."""
    sections = {}
    current = None
    heading = re.compile(r"^#{1,6}\s+(" + NUM + r")\.?\s")
    item = re.compile(r"^(\d+)\.\s")
    in_code = False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            in_code = not in_code
            continue
        if in_code:
            continue
        m = heading.match(line)
        if m:
            current = m.group(1)
            sections.setdefault(current, set())
            continue
        if line.startswith("#"):
            current = None
            continue
        m = item.match(line)
        if m and current is not None:
            sections[current].add(m.group(1))
    return sections


def expand(first, rest):
    """Every section number of a citation; a range `1.4-1.5` names its two ends."""
    return [first] + MORE.findall(rest)


def items_after(text, end):
    """Invariant numbers named right after a citation ending at `end`."""
    tail = text[end : end + 60]
    m = ITEM_PAREN.match(tail) or ITEM_WORDS.match(tail)
    return re.findall(r"\d+", m.group(1)) if m else []


def check_text(path, text, sections, internal=False):
    """Problems of one file, as `(line, message)`."""
    problems = []
    patterns = [CITATION] + ([INTERNAL] if internal else [])
    for pattern in patterns:
        for m in pattern.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            nums = expand(m.group(1), m.group(2))
            for n in nums:
                if n not in sections:
                    problems.append((line, f"`{m.group(0).strip()}`: no heading {n} in {DESIGN}"))
            for item in items_after(text, m.end()):
                n = nums[-1]
                if n in sections and item not in sections[n]:
                    problems.append(
                        (line, f"`{m.group(0).strip()}`: section {n} has no item {item}")
                    )
    for m in OUTSIDE.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        problems.append((line, f"`{m.group(0)}` points outside the repository"))
    return problems


def files(root):
    for top, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("mlmap-demo"))
        for name in sorted(names):
            if os.path.splitext(name)[1] in SKIP_EXT:
                continue
            yield os.path.join(top, name)


def check_repo(root):
    design_path = os.path.join(root, DESIGN)
    try:
        with open(design_path, encoding="utf-8") as f:
            design = f.read()
    except OSError as e:
        return [f"{DESIGN}: cannot read: {e}"], 0
    sections = headings(design)
    out, cited = [], 0
    this = os.path.abspath(__file__)
    for path in files(root):
        if os.path.abspath(path) == this:
            continue  # its docstring shows citation forms, not citations
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except (UnicodeDecodeError, OSError):
            continue
        rel = os.path.relpath(path, root)
        cited += len(CITATION.findall(text))
        for line, msg in check_text(rel, text, sections, internal=(rel == DESIGN)):
            out.append(f"{rel}:{line}: {msg}")
    return out, cited


def self_test():
    design = "\n".join(
        [
            "# T",
            "## 1. Maths",
            "### 1.2 Inference",
            "### 1.3 Invariants",
            "1. first",
            "2. second",
            "```",
            "### 9.9 inside a code block",
            "```",
            "## 4. CLI",
        ]
    )
    s = headings(design)
    assert set(s) == {"1", "1.2", "1.3", "4"}, s
    assert s["1.3"] == {"1", "2"}, s
    good = [
        "see DESIGN §1.2.",
        "DESIGN §1.3 (2)",
        "DESIGN §1.3, invariant 1",
        "DESIGN §1.3, invariants 1 and 2",
        "DESIGN §1.2, §1.3; issue",
        "DESIGN.md §1.2-§1.3",
        "DESIGN.md section 1.2 in",
        "DESIGN §4 keys",
    ]
    for t in good:
        assert check_text("x", t, s) == [], (t, check_text("x", t, s))
    bad = [
        "DESIGN §1.7",
        "DESIGN §1.2, §5",
        "DESIGN §1.3 (5)",
        "DESIGN §1.3, invariants 1, 2 and 4",
        "DESIGN.md section 2",
        "see ../shared/DESIGN.md",
        "the paper in ../shared/seed/x.txt",
    ]
    for t in bad:
        assert len(check_text("x", t, s)) == 1, (t, check_text("x", t, s))
    assert len(check_text("x", "as section 1.6 says", s, internal=True)) == 1
    assert check_text("x", "as section 1.2 says", s, internal=True) == []
    assert check_text("x", "as section 1.6 says", s) == []
    print("self-test passed")


def main(argv):
    if argv[1:2] == ["--self-test"]:
        self_test()
        return 0
    root = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    problems, cited = check_repo(root)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} unresolved design reference(s)")
        return 1
    print(f"{cited} design citation(s), all resolved in {DESIGN}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
