#!/usr/bin/env python3
"""The dependency graph of the top-level modules of the core crate (crates/core/src) and the
application (src), as one graph (`crate::X` and `use crate::{X, ..}` outside
`#[cfg(test)]` blocks), printed one module a line, and any cycle between them (exit 1 on a cycle).
Also counts production imports of the CPU twins (`cpu::`, and a method's own `method::<m>::twin`;
production is every file but `cpu/` and the methods' `twin.rs`, outside `#[cfg(test)]`) and the
files outside each method's folder that name it (any case, comments included), where a citation of
its paper by its authors (`CITATIONS`: "Colom, Marques, Santos", "Colom et al.") names the paper,
not the method, and is not counted. A method's `twin.rs` is twin code: its imports are drawn as
`cpu`'s."""
import collections
import os
import re
import sys

here = os.path.join(os.path.dirname(__file__), "..")
core = os.path.join(here, "crates", "core", "src")
roots = [core, os.path.join(here, "src")]
tops = set()
for root in roots:
    for f in os.listdir(root):
        if f.endswith(".rs") and f not in ("lib.rs", "main.rs"):
            tops.add(f[:-3])
        elif os.path.isdir(os.path.join(root, f)):
            tops.add(f)


def files():
    """Every .rs file with its path relative to its crate's src."""
    for root in roots:
        for dp, _, fn in os.walk(root):
            for f in fn:
                if f.endswith(".rs"):
                    p = os.path.join(dp, f)
                    yield p, os.path.relpath(p, root)


edges = collections.defaultdict(set)
cpu_imports = []
for p, relpath in files():
    if True:
        rel = relpath.split(os.sep)
        top = rel[0][:-3] if rel[0].endswith(".rs") else rel[0]
        if top in ("lib", "main"):
            continue
        method_dir = rel[1] if top == "method" and len(rel) == 3 else None
        if method_dir and rel[2] == "twin.rs":
            top = "cpu"
            edges[top].add("method")
        src = re.split(r"#\[cfg\(test\)\]", open(p).read())[0]
        code = "\n".join(l for l in src.split("\n") if not l.strip().startswith("//"))
        for m in re.findall(r"crate::(\w+)", code):
            if m in tops and m != top:
                edges[top].add(m)
        for group in re.findall(r"use crate::\{([^}]*)\}", code):
            for n in re.findall(r"(\w+)", group):
                if n in tops and n != top:
                    edges[top].add(n)
        twin = re.search(r"method::\w+::(twin\b|\{[^}]*\btwin\b)", code)
        if method_dir:
            twin = twin or re.search(r"\btwin::|::twin\b|\{[^}]*\btwin\b", code)
        if top != "cpu" and (re.search(r"\bcpu::", code) or twin):
            cpu_imports.append(relpath)
for k in sorted(edges):
    print(f"{k} -> {', '.join(sorted(edges[k]))}")
index, low, stack, on, sccs, counter = {}, {}, [], set(), [], [0]


def visit(v):
    index[v] = low[v] = counter[0]
    counter[0] += 1
    stack.append(v)
    on.add(v)
    for w in edges[v]:
        if w not in index:
            visit(w)
            low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        scc = []
        while True:
            w = stack.pop()
            on.discard(w)
            scc.append(w)
            if w == v:
                break
        sccs.append(scc)


for v in sorted(tops):
    if v not in index:
        visit(v)
cycles = [s for s in sccs if len(s) > 1]
print(f"cycles: {len(cycles)} {cycles if cycles else ''}")
print(f"production imports of cpu:: or method::<m>::twin: {len(cpu_imports)} {cpu_imports if cpu_imports else ''}")
methods = os.path.join(core, "method")
# The citations of a method's paper by its authors, exactly as written (case-sensitive): they name
# the paper, not the method.
CITATIONS = {"colom": ["Colom, Marques, Santos", "Colom et al."]}
for m in sorted(d for d in os.listdir(methods) if os.path.isdir(os.path.join(methods, d))):
    named = []
    for p, relpath in files():
        if not relpath.startswith(f"method{os.sep}{m}{os.sep}"):
            text = open(p).read()
            for c in CITATIONS.get(m, []):
                text = text.replace(c, "")
            if m in text.lower():
                named.append(relpath)
    cited = " (paper citations by author not counted)" if m in CITATIONS else ""
    print(f"{m}: named in {len(named)} files outside method/{m}/{cited}: {', '.join(sorted(named))}")
sys.exit(1 if cycles or cpu_imports else 0)
