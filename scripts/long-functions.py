#!/usr/bin/env python3
"""The longest Rust functions under a folder (default: both crates' src/, crates/core/src and src), from the `fn` line to the closing brace
(string and char literals and // comments ignored), and how many exceed a limit (default 150 lines;
exit 1 if any does). Usage: scripts/long-functions.py [DIR [LIMIT]]."""
import os, re, sys
here = os.path.join(os.path.dirname(__file__), "..")
roots = [sys.argv[1]] if len(sys.argv) > 1 else [os.path.join(here, "crates", "core", "src"), os.path.join(here, "src")]
limit = int(sys.argv[2]) if len(sys.argv) > 2 else 150
out = []
fn_re = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?(extern\s+\"[^\"]*\"\s+)?fn\s+(\w+)")
for root, (dp, _, fns) in ((r, w) for r in roots for w in os.walk(r)):
    for f in fns:
        if not f.endswith(".rs"):
            continue
        p = os.path.join(dp, f)
        lines = open(p).read().split("\n")
        for i, l in enumerate(lines):
            m = fn_re.match(l)
            if not m:
                continue
            depth, started = 0, False
            for j in range(i, len(lines)):
                s = re.sub(r'"(\\.|[^"\\])*"', '""', lines[j])
                s = re.sub(r"'(\\.|[^'\\])'", "''", s)
                s = s.split("//")[0]
                for c in s:
                    if c == "{":
                        depth += 1; started = True
                    elif c == "}":
                        depth -= 1
                if not started and s.rstrip().endswith(";"):
                    break
                if started and depth == 0:
                    out.append((j - i + 1, f"{os.path.relpath(p, root)}:{i+1}", m.group(7)))
                    break
out.sort(reverse=True)
for n, where, name in out[:15]:
    print(f"{n:5} {where} {name}")
print(f"functions over {limit} lines: {sum(1 for o in out if o[0] > limit)}")
sys.exit(1 if any(o[0] > limit for o in out) else 0)
