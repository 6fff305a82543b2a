"""What the CI checks share: the workspace's crates, their non-test source files, and each
file's text with comments, literals and test modules blanked (line breaks kept, so a
position still names its line). Not a check itself; `.ci/*.py` import it.

A test file is one a `#[cfg(test)]` declaration brings in (`#[cfg(test)] mod tests;`); an
inline `#[cfg(test)] mod NAME { ... }` is blanked. The checks are about the code a user
runs: tests may name flags, reach any layer and run long tables.
"""

import os
import re

from import_cycles import remove_test_modules, strip_comments_and_strings, workspace_roots

__all__ = [
    "crate_files",
    "code_of",
    "line_of",
    "remove_test_modules",
    "strip_comments_and_strings",
    "workspace_roots",
]

# `#[cfg(test)]` with any other attributes after it, then `mod NAME;`.
TEST_MOD = re.compile(r"#\[cfg\(test\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;")
MOD = re.compile(r"(?:#\[path\s*=\s*\"([^\"]+)\"\]\s*)?(?:pub(?:\([^)]*\))?\s+)?\bmod\s+(\w+)\s*;")


def crate_files(root):
    """The non-test .rs files of the crate whose src/ is `root`, as (path, module path
    tuple), from lib.rs and main.rs down its `mod` declarations."""
    found = []
    seen = set()

    def add(path, module):
        if path in seen or not os.path.exists(path):
            return
        seen.add(path)
        found.append((path, module))
        raw = open(path, encoding="utf-8").read()
        text = remove_test_modules(strip_comments_and_strings(raw))
        tests = {m.group(1) for m in TEST_MOD.finditer(text)}
        base = os.path.dirname(path)
        stem = os.path.splitext(os.path.basename(path))[0]
        if stem not in ("lib", "main", "mod"):
            base = os.path.join(base, stem)
        for m in MOD.finditer(text):
            name = m.group(2)
            if name in tests:
                continue
            for candidate in (os.path.join(base, name + ".rs"), os.path.join(base, name, "mod.rs")):
                if os.path.exists(candidate):
                    add(os.path.normpath(candidate), module + (name,))
                    break

    for entry in ("lib.rs", "main.rs"):
        add(os.path.normpath(os.path.join(root, entry)), ())
    return found


def code_of(path):
    """The file's text without comments, literals and inline test modules."""
    return remove_test_modules(strip_comments_and_strings(open(path, encoding="utf-8").read()))


def line_of(text, pos):
    """The 1-based line of a position in `text`."""
    return text.count("\n", 0, pos) + 1
