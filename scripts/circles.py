#!/usr/bin/env python3
"""Circles of files inside each crate and Python package (issue 36): files that import each
other in a loop, read from their own `use` / `import` lines.

    python3 scripts/circles.py [ROOT]     # prints each circle and the names that tie it;
                                          # exits 1 when there is one

Rust: a file's module path follows its place under `src/` (`src/a/b.rs` is `crate::a::b`,
`src/a/mod.rs` and `src/a.rs` are `crate::a`); `use crate::...`, `use super::...`, `use
self::...` and the same paths written inline in code point at the deepest module that exists,
and a name that a `lib.rs` / `mod.rs` re-exports (`pub use x::Name`) points at the file that
defines it. `mod x;` lines are not imports (a parent lists its children; it does not use them).
Python: `from . import x`, `from .x import y`, `from .. import z` inside a package.
"""

import re
import sys
from pathlib import Path

RUST_PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE_GROUP = re.compile(r"\buse\s+(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)*)::\{([^;]*)\}\s*;", re.S)
PUB_USE = re.compile(r"pub(?:\([^)]*\))?\s+use\s+(self::|crate::)?([A-Za-z_][\w:]*)::(\{[^;]*\}|[A-Za-z_]\w*)\s*;", re.S)


def strip_comments(text):
    """Code without comments and without test-only items (`#[cfg(test)]` modules, statements
    and functions: tests may reach anywhere in their crate)."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]", text):
        if m.start() < i:
            continue
        out.append(text[i:m.start()])
        j = m.end()
        brace, semi = text.find("{", j), text.find(";", j)
        if brace != -1 and (semi == -1 or brace < semi):
            depth, k = 0, brace
            while k < len(text):
                depth += {"{": 1, "}": -1}.get(text[k], 0)
                k += 1
                if depth == 0:
                    break
            i = k
        else:
            i = semi + 1 if semi != -1 else len(text)
    out.append(text[i:])
    return "".join(out)


def crate_modules(src):
    """Module path (tuple) -> file, for one crate's src/ (and its examples/benches skipped)."""
    mods = {}
    for f in src.rglob("*.rs"):
        rel = f.relative_to(src).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] in ("lib", "main") and len(parts) == 1:
            parts = []
        elif parts[-1] == "mod":
            parts = parts[:-1]
        if parts and parts[0] == "bin":
            continue
        mods.setdefault(tuple(parts), f)
    return mods


def reexports(mods, texts):
    """(module, name) -> module that defines it, from `pub use` lines of each module."""
    out = {}
    for m, f in mods.items():
        for prefix, path, names in PUB_USE.findall(texts[f]):
            target = tuple(m) + tuple(p for p in path.split("::") if p) if prefix != "crate::" \
                else tuple(p for p in path.split("::") if p)
            for n in re.findall(r"[A-Za-z_]\w*", names):
                if n != "self":
                    out[(m, n)] = target
    return out


def resolve(mods, rex, path):
    """The deepest existing module of `path`, following re-exports of its last name."""
    for cut in range(len(path), -1, -1):
        m = tuple(path[:cut])
        if m in mods:
            if cut < len(path):
                seen = set()
                key = (m, path[cut])
                while key in rex and key not in seen:
                    seen.add(key)
                    target = rex[key]
                    if target in mods:
                        m = target
                    key = (target, path[cut])
            return m
    return None


def rust_graph(src):
    mods = crate_modules(src)
    texts = {f: strip_comments(f.read_text(errors="replace")) for f in mods.values()}
    rex = reexports(mods, texts)
    edges = {}
    for m, f in mods.items():
        text = texts[f]
        # `use a::{b, c::d}` groups: each member a path of its own
        paths = []
        for head, base, group in USE_GROUP.findall(text):
            for member in re.split(r",(?![^{]*\})", group):
                member = member.strip().split(" as ")[0].strip()
                if member and member != "*":
                    paths.append((head, base + "::" + member.replace("{", "").replace("}", "")))
                elif member == "*":
                    paths.append((head, base))
        paths += [(h, p) for h, p in RUST_PATH.findall(text)]
        for head, rest in paths:
            parts = [p for p in rest.split("::") if p and p != "self"]
            if head == "crate":
                base = []
            elif head == "super":
                base = list(m[:-1])
                while parts and parts[0] == "super":
                    base = base[:-1]
                    parts = parts[1:]
            else:
                base = list(m)
            target = resolve(mods, rex, tuple(base + parts))
            if target is None or target == m:
                continue
            # a child reaching its own ancestors' modules through `super` is still an edge
            names = edges.setdefault((m, target), set())
            if parts:
                names.add(parts[-1])
    files = {m: f for m, f in mods.items()}
    return files, edges


def python_graph(pkg):
    files = {}
    for f in pkg.rglob("*.py"):
        rel = f.relative_to(pkg).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        files[tuple(parts)] = f
    edges = {}
    for m, f in files.items():
        here = list(m) if f.name == "__init__.py" else list(m[:-1])
        for dots, mod, names in re.findall(
            r"^\s*from\s+(\.+)([\w.]*)\s+import\s+([^\n(]+|\([^)]*\))", f.read_text(), re.M
        ):
            base = here[: len(here) - (len(dots) - 1)] if len(dots) > 1 else here
            mpath = base + [p for p in mod.split(".") if p]
            for n in re.findall(r"(\w+)(?:\s+as\s+\w+)?", names):
                cand = tuple(mpath + [n])
                target = cand if cand in files else tuple(mpath)
                if target in files and target != m:
                    edges.setdefault((m, target), set()).add(n)
    return files, edges


def circles(files, edges):
    """Strongly connected components of more than one file (Tarjan)."""
    graph = {m: [] for m in files}
    for a, b in edges:
        graph[a].append(b)
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in files:
        if v not in index:
            visit(v)
    return out


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    units = []
    for cargo in sorted(root.glob("**/Cargo.toml")):
        src = cargo.parent / "src"
        if src.is_dir() and "target" not in cargo.parts and ".git" not in cargo.parts:
            units.append((cargo.parent, rust_graph(src)))
    for pkg in [root / "blender_addon", root / "python" / "tessd",
                root / "freecad_plugin" / "freecad" / "tessd"]:
        if pkg.is_dir():
            units.append((pkg, python_graph(pkg)))
    found = 0
    for where, (files, edges) in units:
        for comp in circles(files, edges):
            found += 1
            names = [str(files[m].relative_to(root)) for m in comp]
            print(f"circle {found}: {len(comp)} files: {', '.join(names)}")
            for (a, b), ns in sorted(edges.items()):
                if a in comp and b in comp:
                    print(f"  {files[a].relative_to(root)} -> {files[b].relative_to(root)}: "
                          f"{', '.join(sorted(ns))}")
    print(f"{found} circle(s) in {len(units)} crates and packages")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
