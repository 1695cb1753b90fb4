#!/usr/bin/env python3
"""Print a crate's module graph (edges `a -> b`: a.rs names crate::b) and fail on a cycle.

Usage: scripts/module_dag.py crates/obsan-diagnose [crates/obsan-data ...]  (CI: crates/*)

An edge is any `crate::NAME` in a module's code (comments and `#[cfg(test)]` modules
excluded), NAME a module of the crate or a name lib.rs re-exports from one. Exit 1 when
a crate's graph has a cycle (docs/architecture.md states these graphs as invariants).

It also counts each crate's root exports: the names `pub use` brings into lib.rs and the
`pub` items (fn, struct, enum, trait, type, const, static) lib.rs defines at its top level.
Public modules are namespaces and are not counted, nor what they re-export. Exit 1 when a
root exports more than MAX_EXPORTS names (docs/architecture.md, "small public APIs").
"""
import pathlib
import re
import sys

MAX_EXPORTS = 40


def modules(src):
    mods = {p.stem: p for p in src.glob("*.rs") if p.stem not in ("lib", "main")}
    mods.update({p.parent.name: p for p in src.glob("*/mod.rs")})
    return mods


def code(path):
    out = []
    for line in path.read_text().splitlines():
        if line.strip().startswith("#[cfg(test)]"):
            break
        out.append(line.split("//")[0])
    return "\n".join(out)


def reexports(src, mods):
    owner = {}
    lib = code(src / "lib.rs")
    for m, body in re.findall(r"pub use (\w+)::(\{[^}]*\}|\w+)", lib):
        if m in mods:
            for name in re.findall(r"\w+", body):
                owner[name] = m
    return owner


def graph(crate):
    src = pathlib.Path(crate) / "src"
    mods = modules(src)
    owner = reexports(src, mods)
    edges = {}
    for m, path in mods.items():
        text = code(path)
        names = set(re.findall(r"crate::(\w+)", text))
        for group in re.findall(r"crate::\{([^}]*)\}", text):
            names.update(re.findall(r"^\s*(\w+)", g)[0] for g in group.split(",") if g.strip())
        targets = {n if n in mods else owner.get(n) for n in names}
        edges[m] = sorted(t for t in targets if t and t != m)
    return edges


def root_exports(crate):
    """The names lib.rs exports at its top level (not those inside `pub mod` blocks)."""
    text = (pathlib.Path(crate) / "src" / "lib.rs").read_text()
    lib = "\n".join(line.split("//")[0] for line in text.splitlines())
    lib = re.sub(r'"(?:\\.|[^"\\\n])*"', '""', lib)  # braces in strings do not nest
    names = []
    item = r"^pub (?:fn|struct|enum|trait|type|const|static) (\w+)"
    for m in re.finditer(item + r"|^pub use ([^;]*);", lib, re.M):
        if lib.count("{", 0, m.start()) != lib.count("}", 0, m.start()):
            continue  # inside a public module or an item's body
        if m.group(1):
            names.append(m.group(1))
            continue
        body = re.sub(r"\w+ as (\w+)", r"\1", m.group(2))
        inner = re.search(r"\{(.*)\}", body, re.S)
        parts = inner.group(1).split(",") if inner else [body]
        names += [s.strip().split("::")[-1] for s in parts if s.strip()]
    return names


def cycle(edges):
    state = {}
    stack = []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for t in edges.get(m, []):
            if state.get(t) == 1:
                return stack[stack.index(t):] + [t]
            if t not in state:
                c = visit(t)
                if c:
                    return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state:
            c = visit(m)
            if c:
                return c
    return None


def main():
    bad = False
    for crate in sys.argv[1:]:
        edges = graph(crate)
        print(f"{crate}:")
        for m in sorted(edges):
            print(f"  {m} -> {', '.join(edges[m]) or '(none)'}")
        c = cycle(edges)
        if c:
            print(f"  CYCLE: {' -> '.join(c)}")
            bad = True
        exports = root_exports(crate)
        print(f"  root exports: {len(exports)} (at most {MAX_EXPORTS})")
        if len(exports) > MAX_EXPORTS:
            print(f"  TOO MANY ROOT EXPORTS in {crate}/src/lib.rs: {len(exports)} > {MAX_EXPORTS};"
                  " put the less used behind a public module")
            bad = True
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
