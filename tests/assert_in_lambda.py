#!/usr/bin/env python3
"""ctest assert_in_lambda: no GoogleTest ASSERT_* inside a lambda in tests/.

Usage: assert_in_lambda.py SOURCE_DIR

An ASSERT_* returns from the function it is in: inside a lambda it ends the lambda, not the test,
and a loop calling the lambda goes on failing (issue 44 found seven such checks, one called
200,000 times). Return a testing::AssertionResult (or record the first failure) from the lambda
and ASSERT on it in the test's body. Fails naming each file and line. A lambda's parameters are
matched without nested parentheses; Python's standard library only.
"""
import glob
import os
import re
import sys

SRC = sys.argv[1]
LAMBDA = re.compile(r"\]\s*\([^()]*\)\s*(?:mutable\s*)?(?:->\s*[\w:<>]+\s*)?\{")


def body_end(text, open_brace):
    depth = 0
    for j in range(open_brace, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(text)


found = []
files = sorted(glob.glob(os.path.join(SRC, "tests", "*.cpp")) +
               glob.glob(os.path.join(SRC, "tests", "*.hpp")))
for path in files:
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for m in LAMBDA.finditer(text):
        start = m.end() - 1
        if re.search(r"\bASSERT_", text[start:body_end(text, start)]):
            found.append(f"{os.path.relpath(path, SRC)}:{text.count(chr(10), 0, m.start()) + 1}")
if found:
    print("FAIL: ASSERT_* inside a lambda (it ends the lambda, not the test):\n  " +
          "\n  ".join(found))
    sys.exit(1)
print(f"no ASSERT_* inside a lambda in {len(files)} test files")
