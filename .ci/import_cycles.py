#!/usr/bin/env python3
"""File-level import cycles in the workspace's Rust sources.

Each .rs file under a crate's src/ is a node; a `use` or path expression that names an item
of another file (through `crate::`, `super::`, `self::` or a child module) is an edge. A
strongly connected component with more than one file is a cycle: the files import each
other and cannot be read, tested or moved one at a time. `mod` declarations are not edges
(a parent owning a child module is the tree, not a dependency), and neither is a file's own
`#[cfg(test)] mod tests` (tests of a file may use what the file's users provide). A `pub use`
is a module's public face, no edge unless the file uses the name itself; a path through it
is followed to the file that defines the item.

Usage: python3 .ci/import_cycles.py [CRATE_SRC ...]   (default: every workspace member's src/)
       python3 .ci/import_cycles.py --self-test         (checks the script on made-up crates)
Exits 1 with a list of the cycles if there is any beyond the ALLOWED edges.
"""

import os
import re
import sys

# Import edges known and owned by someone else, as unordered pairs of paths from the
# repository root; both directions between the two files are ignored. Each entry is a debt:
# delete it once the cycle is gone (the script says when an entry has become stale).
ALLOWED: set = set()



def workspace_roots():
    """The src/ folder of every member of the workspace in Cargo.toml, root package first."""
    text = open("Cargo.toml", encoding="utf-8").read()
    m = re.search(r"^\s*members\s*=\s*\[(.*?)\]", text, re.S | re.M)
    members = re.findall(r'"([^"]+)"', m.group(1)) if m else ["."]
    roots = [os.path.normpath(os.path.join(member, "src")) for member in members]
    return [r for r in roots if os.path.isdir(r)]


def strip_comments_and_strings(text):
    """Source with comments, string and char literals blanked (line breaks kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and not (
            i and (text[i - 1].isalnum() or text[i - 1] == "_")
        ):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j + 1
        elif c == "'":
            # A char literal ('a', '\n', '\u{..}') or a lifetime ('a): only blank literals.
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", text[i:])
            if m:
                out.append("' '")
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def remove_test_modules(text):
    """Drops `#[cfg(test)] mod NAME { ... }` bodies (text already without comments)."""
    out, pos = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{", text):
        if m.start() < pos:
            continue
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        out.append(text[pos:m.start()])
        out.append("\n" * text.count("\n", m.start(), j))
        pos = j
    out.append(text[pos:])
    return "".join(out)


class Crate:
    def __init__(self, root):
        self.root = os.path.normpath(root)
        self.files = {}  # module path tuple -> file
        for entry in ("lib.rs", "main.rs"):
            path = os.path.join(self.root, entry)
            if os.path.exists(path):
                self.add(path, ())

    def add(self, path, module):
        if module in self.files:
            return
        self.files[module] = path
        text = strip_comments_and_strings(open(path, encoding="utf-8").read())
        text = remove_test_modules(text)
        base = os.path.dirname(path)
        stem = os.path.splitext(os.path.basename(path))[0]
        if stem not in ("lib", "main", "mod"):
            base = os.path.join(base, stem)
        for m in re.finditer(r"\bmod\s+(\w+)\s*;", text):
            name = m.group(1)
            for candidate in (os.path.join(base, name + ".rs"), os.path.join(base, name, "mod.rs")):
                if os.path.exists(candidate):
                    self.add(candidate, module + (name,))
                    break

    def file_of(self, module):
        """The file defining the deepest existing prefix of a module path."""
        while module not in self.files:
            module = module[:-1]
        return self.files[module]


def use_trees(text):
    """Every `use` item as (is_public, is_only_reexport, list of (path, name)), and every
    path outside `use` items as a private one."""
    items = []

    def expand(prefix, tree, out):
        tree = tree.strip()
        if not tree:
            return
        if tree.startswith("{"):
            depth, start = 0, 1
            for k, ch in enumerate(tree):
                if ch == "{":
                    depth += 1
                elif ch == "}":
                    depth -= 1
                    if depth == 0:
                        expand(prefix, tree[start:k], out)
                elif ch == "," and depth == 1:
                    expand(prefix, tree[start:k], out)
                    start = k + 1
            return
        m = re.match(r"([\w:]*?)::\{(.*)\}$", tree, re.S)
        if m:
            expand(prefix + [s for s in m.group(1).split("::") if s], "{" + m.group(2) + "}", out)
            return
        parts = re.split(r"\s+as\s+", tree)
        segments = prefix + [s for s in parts[0].strip().split("::") if s]
        if segments and segments[-1] == "self":
            segments = segments[:-1]
        alias = parts[1].strip() if len(parts) > 1 else (segments[-1] if segments else "")
        out.append((segments, alias))

    rest = []
    pos = 0
    for m in re.finditer(r"(\bpub(?:\s*\([^)]*\))?\s+)?\buse\s+([^;]+);", text):
        out = []
        expand([], m.group(2), out)
        items.append((bool(m.group(1)), out))
        rest.append(text[pos:m.start()])
        pos = m.end()
    rest.append(text[pos:])
    body = "".join(rest)
    # A re-exported name the file also uses itself is a dependency like any other.
    items = [
        (public, public and not any(alias and re.search(r"\b%s\b" % re.escape(alias), body)
                                    for _, alias in out), out)
        for public, out in items
    ]
    inline = []
    # Paths outside `use` items: `crate::…`, `super::…`, `self::…`, and `child::…` (which
    # `absolute` keeps only when `child` is a module of the file; others are other crates).
    for m in re.finditer(r"(?<![\w:])(\w+(?:::\w+)+)", body):
        segments = m.group(1).split("::")
        inline.append((segments, segments[-1]))
    items.append((False, False, inline))
    return items


def absolute(crate, module, segments):
    """A path as seen from `module`, made absolute; None for external crates and std."""
    head = segments[0]
    if head == "crate":
        return tuple(segments[1:])
    if head in ("super", "self"):
        target, rest = module, segments
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super":
                target = target[:-1]
            rest = rest[1:]
        return target + tuple(rest)
    if module + (head,) in crate.files:
        return module + tuple(segments)  # a child module named without self::
    return None


def edges(crate):
    """File -> files it uses. A public `use` (re-export) is a module's public face, like its
    `mod` items, so it is no edge; a path through it is followed to the file that defines
    the item, so the edge goes where the dependency really is."""
    module_of = {path: module for module, path in crate.files.items()}
    trees = {}
    reexports = {}  # module -> {public name: absolute path}
    for path, module in module_of.items():
        text = remove_test_modules(strip_comments_and_strings(open(path, encoding="utf-8").read()))
        trees[path] = use_trees(text)
        names = {}
        for public, _, out in trees[path]:
            if public:
                for segments, alias in out:
                    if segments and alias:
                        target = absolute(crate, module, segments)
                        if target is not None:
                            names[alias] = target
        reexports[module] = names

    def resolve(target, depth=0):
        prefix = target
        while prefix not in crate.files:
            prefix = prefix[:-1]
        rest = target[len(prefix):]
        if rest and depth < 20:
            via = reexports.get(prefix, {}).get(rest[0])
            if via is not None and via != target:
                return resolve(via + rest[1:], depth + 1)
        return crate.files[prefix]

    result = {path: set() for path in crate.files.values()}
    for path, module in module_of.items():
        for _, only_reexport, out in trees[path]:
            if only_reexport:
                continue
            for segments, _ in out:
                if not segments:
                    continue
                target = absolute(crate, module, segments)
                if target is None:
                    continue
                dest = resolve(target)
                if dest != path:
                    result[path].add(dest)
    return result


def cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(tuple(sorted(component)))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def self_test():
    """Checks the script on small crates whose cycles are known by construction."""
    import tempfile

    cases = {
        # a.rs and b.rs use each other's items: one cycle of two files.
        "mutual": ({
            "lib.rs": "mod a;\nmod b;\n",
            "a.rs": "use crate::b::B;\npub struct A;\n",
            "b.rs": "pub struct B;\npub fn f(_: super::a::A) {}\n",
        }, [("a.rs", "b.rs")]),
        # The parent re-exports its children and a child uses a sibling through the
        # re-export: no cycle, because the path is followed to the sibling's file.
        "facade": ({
            "lib.rs": "pub mod m;\n",
            "m/mod.rs": "mod x;\nmod y;\npub use x::X;\npub use y::{Y, Z as W};\n",
            "m/x.rs": "use super::{W, Y};\npub struct X(Y, W);\n",
            "m/y.rs": "pub struct Y;\npub struct Z;\n",
        }, []),
        # A parent defining an item its child uses while calling the child: a cycle, in
        # a `use` with nested braces; a test module's and a comment's paths do not count.
        "parent": ({
            "lib.rs": "mod p;\n",
            "p/mod.rs": "mod c;\npub struct E;\npub fn run() { c::go() }\n"
                        "// use self::q::Nothing;\n",
            "p/c.rs": "use crate::{p::{E}};\npub fn go() { let _ = E; }\n",
        }, [("p/c.rs", "p/mod.rs")]),
        "tests": ({
            "lib.rs": "mod a;\nmod b;\n",
            "a.rs": "use crate::b::B;\n#[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
            "b.rs": "pub struct B;\n#[cfg(test)]\nmod tests {\n    use crate::a;\n}\n",
        }, []),
    }
    failed = 0
    for name, (files, want) in cases.items():
        with tempfile.TemporaryDirectory() as root:
            for rel, text in files.items():
                os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
                with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                    f.write(text)
            found = [tuple(os.path.relpath(p, root) for p in c) for c in cycles(edges(Crate(root)))]
            if sorted(found) != sorted(want):
                failed += 1
                print(f"self-test {name}: found {found}, expected {want}")
    print(f"self-test: {len(cases) - failed} passed, {failed} failed")
    return 1 if failed else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    here = os.path.dirname(os.path.abspath(__file__))
    os.chdir(os.path.dirname(here))
    roots = argv[1:] or workspace_roots()
    bad = 0
    for root in roots:
        crate = Crate(root)
        graph = edges(crate)
        for pair in ALLOWED:
            a, b = sorted(pair)
            if a in graph and b in graph:
                if b in graph[a] and a in graph[b]:
                    print(f"allowed, to be removed: {a} <-> {b}")
                else:
                    print(f"stale allow-list entry, delete it: {a} <-> {b}")
                graph[a].discard(b)
                graph[b].discard(a)
        for component in cycles(graph):
            bad += 1
            print(f"import cycle in {root}:")
            for f in component:
                inside = sorted(t for t in graph[f] if t in component)
                print(f"  {f} -> {', '.join(inside)}")
        print(f"{root}: {len(crate.files)} files checked")
    if bad:
        print(f"{bad} import cycle(s); break each by moving the shared item to the file that owns it")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
