#!/usr/bin/env python3
"""Lists Rust functions longer than a limit (default 80 lines), outside tests.

Usage: scripts/long_functions.py [LIMIT] [DIR ...]   (default DIR: crates, benches, examples)

A function counts from its `fn` line to its closing brace. Skipped: files named tests.rs or under a
tests/ folder, and `#[cfg(test)]` modules. A function whose doc comment or body says why it is long
(a comment containing "long:") is listed with that reason instead of as a finding. Exit status 1 when
an unexplained long function remains.
"""
import os
import re
import sys

FN = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?(extern\s+\"[^\"]*\"\s+)?fn\s+(\w+)")


def strip(line):
    """The line without string/char literals and // comments (good enough for brace counting)."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "''", line)
    return line.split("//", 1)[0]


def functions(path):
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    i, skip_depth, depth = 0, None, 0
    while i < len(lines):
        line = lines[i]
        if skip_depth is None and line.strip().startswith("#[cfg(test)]"):
            # Skip the next item (a test module) entirely.
            j = i + 1
            d, started = 0, False
            while j < len(lines):
                s = strip(lines[j])
                d += s.count("{") - s.count("}")
                started = started or "{" in s
                if (started and d <= 0) or (not started and s.rstrip().endswith(";")):
                    break
                j += 1
            i = j + 1
            continue
        m = FN.match(line)
        if m:
            # Find the body's end by braces (a declaration without a body ends with ';').
            d, started, j = 0, False, i
            while j < len(lines):
                s = strip(lines[j])
                if not started and s.rstrip().endswith(";") and "{" not in s:
                    break
                d += s.count("{") - s.count("}")
                started = started or "{" in s
                if started and d <= 0:
                    break
                j += 1
            if started:
                # Doc comments, comments and attributes just above.
                k = i - 1
                while k >= 0 and (lines[k].strip().startswith("//") or lines[k].strip().startswith("#[")):
                    k -= 1
                text = "\n".join(lines[k + 1 : j + 1])
                why = re.search(r"long:\s*(.*)", text)
                yield m.group(7), i + 1, j - i + 1, why.group(1).strip() if why else None
        i += 1


def main():
    args = sys.argv[1:]
    limit = int(args.pop(0)) if args and args[0].isdigit() else 80
    roots = args or ["crates", "benches", "examples"]
    found = 0
    for root in roots:
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = sorted(d for d in dirnames if d not in ("tests", "target") and not d.startswith("."))
            for name in sorted(filenames):
                if not name.endswith(".rs") or name == "tests.rs" or name.endswith("_tests.rs"):
                    continue
                path = os.path.join(dirpath, name)
                for fname, line, n, why in functions(path):
                    if n > limit:
                        if why:
                            print(f"{path}:{line}: {fname} {n} lines (long: {why})")
                        else:
                            print(f"{path}:{line}: {fname} {n} lines")
                            found += 1
    print(f"{found} unexplained function(s) over {limit} lines")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
