#!/usr/bin/env python3
"""No C or C++ file of the project calls assert() or includes <cassert> /
<assert.h>: the full suite runs on the optimised build (tools/test.sh), where
NDEBUG would turn such a check into nothing. A check belongs in a test's
EXPECT/ASSERT macro or in the code's own error path (a named error bit).

    check_no_assert.py <source-dir>     check the repository
    check_no_assert.py --self-test      prove the check can fail

Exit status 0 with a one-line summary, 1 with one line per finding.
"""
import os
import re
import sys
import tempfile

DIRS = ("firmware", "hal", "sim", "tests", "tools")
SKIP = ("build", ".venv", "_deps")  # build trees and the venv, not the project's sources
SOURCE_EXT = (".h", ".hpp", ".c", ".cc", ".cpp")
# assert( or static_assert( are told apart by the word boundary before it
CALL = re.compile(r"(?<![A-Za-z0-9_])assert\s*\(")
HEADER = re.compile(r"^\s*#\s*include\s*<(cassert|assert\.h)>")
COMMENT = re.compile(r"//.*$")


def sources(root):
    for d in DIRS:
        for dirpath, dirs, files in os.walk(os.path.join(root, d)):
            dirs[:] = [x for x in dirs if x not in SKIP]
            for f in sorted(files):
                if f.endswith(SOURCE_EXT):
                    yield os.path.join(dirpath, f)


def check(root):
    findings = []
    n = 0
    for path in sources(root):
        n += 1
        with open(path, encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, 1):
                code = COMMENT.sub("", line)
                if HEADER.match(code) or CALL.search(code):
                    findings.append(f"{os.path.relpath(path, root)}:{lineno}: {line.strip()}")
    return n, findings


def self_test():
    bad = {"a.c": "#include <assert.h>\n", "b.cpp": "void f(int x) { assert(x > 0); }\n",
           "c.hpp": "#include <cassert>\n"}
    good = {"d.cpp": "static_assert(sizeof(int) == 4, \"\");\n// assert(x) in a comment\n"}
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "tests"))
        for name, text in {**bad, **good}.items():
            with open(os.path.join(root, "tests", name), "w") as fh:
                fh.write(text)
        _n, findings = check(root)
    caught = {f.split(":")[0].split("/")[-1] for f in findings}
    if caught != set(bad):
        print(f"self-test FAILED: caught {sorted(caught)}, expected {sorted(bad)}")
        return 1
    print(f"self-test passed: {len(bad)} bad files caught, static_assert and comments allowed")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    n, findings = check(sys.argv[1])
    for f in findings:
        print(f)
    if findings:
        return 1
    print(f"no assert() in {n} C/C++ files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
