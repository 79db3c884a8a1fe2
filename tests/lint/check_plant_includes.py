#!/usr/bin/env python3
"""The plant never uses the firmware's math: no file under the plant folders
(sim/src, sim/include) includes a firmware or HAL header.

    check_plant_includes.py <source-dir>     check the repository
    check_plant_includes.py --self-test      prove the check can fail

A plant file may include the standard library, Eigen, and files of the plant
itself (found next to the including file or under sim/include). It fails on
an include that
  - names a firmware or HAL path (firmware/..., hal/..., hal_host/...,
    kernels/..., app/...) or a firmware-style header (mc_*.h), or
  - resolves to a file under firmware/ or hal/ through any of the include
    directories the firmware's targets export, or
  - is a quoted include that does not resolve inside the plant (a quoted
    include is always a project file, so it must be the plant's own).
Exit status 0 with a one-line summary, 1 with one line per finding.
"""
import os
import re
import sys
import tempfile

PLANT_DIRS = ("sim/src", "sim/include")
PLANT_INCLUDE_ROOTS = ("sim/include",)
# Include directories of the firmware side (what its CMake targets export).
FIRMWARE_INCLUDE_ROOTS = ("firmware/kernels", "firmware/app", "firmware/app/drive", "firmware/app/ctrl",
                          "firmware/app/can", "firmware", "hal/include",
                          "hal/host/include", "hal/fake/include", "hal/stm32f405/include", "hal")
FORBIDDEN_PREFIX = re.compile(r"^(firmware|hal|hal_host|kernels|app|targets)/")
FIRMWARE_STYLE = re.compile(r"(^|/)mc_[A-Za-z0-9_]*\.h$")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
SOURCE_EXT = (".h", ".hpp", ".hh", ".c", ".cc", ".cpp", ".cxx", ".inc", ".ipp")


def plant_files(root):
    for d in PLANT_DIRS:
        for dirpath, _dirs, files in os.walk(os.path.join(root, d)):
            for f in sorted(files):
                if f.endswith(SOURCE_EXT):
                    yield os.path.join(dirpath, f)


def resolves(root, roots, name):
    return any(os.path.isfile(os.path.join(root, r, name)) for r in roots)


def check(root):
    findings = []
    n_files = n_includes = 0
    for path in plant_files(root):
        n_files += 1
        rel = os.path.relpath(path, root)
        with open(path, encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                n_includes += 1
                kind, name = m.group(1), m.group(2).strip()
                where = f"{rel}:{lineno}: #include {kind}{name}{'>' if kind == '<' else chr(34)}"
                if FORBIDDEN_PREFIX.match(name) or FIRMWARE_STYLE.search(name):
                    findings.append(f"{where}: a firmware/HAL header in the plant")
                    continue
                own = os.path.isfile(os.path.join(os.path.dirname(path), name)) or \
                    resolves(root, PLANT_INCLUDE_ROOTS, name)
                if not own and resolves(root, FIRMWARE_INCLUDE_ROOTS, name):
                    findings.append(f"{where}: resolves to a firmware/HAL file")
                elif kind == '"' and not own:
                    findings.append(f"{where}: a project header from outside the plant")
    return findings, n_files, n_includes


def main_check(root):
    findings, n_files, n_includes = check(root)
    for f in findings:
        print(f)
    if findings:
        print(f"plant includes: {len(findings)} finding(s): the plant (sim/src, sim/include) "
              "must not use firmware or HAL code", file=sys.stderr)
        return 1
    if n_files == 0:
        print("plant includes: no plant files found (wrong source directory?)", file=sys.stderr)
        return 1
    print(f"plant includes: {n_files} files, {n_includes} includes, no firmware or HAL header")
    return 0


def self_test():
    """Each bad file must be caught, the good tree must pass."""
    good = {
        "sim/include/mcsim/a.hpp": '#include <cmath>\n#include <Eigen/Core>\n#include "mcsim/b.hpp"\n',
        "sim/include/mcsim/b.hpp": "#pragma once\n",
        "sim/src/a.cpp": '#include "mcsim/a.hpp"\n#include "util.hpp"\n',
        "sim/src/util.hpp": "#pragma once\n",
        "firmware/kernels/math/mc_math.h": "",
        "firmware/app/drive/mc_drive.h": "",
        "hal/include/hal/hal.h": "",
        "firmware/kernels/pi/pi_detail.h": "",
    }
    bad_lines = [
        '#include "mc_drive.h"',                 # firmware header by name
        '#include "math/mc_math.h"',             # kernel header through its root
        "#include <mc_drive.h>",                 # angle brackets do not hide it
        '#include "hal/hal.h"',                  # HAL
        "#  include <hal/hal.h>",                # spaced directive
        '#include "firmware/kernels/math/mc_math.h"',
        '#include "pi/pi_detail.h"',             # not mc_*, found under firmware/kernels
        '#include "../../firmware/app/drive/mc_drive.h"',
        '#include "scenario.hpp"',               # a project header from outside the plant
    ]
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        for rel, text in good.items():
            os.makedirs(os.path.dirname(os.path.join(tmp, rel)), exist_ok=True)
            with open(os.path.join(tmp, rel), "w", encoding="utf-8") as fh:
                fh.write(text)
        findings, _, _ = check(tmp)
        if findings:
            print("self-test: the clean plant was refused:", *findings, sep="\n  ")
            failures += 1
        for plant_dir in ("sim/src", "sim/include/mcsim"):
            for line in bad_lines:
                bad = os.path.join(tmp, plant_dir, "bad.hpp")
                with open(bad, "w", encoding="utf-8") as fh:
                    fh.write("#pragma once\n" + line + "\n")
                findings, _, _ = check(tmp)
                os.remove(bad)
                if len(findings) != 1:
                    print(f"self-test: {plant_dir}: {line!r} gave {len(findings)} findings, want 1")
                    failures += 1
    if failures:
        print(f"self-test: {failures} case(s) wrong", file=sys.stderr)
        return 1
    print(f"self-test: clean tree passes, all {2 * len(bad_lines)} bad includes caught")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 2 and sys.argv[1] == "--self-test":
        sys.exit(self_test())
    if len(sys.argv) == 2:
        sys.exit(main_check(sys.argv[1]))
    print(__doc__, file=sys.stderr)
    sys.exit(2)
