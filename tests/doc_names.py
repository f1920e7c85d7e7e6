#!/usr/bin/env python3
"""ctest doc_names: the docs name every source file, and every file they name exists.

Usage: doc_names.py SOURCE_DIR

Fails (printing the offending names) when
  * a source file under src/ (its name up to the first dot, e.g. `planet_renderer` for
    src/render/planet_renderer.cpp) appears as a word in no file under docs/ nor in README.md;
  * a doc (docs/*.md, README.md) names a path under src/, bench/, tests/, fuzz/, scripts/,
    docs/, calib/, markers/ or data/, or a layer's file (`render/sun.hpp`), that does not exist;
  * a source file (src/, bench/, tests/, fuzz/) cites a docs/*.md that does not exist.
Paths with wildcards (`tests/test_edit_*.cpp`, `fuzz/corpus/<target>/`) match when the pattern
matches something. Python's standard library only.
"""
import glob
import os
import re
import sys

SRC = sys.argv[1]
LAYERS = sorted(d for d in os.listdir(os.path.join(SRC, "src"))
                if os.path.isdir(os.path.join(SRC, "src", d)))
TOP = ["src", "bench", "tests", "fuzz", "scripts", "docs", "calib", "markers", "data", ".ci"]
SOURCE_EXTENSIONS = (".hpp", ".cpp", ".h", ".in", ".py", ".sh", ".cmake")


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def docs():
    paths = sorted(glob.glob(os.path.join(SRC, "docs", "*.md")))
    readme = os.path.join(SRC, "README.md")
    return paths + ([readme] if os.path.exists(readme) else [])


def exists(path):
    """A path relative to the source tree exists, or as a pattern matches something;
    `a.{hpp,cpp}` stands for both."""
    braces = re.search(r"\{([^}]*)\}", path)
    if braces:
        return all(exists(path[:braces.start()] + alt + path[braces.end():])
                   for alt in braces.group(1).split(","))
    pattern = re.sub(r"<[^>]*>", "*", path).rstrip("/")
    if any(c in pattern for c in "*?["):
        return bool(glob.glob(os.path.join(SRC, pattern)))
    return os.path.exists(os.path.join(SRC, pattern))


def unnamed_sources(doc_text):
    words = set(re.findall(r"[A-Za-z0-9_]+", doc_text))
    missing = []
    for root, _, files in os.walk(os.path.join(SRC, "src")):
        for name in files:
            stem = name.split(".", 1)[0]
            if stem not in words:
                missing.append(os.path.relpath(os.path.join(root, name), SRC))
    return sorted(missing)


# A path: a top folder or a layer, a slash, then path characters; ends before punctuation that
# closes a sentence or a code span.
PATH = re.compile(r"(?<![A-Za-z0-9_./-])((?:%s)/[A-Za-z0-9_.*<>{},/-]*[A-Za-z0-9_*>}/])" %
                  "|".join(re.escape(t) for t in TOP + LAYERS))


def gone_paths(path, text):
    gone = []
    for m in PATH.finditer(text):
        p = m.group(1)
        top = p.split("/", 1)[0]
        if top in LAYERS and top not in TOP:
            # `render/sun.hpp`: a layer's file (only names with an extension are files; `io/` alone
            # or `tracking/synth` in prose is not checked).
            if "." not in p.rsplit("/", 1)[-1]:
                continue
            p = "src/" + p
        if not exists(p):
            gone.append(f"{os.path.relpath(path, SRC)}: {m.group(1)}")
    return gone


def cited_docs_gone():
    gone = []
    for top in ["src", "bench", "tests", "fuzz", "scripts"]:
        for root, _, files in os.walk(os.path.join(SRC, top)):
            for name in files:
                if not name.endswith(SOURCE_EXTENSIONS):
                    continue
                path = os.path.join(root, name)
                for m in re.finditer(r"docs/[A-Za-z0-9_-]+\.md", read(path)):
                    if not exists(m.group(0)):
                        gone.append(f"{os.path.relpath(path, SRC)}: {m.group(0)}")
    return sorted(set(gone))


def main():
    doc_paths = docs()
    doc_text = "\n".join(read(p) for p in doc_paths)
    problems = []
    missing = unnamed_sources(doc_text)
    if missing:
        problems.append("source files named in no doc (docs/*.md, README.md):\n  " +
                        "\n  ".join(missing))
    gone = [g for p in doc_paths for g in gone_paths(p, read(p))]
    if gone:
        problems.append("paths the docs name that do not exist:\n  " + "\n  ".join(gone))
    cited = cited_docs_gone()
    if cited:
        problems.append("docs the sources cite that do not exist:\n  " + "\n  ".join(cited))
    if problems:
        print("FAIL: " + "\n".join(problems))
        sys.exit(1)
    print(f"{len(doc_paths)} docs name every source file under src/, and every path they name exists")


if __name__ == "__main__":
    main()
