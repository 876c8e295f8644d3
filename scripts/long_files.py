#!/usr/bin/env python3
"""Lists source files longer than a limit (default 500 lines): every .rs and .py file, tests included.

Usage: scripts/long_files.py [LIMIT] [DIR ...]   (default DIR: crates, benches, examples, scripts)

A file counts its lines as `wc -l` does. Skipped: target/ and hidden folders. Exit status 1 when a file over
the limit remains.
"""
import os
import sys

def main():
    args = sys.argv[1:]
    limit = int(args.pop(0)) if args and args[0].isdigit() else 500
    roots = args or ["crates", "benches", "examples", "scripts"]
    found = 0
    for root in roots:
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = sorted(d for d in dirnames if d != "target" and not d.startswith("."))
            for name in sorted(filenames):
                if not name.endswith((".rs", ".py")):
                    continue
                path = os.path.join(dirpath, name)
                with open(path, encoding="utf-8") as f:
                    n = f.read().count("\n")
                if n > limit:
                    print(f"{path}: {n} lines")
                    found += 1
    print(f"{found} file(s) over {limit} lines")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
