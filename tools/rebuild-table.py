#!/usr/bin/env python3
"""How many objects a touch of a header rebuilds: for each of the project's most-included
headers, the .cc files that include it directly or through other project headers (what make or
ninja recompiles after the touch), read from the sources' #include lines.

  tools/rebuild-table.py [--rev REV] [--top N] [--headers H1,H2,...]

--rev reads the tree of a git revision instead of the working tree (the "before" of a change);
--headers names the headers to list (default: the N most-included of the tree read).
Prints a Markdown table: header, objects rebuilt, and the share of all objects.
"""
import argparse
import os
import re
import subprocess
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
SOURCE_DIRS = ("base", "src", "render", "encode", "dataset", "run", "inspect", "serve", "bench",
               "cli", "tests", "fuzz")


def tree(root, rev):
    """{path: text} of the .cc and .h files under SOURCE_DIRS."""
    files = {}
    if rev:
        names = subprocess.run(["git", "-C", root, "ls-tree", "-r", "--name-only", rev],
                               capture_output=True, text=True, check=True).stdout.split()
        for name in names:
            if name.split("/")[0] in SOURCE_DIRS and name.endswith((".cc", ".h")):
                files[name] = subprocess.run(["git", "-C", root, "show", f"{rev}:{name}"],
                                             capture_output=True, text=True,
                                             errors="replace").stdout
    else:
        for top in SOURCE_DIRS:
            for dirpath, _, filenames in os.walk(os.path.join(root, top)):
                for f in filenames:
                    if f.endswith((".cc", ".h")):
                        path = os.path.relpath(os.path.join(dirpath, f), root)
                        with open(os.path.join(root, path), errors="replace") as text:
                            files[path] = text.read()
    return files


def closure(files):
    """{object source: set of project headers it includes, transitively}."""
    direct = {}
    for path, text in files.items():
        found = set()
        for inc in INCLUDE.findall(text):
            for candidate in (inc, os.path.normpath(os.path.join(os.path.dirname(path), inc))):
                if candidate in files:
                    found.add(candidate)
                    break
        direct[path] = found
    memo = {}

    def reach(path, stack=()):
        if path in memo:
            return memo[path]
        out = set()
        for h in direct.get(path, ()):
            if h in stack:
                continue
            out.add(h)
            out |= reach(h, stack + (path,))
        memo[path] = out
        return out

    return {p: reach(p) for p in files if p.endswith(".cc")}


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rev", default="")
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("--headers", default="")
    args = parser.parse_args(argv)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    objects = closure(tree(root, args.rev))
    counts = {}
    for headers in objects.values():
        for h in headers:
            counts[h] = counts.get(h, 0) + 1
    if args.headers:
        chosen = args.headers.split(",")
    else:
        chosen = sorted(counts, key=lambda h: (-counts[h], h))[:args.top]
    print(f"| header | objects rebuilt (of {len(objects)}) |")
    print("|---|---:|")
    for h in chosen:
        print(f"| `{h}` | {counts.get(h, 0)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
