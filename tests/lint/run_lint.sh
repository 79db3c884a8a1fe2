#!/usr/bin/env bash
# Static analysis as tests.
#   run_lint.sh cppcheck <source-dir>          firmware/ and hal/ (the code that runs on the drive)
#   run_lint.sh clang-tidy <source-dir> <build-dir-with-compile_commands.json>
#                                              firmware/ and hal/, the top-level .clang-tidy
#   run_lint.sh clang-tidy-sim <source-dir> <build-dir>
#                                              sim/ (C++17), sim/.clang-tidy
#   run_lint.sh ruff <source-dir> <ruff>       every Python file, .ruff.toml
# Exits non-zero on any finding. Suppressions live next to the code they
# concern (cppcheck-suppress / NOLINT with a reason), never here.
set -euo pipefail
tool=$1; src=$2
cd "$src"
mapfile -t C_FILES < <(find firmware hal -name '*.c' | sort)
mapfile -t CXX_FILES < <(find firmware hal -name '*.cpp' | sort)
case "$tool" in
  cppcheck)
    # --library=posix is not needed: firmware is freestanding C11.
    # missingIncludeSystem: system headers (stdint.h...) are not parsed on purpose.
    cppcheck --quiet --error-exitcode=1 --inline-suppr \
      --enable=warning,style,performance,portability \
      --std=c11 --language=c \
      --suppress=missingIncludeSystem \
      --suppress=unusedFunction \
      -I firmware/kernels -I hal/include \
      "${C_FILES[@]}"
    if ((${#CXX_FILES[@]})); then
      cppcheck --quiet --error-exitcode=1 --inline-suppr \
        --enable=warning,style,performance,portability \
        --std=c++17 --language=c++ \
        --suppress=missingIncludeSystem \
        --suppress=unusedFunction \
        -I firmware/kernels -I hal/include -I sim/include \
        "${CXX_FILES[@]}"
    fi
    echo "cppcheck: ${#C_FILES[@]} C and ${#CXX_FILES[@]} C++ files, no findings"
    ;;
  clang-tidy)
    build=$3
    # GCC-only warning flags in compile_commands.json are unknown to clang.
    rc=0
    out=$(clang-tidy --quiet -p "$build" --extra-arg=-Wno-unknown-warning-option \
      "${C_FILES[@]}" "${CXX_FILES[@]}" 2>&1) || rc=$?
    printf '%s\n' "$out" | grep -v 'warnings\? generated' || true
    if [ "$rc" -ne 0 ]; then
      echo "clang-tidy: findings above (exit $rc)" >&2
      exit "$rc"
    fi
    echo "clang-tidy: $((${#C_FILES[@]} + ${#CXX_FILES[@]})) files, no findings"
    ;;
  clang-tidy-sim)
    build=$3
    # Every translation unit of sim/ (headers under sim/ through them, see
    # HeaderFilterRegex); two at a time, as the machine has two cores.
    mapfile -t SIM_FILES < <(find sim -name '*.cpp' | sort)
    if ((${#SIM_FILES[@]} == 0)); then
      echo "clang-tidy-sim: no files under sim/ (wrong source directory?)" >&2
      exit 2
    fi
    for f in "${SIM_FILES[@]}"; do
      if ! grep -q "\"file\": \"[^\"]*/$f\"" "$build/compile_commands.json"; then
        echo "clang-tidy-sim: $f is not in $build/compile_commands.json (not built?)" >&2
        exit 2
      fi
    done
    rc=0
    out=$(printf '%s\0' "${SIM_FILES[@]}" |
      xargs -0 -P "${MC_LINT_JOBS:-2}" -n 4 clang-tidy --quiet -p "$build" \
        --extra-arg=-Wno-unknown-warning-option 2>&1) || rc=$?
    printf '%s\n' "$out" | grep -v 'warnings\? generated\|^Suppressed \|^Use -header-filter' || true
    if [ "$rc" -ne 0 ]; then
      echo "clang-tidy-sim: findings above (exit $rc)" >&2
      exit 1
    fi
    echo "clang-tidy-sim: ${#SIM_FILES[@]} files (and the sim/ headers they include), no findings"
    ;;
  ruff)
    ruff=$3
    # The configuration must be the one in force: a file that breaks a
    # selected rule (F401 unused import, B006 mutable default) is refused
    # when fed through stdin under a tools/ name.
    probe=$'import os\n\n\ndef f(x=[]):\n    return x\n'
    if probe_out=$(printf '%s' "$probe" | "$ruff" check --no-cache --output-format concise \
        --stdin-filename tools/lint_probe.py - 2>&1); then
      echo "ruff: the probe with an unused import and a mutable default passed: config not applied" >&2
      exit 1
    fi
    for code in F401 B006; do
      if ! grep -q "$code" <<<"$probe_out"; then
        echo "ruff: the probe did not raise $code: $probe_out" >&2
        exit 1
      fi
    done
    n=$("$ruff" check --no-cache --show-files . | grep -c '\.py$' || true)
    if [ "$n" -lt 10 ]; then
      echo "ruff: only $n Python files found (wrong source directory?)" >&2
      exit 1
    fi
    "$ruff" check --no-cache --output-format concise .
    echo "ruff: $n Python files, no findings"
    ;;
  *) echo "unknown tool $tool" >&2; exit 2 ;;
esac
