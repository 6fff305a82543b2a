#!/usr/bin/env python3
"""No library message names a command-line flag: a string literal in the non-test code of
`src/` outside the command line (`src/cli/`, `src/main.rs`) holds no `--flag`. The library
is called by the commands and by the experiment, each with its own options; a message
naming one command's flag misleads every other caller. The library names what is wrong
(the option, the file, the value); the command that set it from a flag says which flag.

Usage: python3 .ci/flag_messages.py [--strict]   (--strict: the KNOWN list counts as offenders)
       python3 .ci/flag_messages.py --self-test
Exits 1 listing every literal that names a flag, with its file and line.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rust_source import crate_files, remove_test_modules, strip_comments_and_strings  # noqa: E402

FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")

# Literals naming a flag when this check was added, as "FILE: FLAG" (every literal of
# FILE naming FLAG). Each is a debt: move the flag's name to the command (the library's
# error says which option, the command maps it to its flag), then delete the entry (the
# script says when one has become stale).
KNOWN = set()

# Literals that are, whole, the name of a readings format by the command that writes it:
# values of validation.json's inputs and of the report that a reader matches, not messages
# a user acts on.
FORMAT_NAMES = {
    "metamer spot --json",
    "metamer render spots --json",
}


# Files whose literals are documents another program reads, not library messages: the
# README and script `metamer export` writes beside a scene name the commands a reader runs
# (metamer's and the script's own), as a document does.
DOCUMENTS = {
    "src/export/readme.rs",
    "src/export/blender.rs",
}


def literals(text):
    """(line, content) of every string literal outside comments."""
    out = []
    i, n, line = 0, len(text), 1
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            line += text.count("\n", i, j)
            i = j
        elif c in "rb" and re.match(r'(b?r#*"|b")', text[i:i + 10]) and not (
            i and (text[i - 1].isalnum() or text[i - 1] == "_")
        ):
            m = re.match(r'b?r(#*)"', text[i:])
            if m:
                close = '"' + m.group(1)
                start = i + len(m.group(0))
                j = text.find(close, start)
                j = n if j < 0 else j
                out.append((line, text[start:j]))
                line += text.count("\n", i, j)
                i = j + len(close)
            else:
                i += 1  # b"...": the quote is read next
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append((line, text[i + 1:j]))
            line += text.count("\n", i, j)
            i = j + 1
        elif c == "'":
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", text[i:])
            i += len(m.group(0)) if m else 1
        else:
            if c == "\n":
                line += 1
            i += 1
    return out


def test_lines(text):
    """Lines inside inline `#[cfg(test)] mod` bodies."""
    stripped = strip_comments_and_strings(text)
    kept = remove_test_modules(stripped)
    return {
        k + 1
        for k, (a, b) in enumerate(zip(stripped.split("\n"), kept.split("\n")))
        if a != b
    }


def offenders(root):
    """(file, line, flag) of every flag named in a literal of the library's non-test code."""
    out = []
    cli = os.path.join(root, "cli") + os.sep
    for path, _ in crate_files(root):
        if path.startswith(cli) or os.path.basename(path) == "main.rs":
            continue
        if os.path.relpath(path, os.path.dirname(root) or ".") in DOCUMENTS:
            continue
        text = open(path, encoding="utf-8").read()
        tests = test_lines(text)
        for line, content in literals(text):
            if line in tests or content in FORMAT_NAMES:
                continue
            for m in FLAG.finditer(content):
                out.append((path, line, m.group(0)))
    return out


def run(root, known, strict):
    bad, seen = [], set()
    for path, line, flag in offenders(root):
        key = f"{path}: {flag}"
        if key in known:
            seen.add(key)
            if not strict:
                continue
        bad.append(f"{path}:{line}: a library message names the flag {flag}")
    stale = [f"stale KNOWN entry, delete it: {k}" for k in sorted(known - seen)]
    return bad, stale


def self_test():
    import tempfile

    files = {
        "lib.rs": "mod a;\nmod cli;\n#[cfg(test)]\nmod tests;\n",
        "cli/mod.rs": 'const C: &str = "--force";\n',
        "a.rs": (
            'pub fn f() -> String {\n    format!("use --force to replace {}", 1)\n}\n'
            '// "--in-a-comment"\n'
            'pub const OK: &str = "a -- b, x--y, ----";\n'
            'pub const RAW: &str = r#"see\n --white"#;\n'
            'pub const NAME: &str = "metamer spot --json";\n'
            '#[cfg(test)]\nmod t { const T: &str = "--test-only"; }\n'
            'pub const MSG: &str = "metamer spot --json is bad";\n'
        ),
        "tests.rs": 'const T: &str = "--force";\n',
    }
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        found = [(os.path.relpath(p, root), n, flag) for p, n, flag in offenders(root)]
        known_bad, _ = run(root, {os.path.join(root, "a.rs") + ": --force"}, False)
    want = [("a.rs", 2, "--force"), ("a.rs", 6, "--white"), ("a.rs", 11, "--json")]
    failed = 0
    if sorted(found) != want:
        failed += 1
        print(f"self-test: found {found}, expected {want}")
    if len(known_bad) != 2 or "--white" not in known_bad[0]:
        failed += 1
        print(f"self-test: with a known entry: {known_bad}")
    print(f"self-test: {2 - failed} passed, {failed} failed")
    return 1 if failed else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    strict = "--strict" in argv[1:]
    here = os.path.dirname(os.path.abspath(__file__))
    os.chdir(os.path.dirname(here))
    bad, stale = run("src", KNOWN, strict)
    for line in bad + ([] if strict else stale):
        print(line)
    print("src (without src/cli/): string literals checked for command-line flags")
    if bad:
        print(f"{len(bad)} literal(s) naming a flag: say what is wrong, and let the command name its flag")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
