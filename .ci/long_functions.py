#!/usr/bin/env python3
"""No function of the workspace's non-test code is longer than LIMIT lines (from its `fn`
line to its closing brace), unless a comment right above it (among its doc comments and
attributes) says why, in the form `// Over 100 lines: WHY`. A long function is usually
several steps in a row; split it where its sections are (a writer by the sections it
writes, as the readers are split by the sections they read).

Usage: python3 .ci/long_functions.py [--strict]   (--strict: the KNOWN list counts as offenders)
       python3 .ci/long_functions.py --self-test
       python3 .ci/long_functions.py --list        (every function over the limit, longest first)
Exits 1 listing every function over the limit, with its file, line and length.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rust_source import code_of, crate_files, line_of, workspace_roots  # noqa: E402

LIMIT = 100
REASON = re.compile(r"^\s*//\s*Over 100 lines:\s*\S")

# Functions over the limit in code someone else was changing when this check was added, as
# "FILE:FUNCTION". Each is a debt: split it by its sections, then delete its entry (the
# script says when one has become stale).
KNOWN = set()

FN = re.compile(r"\bfn\s+(\w+)")


def functions(path):
    """(name, first line, length in lines) of every function with a body in the file's
    non-test code."""
    text = code_of(path)
    out = []
    for m in FN.finditer(text):
        # The body starts at the first `{` outside the signature's brackets; a `;` first
        # means a declaration without a body (a trait's required method).
        depth, j = 0, m.end()
        while j < len(text):
            ch = text[j]
            if ch in "(<[":
                depth += 1
            elif ch in ")>]":
                # `->` is no closing bracket.
                if not (ch == ">" and text[j - 1] == "-"):
                    depth -= 1
            elif ch == ";" and depth <= 0:
                j = -1
                break
            elif ch == "{" and depth <= 0:
                break
            j += 1
        if j < 0 or j >= len(text):
            continue
        level, k = 1, j + 1
        while k < len(text) and level:
            level += {"{": 1, "}": -1}.get(text[k], 0)
            k += 1
        first, last = line_of(text, m.start()), line_of(text, k - 1)
        out.append((m.group(1), first, last - first + 1))
    return out


def has_reason(lines, first):
    """Whether the comments and attributes right above line `first` (1-based) give the
    reason for a long function."""
    i = first - 2
    while i >= 0:
        line = lines[i].strip()
        if REASON.match(lines[i]):
            return True
        if line.startswith("//") or line.startswith("#[") or line.startswith("#!["):
            i -= 1
            continue
        return False
    return False


def long_functions(roots, limit=LIMIT):
    """(file, line, name, length, has a reason) of every function over `limit` lines."""
    out = []
    for root in roots:
        for path, _ in crate_files(root):
            lines = open(path, encoding="utf-8").read().split("\n")
            for name, first, length in functions(path):
                if length > limit:
                    out.append((path, first, name, length, has_reason(lines, first)))
    return out


def run(roots, known, strict, limit=LIMIT):
    found = long_functions(roots, limit)
    bad, seen = [], set()
    for path, line, name, length, reason in found:
        key = f"{path}:{name}"
        if reason:
            continue
        if key in known:
            seen.add(key)
            if not strict:
                continue
        bad.append(f"{path}:{line}: fn {name} is {length} lines (limit {limit})")
    stale = [f"stale KNOWN entry, delete it: {k}" for k in sorted(known - seen)]
    return bad, stale


def self_test():
    import tempfile

    body = "    let x = 1;\n" * 101
    files = {
        "lib.rs": "mod a;\n#[cfg(test)]\nmod tests;\n",
        "a.rs": (
            f"pub fn long_one() {{\n{body}}}\n"
            f"/// Docs.\n// Over 100 lines: one table, row by row.\n#[inline]\nfn long_with_reason() {{\n{body}}}\n"
            f"fn short() -> Vec<u8> {{\n    vec![]\n}}\n"
            "trait T {\n    fn declared(&self);\n}\n"
            # Braces in a string and a comment do not count.
            f"fn tricky(x: impl Fn() -> u8) {{\n    let s = \"{{{{\";\n    // }}\n{body}}}\n"
            f"#[cfg(test)]\nmod inline {{\n    fn long_test() {{\n{body}    }}\n}}\n"
        ),
        "tests.rs": f"fn long_in_tests() {{\n{body}}}\n",
    }
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        found = sorted((n, length, r) for _, _, n, length, r in long_functions([root]))
        want = [("long_one", 103, False), ("long_with_reason", 103, True), ("tricky", 105, False)]
        bad, _ = run([root], {os.path.join(root, "a.rs") + ":long_one"}, False)
        strict_bad, _ = run([root], {os.path.join(root, "a.rs") + ":long_one"}, True)
    failed = 0
    if found != want:
        failed += 1
        print(f"self-test: found {found}, expected {want}")
    if len(bad) != 1 or "tricky" not in bad[0] or len(strict_bad) != 2:
        failed += 1
        print(f"self-test: known list: {bad}, strict: {strict_bad}")
    print(f"self-test: {2 - failed} passed, {failed} failed")
    return 1 if failed else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    here = os.path.dirname(os.path.abspath(__file__))
    os.chdir(os.path.dirname(here))
    roots = workspace_roots()
    if argv[1:] == ["--list"]:
        for path, line, name, length, reason in sorted(long_functions(roots), key=lambda f: -f[3]):
            print(f"{length:4} {path}:{line} {name}{'  (reason given)' if reason else ''}")
        return 0
    strict = "--strict" in argv[1:]
    bad, stale = run(roots, KNOWN, strict)
    for line in bad + ([] if strict else stale):
        print(line)
    print(f"{', '.join(roots)}: functions checked against {LIMIT} lines")
    if bad:
        print(f"{len(bad)} function(s) over {LIMIT} lines: split each by its sections, or say why above it")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
