#!/usr/bin/env python3
"""The layers of the library's top-level modules: a module uses only modules of the layers
below its own, never a module of its own layer or of a layer above.

The order is stated once, here (LAYERS), and described in docs/architecture.md. It was
read off the imports of the code: each module sits on the lowest layer above everything
it uses. A use is a path (`crate::m::…`, `super::…` reaching another top-level module, or
`metamer::m::…` in the binary) in a file's non-test code; tests may reach any layer.

Usage: python3 .ci/layers.py [--strict]   (--strict: the KNOWN list counts as offenders)
       python3 .ci/layers.py --self-test
Exits 1 listing every import that runs up or across a layer, with its file and line.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rust_source import code_of, crate_files, line_of  # noqa: E402

# Bottom to top. `main` and `cli` are the binary: the command line over the library.
LAYERS = [
    # Leaves: no other module of the crate.
    ["calendar", "digest", "numeric_csv", "output", "plot"],
    # Colour science (metamer-color re-exported, the spectral tables).
    ["color"],
    # Images and their files; light distributions and their files.
    ["image", "light"],
    # The renderer; the session engine (its screen shows 8-bit images).
    ["render", "session"],
    # Another renderer's scene; one spot reading; validation of readings.
    ["export", "spot", "validation"],
    # The rig: screens, the simulated box and meter.
    ["rig"],
    # Measuring the box, on the rig.
    ["measure_box"],
    # The display: models, characterization on the rig, reproduction.
    ["display"],
    # The experiment's stages, over all of the above.
    ["experiment"],
    # The binary.
    ["main", "cli"],
]

# Imports known to run up a layer, each in a file someone else is changing, as
# "FILE -> MODULE" (every use of MODULE in FILE). Each entry is a debt: delete it once the
# import is gone (the script says when one has become stale).
KNOWN = set()


def layer_of(layers):
    return {m: i for i, names in enumerate(layers) for m in names}


def top_module(file_module, segments):
    """The top-level module a path names, seen from a file of module path `file_module`;
    None for other crates, std and the file's own items."""
    head = segments[0]
    if head in ("crate", "metamer"):
        return segments[1] if len(segments) > 1 else None
    if head in ("super", "self"):
        target = list(file_module)
        rest = list(segments)
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super":
                target = target[:-1]
            rest = rest[1:]
        full = target + rest
        return full[0] if full else None
    return None


PATH = re.compile(r"(?<![\w:])((?:crate|metamer|super|self)(?:::\w+)+)")


def violations(root, layers):
    """(file, line, module, used) for every use running up or across a layer."""
    level = layer_of(layers)
    out = []
    for path, module in crate_files(root):
        own = module[0] if module else os.path.splitext(os.path.basename(path))[0]
        if own not in level:
            continue
        text = code_of(path)
        # A `use` tree with braces names its prefix once: expand `a::{b, c::d}` into paths.
        for m in re.finditer(r"\buse\s+([^;]+);", text):
            for segments in expand(m.group(1)):
                check(out, level, path, module, own, segments, line_of(text, m.start()))
        body = re.sub(r"\buse\s+[^;]+;", lambda m: "\n" * m.group(0).count("\n"), text)
        for m in PATH.finditer(body):
            check(out, level, path, module, own, m.group(1).split("::"), line_of(body, m.start()))
    return sorted(set(out))


def check(out, level, path, module, own, segments, line):
    used = top_module(module, segments)
    if used is None or used == own or used not in level:
        return
    if level[used] >= level[own]:
        out.append((path, line, own, used))


def expand(tree, prefix=()):
    """Every path of a `use` tree, as segment lists (aliases dropped)."""
    tree = tree.strip()
    m = re.match(r"^([\w:]*?)(?:::)?\{(.*)\}$", tree, re.S)
    if not m:
        segments = [s for s in re.split(r"\s+as\s+", tree)[0].strip().split("::") if s]
        return [list(prefix) + segments] if segments else []
    head = [s for s in m.group(1).split("::") if s]
    parts, depth, start, inner = [], 0, 0, m.group(2)
    for k, ch in enumerate(inner):
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(inner[start:k])
            start = k + 1
    parts.append(inner[start:])
    result = []
    for part in parts:
        if part.strip() in ("self", ""):
            if part.strip() == "self":
                result.append(list(prefix) + head)
            continue
        result.extend(expand(part, tuple(prefix) + tuple(head)))
    return result


def run(root, layers, known, strict):
    found = violations(root, layers)
    bad, used_known = [], set()
    for path, line, own, used in found:
        key = f"{path} -> {used}"
        if not strict and key in known:
            used_known.add(key)
            continue
        bad.append((path, line, own, used))
    level = layer_of(layers)
    for path, line, own, used in bad:
        how = "up" if level[used] > level[own] else "across"
        print(f"{path}:{line}: {own} (layer {level[own]}) uses {used} (layer {level[used]}), {how} a layer")
    if not strict:
        for key in sorted(known - used_known):
            print(f"stale KNOWN entry, delete it: {key}")
        for key in sorted(used_known):
            print(f"known, to be removed: {key}")
    return bad


def self_test():
    import tempfile

    layers = [["low"], ["mid", "peer"], ["high"]]
    files = {
        "lib.rs": "pub mod low;\npub mod mid;\npub mod peer;\npub mod high;\n",
        "low.rs": "use crate::mid::M;\n",  # up: caught
        "mid/mod.rs": "mod a;\n#[cfg(test)]\nmod tests;\npub struct M;\n",
        # across (peer), in a braced tree; super:: reaching the root; a comment is no use.
        "mid/a.rs": "use crate::{low::L, peer::{P}};\nfn f() { super::super::high::h() }\n// crate::high\n",
        "mid/tests.rs": "use crate::high::H;\n",  # a test file: not looked at
        "peer.rs": "pub struct P;\n#[cfg(test)]\nmod tests { use crate::high::H; }\n",
        "high.rs": "use crate::low::L;\nfn g() { let _ = crate::mid::M; }\n",
    }
    want = [
        ("low.rs", 1, "low", "mid"),
        ("mid/a.rs", 1, "mid", "peer"),
        ("mid/a.rs", 2, "mid", "high"),
    ]
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        found = [(os.path.relpath(p, root), n, a, b) for p, n, a, b in violations(root, layers)]
    failed = 0 if sorted(found) == sorted(want) else 1
    if failed:
        print(f"self-test: found {found}, expected {want}")
    print(f"self-test: {1 - failed} passed, {failed} failed")
    return failed


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    strict = "--strict" in argv[1:]
    here = os.path.dirname(os.path.abspath(__file__))
    os.chdir(os.path.dirname(here))
    names = [m for layer in LAYERS for m in layer]
    top = sorted(
        {os.path.splitext(e)[0] for e in os.listdir("src") if e.endswith(".rs") or os.path.isdir(os.path.join("src", e))}
        - {"lib"}
    )
    unplaced = [m for m in top if m not in names and any(
        os.path.exists(p) for p in (f"src/{m}.rs", f"src/{m}/mod.rs"))]
    if unplaced:
        print(f"top-level modules on no layer (add them to LAYERS): {', '.join(unplaced)}")
        return 1
    bad = run("src", LAYERS, KNOWN, strict)
    print(f"src: {len(names)} modules on {len(LAYERS)} layers checked")
    if bad:
        print(f"{len(bad)} import(s) against the layers: move the item down, or the user up")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
