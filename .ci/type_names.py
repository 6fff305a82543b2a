#!/usr/bin/env python3
"""One name, one concept: no public type (struct, enum, trait, type alias, union) is
defined under the same name twice in the workspace's non-test code, unless the name is an
accepted role name (ROLE_NAMES), and no `use … as` renames a type that is defined twice.

A role name is the same part played in several modules, each type always reached by its
module path (`fit::Request`, `verify::Report`): reading the path says which one it is, so
no alias is needed, and an alias that is needed means the name is no role name.

Usage: python3 .ci/type_names.py [--strict]   (--strict: the KNOWN list counts as offenders)
       python3 .ci/type_names.py --self-test
Exits 1 listing every name defined twice, with each definition's file and line.
"""

import collections
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rust_source import code_of, crate_files, line_of, workspace_roots  # noqa: E402

# Names accepted in several modules, each for one role: why it is a role, not a concept.
ROLE_NAMES = {
    # Each command's clap arguments (`src/cli/NAME.rs`), reached as `NAME::Args`.
    "Args": "a command's arguments",
    # A library job's input, output and failure, one per job module (`display::job::fit`,
    # `display::job::verify`, …), reached by the module's path.
    "Request": "a job's input",
    "Report": "a job's result",
    "Error": "a job's failure",
    "Event": "what a job tells its caller as it runs",
    # Where a run ended (finished, incomplete, stopped), one per kind of run.
    "Outcome": "where a run ended",
    # What a finished run found, as its summary file writes it.
    "Summary": "a finished run's summary",
    # The files a run writes.
    "Files": "the files a run writes",
    # A candidate of a module's own selection (display models, light distribution models).
    "Candidate": "a candidate of a selection",
    # The header line of a JSON-lines file format (a journal, a transcript).
    "Header": "a JSON-lines file's header",
    # One emulator's settings per instrument model (`cs100a::`, `i1pro::`).
    "EmulatorConfig": "an instrument emulator's settings",
    # One protocol codec's reply error per instrument model.
    "ReplyError": "a protocol's reply error",
}

# Names defined twice for different concepts in code someone else is changing, as
# "NAME": {files}. Each is a debt: rename one of the types, then delete its entry (the
# script says when one has become stale).
KNOWN = {}

# `use … as` aliases of names defined twice, in code someone else is changing, as
# "FILE: NAME as ALIAS". Each is a debt, like KNOWN.
KNOWN_ALIASES = set()

DEFINITION = re.compile(
    r"(?m)^[ \t]*pub[ \t]+(?:unsafe[ \t]+)?(struct|enum|trait|type|union)[ \t]+([A-Za-z_]\w*)"
)
ALIAS = re.compile(r"\b([A-Z]\w*)\s+as\s+([A-Z]\w*)")


def definitions(roots):
    """name -> [(file, line, kind)] of every public type in the crates' non-test code."""
    found = collections.defaultdict(list)
    aliases = []
    for root in roots:
        for path, _ in crate_files(root):
            text = code_of(path)
            for m in DEFINITION.finditer(text):
                found[m.group(2)].append((path, line_of(text, m.start()), m.group(1)))
            for use in re.finditer(r"\buse\s+([^;]+);", text):
                for a in ALIAS.finditer(use.group(1)):
                    aliases.append((path, line_of(text, use.start()), a.group(1), a.group(2)))
    return found, aliases


def problems(roots, roles, known, known_aliases, strict):
    """Lines to print for each offending name and alias, and the stale allow-list entries."""
    found, aliases = definitions(roots)
    bad, stale = [], []
    twice = {n: defs for n, defs in found.items() if len(defs) > 1}
    for name, defs in sorted(twice.items()):
        if name in roles:
            continue
        files = {p for p, _, _ in defs}
        allowed = known.get(name)
        if not strict and allowed is not None and allowed <= files:
            continue
        where = ", ".join(f"{p}:{n} ({k})" for p, n, k in defs)
        bad.append(f"{name} is defined {len(defs)} times: {where}")
    for name, allowed in sorted(known.items()):
        if name not in twice or not allowed <= {p for p, _, _ in twice[name]}:
            stale.append(f"stale KNOWN entry, delete it: {name}")
    seen_aliases = set()
    for path, line, name, alias in aliases:
        if name not in found or len(found[name]) < 2:
            continue
        key = f"{path}: {name} as {alias}"
        seen_aliases.add(key)
        if not strict and key in known_aliases:
            continue
        bad.append(f"{path}:{line}: `{name} as {alias}`: {name} is defined {len(found[name])} times; name the type for what it is")
    for key in sorted(known_aliases - seen_aliases):
        stale.append(f"stale KNOWN_ALIASES entry, delete it: {key}")
    return bad, stale


def self_test():
    import tempfile

    files = {
        "lib.rs": "pub mod a;\npub mod b;\n#[cfg(test)]\nmod t;\n",
        "a.rs": "pub struct Thing;\npub enum Error {}\npub(crate) struct Inner;\n"
                "// pub struct InComment;\n",
        "b.rs": "pub trait Thing {}\npub struct Error;\nstruct Inner;\nuse crate::a::Error as AError;\n"
                "#[cfg(test)]\nmod tests { pub struct OnlyInTests; }\n",
        "t.rs": "pub struct OnlyInTests;\n",
    }
    failed = 0
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        cases = [
            # Thing twice; Error is a role name but aliased.
            ({"Error": ""}, {}, set(), False, ["Thing", "Error as AError"]),
            # Known debts pass unless --strict.
            ({"Error": ""}, {"Thing": {os.path.join(root, "a.rs"), os.path.join(root, "b.rs")}},
             {os.path.join(root, "b.rs") + ": Error as AError"}, False, []),
            ({"Error": ""}, {"Thing": {os.path.join(root, "a.rs"), os.path.join(root, "b.rs")}},
             {os.path.join(root, "b.rs") + ": Error as AError"}, True, ["Thing", "Error as AError"]),
            # No role names: Error is a duplicate too.
            ({}, {}, set(), False, ["Error is", "Thing", "Error as AError"]),
        ]
        for k, (roles, known, known_aliases, strict, want) in enumerate(cases):
            bad, _ = problems([root], roles, known, known_aliases, strict)
            ok = len(bad) == len(want) and all(any(w in b for b in bad) for w in want)
            if not ok:
                failed += 1
                print(f"self-test case {k}: found {bad}, expected {want}")
    print(f"self-test: {4 - failed} passed, {failed} failed")
    return 1 if failed else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    strict = "--strict" in argv[1:]
    here = os.path.dirname(os.path.abspath(__file__))
    os.chdir(os.path.dirname(here))
    roots = workspace_roots()
    bad, stale = problems(roots, ROLE_NAMES, KNOWN, KNOWN_ALIASES, strict)
    for line in bad + ([] if strict else stale):
        print(line)
    print(f"{', '.join(roots)}: public type names checked")
    if bad:
        print(f"{len(bad)} name(s) for more than one concept: rename one type for what it is")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
