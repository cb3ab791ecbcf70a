"""Files and functions of the C++ core over the size limits (docs/design.md, "Size of files and functions").

    /usr/bin/python3 tests/tools/code_size.py [--files 600] [--functions 100] [folders ...]

Lists every .cpp/.hpp over the file limit (lines) and every function over the function limit (lines from its
signature to its closing brace, as universal-ctags finds them), longest first. Exit status 0: it reports, it does not
judge (a limit is a guide, see the design notes).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORE = ("framework", "kernels", "units")


def files_over(folders, limit):
    out = []
    for folder in folders:
        for base, _, names in os.walk(os.path.join(ROOT, folder)):
            for name in names:
                if name.endswith((".cpp", ".hpp")):
                    path = os.path.join(base, name)
                    with open(path, encoding="utf-8") as f:
                        n = sum(1 for _ in f)
                    if n > limit:
                        out.append((n, os.path.relpath(path, ROOT)))
    return sorted(out, reverse=True)


def functions_over(folders, limit):
    cmd = ["ctags", "--output-format=json", "--fields=+ne", "--kinds-C++=f", "--languages=C++",
           "--map-C++=+.hpp", "-R", "-f", "-"] + [os.path.join(ROOT, f) for f in folders]
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    out = []
    for line in text.splitlines():
        tag = json.loads(line)
        if "end" in tag and tag.get("kind") == "function":
            n = tag["end"] - tag["line"] + 1
            if n > limit:
                scope = tag.get("scope", "")
                name = re.sub(r"__anon[0-9a-f]+::", "", f"{scope}::{tag['name']}" if scope else tag["name"])
                out.append((n, f"{os.path.relpath(tag['path'], ROOT)}:{tag['line']}", name))
    return sorted(out, reverse=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--files", type=int, default=600)
    ap.add_argument("--functions", type=int, default=100)
    ap.add_argument("folders", nargs="*", default=list(CORE))
    a = ap.parse_args()
    files = files_over(a.folders, a.files)
    funcs = functions_over(a.folders, a.functions)
    print(f"files over {a.files} lines: {len(files)}")
    for n, p in files:
        print(f"  {n:5d}  {p}")
    print(f"functions over {a.functions} lines: {len(funcs)}")
    for n, where, name in funcs:
        print(f"  {n:5d}  {name}  ({where})")


if __name__ == "__main__":
    main()
