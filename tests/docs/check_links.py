#!/usr/bin/env python3
"""Every relative link of README.md, CHANGELOG.md, docs/*.md and share/*/README.md points to a
file or folder that exists (and an #anchor, when given, to a heading of that Markdown file).

Usage: check_links.py SOURCE_DIR
"""
import glob
import os
import re
import sys


def anchors(path):
    """GitHub's anchors of a Markdown file's headings."""
    out, fenced = set(), False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            fenced = not fenced
        m = None if fenced else re.match(r"^#+\s+(.*?)\s*$", line)
        if m:
            a = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
            n = 1
            base = a
            while a in out:
                a = f"{base}-{n}"
                n += 1
            out.add(a)
    return out


def main():
    src = os.path.abspath(sys.argv[1])
    files = [os.path.join(src, "README.md"), os.path.join(src, "CHANGELOG.md")]
    files += sorted(glob.glob(os.path.join(src, "docs", "*.md")))
    files += sorted(glob.glob(os.path.join(src, "share", "*", "README.md")))
    bad, checked = [], 0
    for f in files:
        if not os.path.exists(f):
            bad.append(f"{os.path.relpath(f, src)}: missing")
            continue
        fenced = False
        for n, line in enumerate(open(f, encoding="utf-8"), 1):
            if line.startswith("```"):
                fenced = not fenced
            if fenced:
                continue
            for target in re.findall(r"\]\(([^)\s]+)\)", line):
                if re.match(r"^[a-z]+:", target):
                    continue  # http:, https:, mailto:
                checked += 1
                path, _, anchor = target.partition("#")
                dest = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
                where = f"{os.path.relpath(f, src)}:{n}: ({target})"
                if not os.path.exists(dest):
                    bad.append(f"{where} -> no such file {os.path.relpath(dest, src)}")
                elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                    bad.append(f"{where} -> no heading #{anchor} in {os.path.relpath(dest, src)}")
    for b in bad:
        print("broken link: " + b, file=sys.stderr)
    print(f"{checked} relative links in {len(files)} files, {len(bad)} broken")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
