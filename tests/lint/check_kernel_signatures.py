#!/usr/bin/env python3
"""One return convention for the kernels (firmware/kernels/README.md):
every kernel function named mc_<capability>_<format>_<verb> whose verb is
init, reset or step (and the step's variants: step_ff, step_lim, step_dq,
...) returns uint32_t, the error bits raised by that call; outputs go
through an out struct or p_ pointers. And f32 and q31 twins have the same
shape: where both mc_x_f32_<verb> and mc_x_q31_<verb> exist, they take the
same number of parameters, each of the same kind (value or pointer, const
or not); only the types differ (float and q31_t, the f32 and q31 structs).

    check_kernel_signatures.py <source-dir>    check firmware/kernels/*/*.h
    check_kernel_signatures.py --self-test     prove the check can fail
    check_kernel_signatures.py --list <dir>    print every signature found

Declarations and definitions in the headers are both read (prototypes and
static inline functions), with comments and preprocessor lines removed, so a
declaration split over several lines is seen whole. A function qualifies
when one of the '_'-separated words of its name after "mc_" is init, reset
or step. Its return type is the text before the name with the storage and
inline qualifiers removed (static, inline, extern, *_INLINE macros); it must
be exactly uint32_t.

Exit status 0 with a one-line summary, 1 with one line per finding (also
when no qualifying function is found at all: the check must not pass on an
empty or unparsed tree).
"""
import glob
import os
import re
import sys
import tempfile

VERBS = {"init", "reset", "step"}
QUALIFIERS = {"static", "inline", "extern", "__inline__", "__inline"}
INLINE_MACRO = re.compile(r"^[A-Z][A-Z0-9_]*INLINE$")
NAME = re.compile(r"\b(mc_[A-Za-z0-9_]+)\s*\(")
KEYWORDS = {"return", "else", "case", "do", "sizeof", "goto"}


def strip_code(text):
    """Comments, string literals and preprocessor lines replaced by blanks
    (newlines kept, so line numbers stay right)."""
    def blank(m):
        return re.sub(r"[^\n]", " ", m.group(0))
    text = re.sub(r"/\*.*?\*/", blank, text, flags=re.DOTALL)
    text = re.sub(r"//[^\n]*", blank, text)
    text = re.sub(r'"(?:\\.|[^"\\\n])*"', blank, text)
    # preprocessor lines, with their continuations
    text = re.sub(r"(?m)^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", blank, text)
    return text


def qualifies(name):
    words = name.split("_")[1:]
    return any(w in VERBS for w in words)


def signatures(path):
    """(line, name, return type, parameter text) of every function declared
    or defined in the header."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        code = strip_code(fh.read())
    found = []
    for m in NAME.finditer(code):
        name = m.group(1)
        # text of this statement before the name
        start = max(code.rfind(";", 0, m.start()), code.rfind("{", 0, m.start()),
                    code.rfind("}", 0, m.start()))
        before = code[start + 1:m.start()]
        if re.search(r"[=(),\[\]?:!&|+\-/%<>^~.]", before):
            continue  # a call inside an expression
        tokens = re.findall(r"[A-Za-z_][A-Za-z0-9_]*|\*", before)
        if not tokens or tokens[0] in KEYWORDS or tokens[-1] in KEYWORDS:
            continue  # a call as a statement, or after a keyword
        # parameter list up to the matching parenthesis
        depth, i = 0, m.end() - 1
        while i < len(code):
            if code[i] == "(":
                depth += 1
            elif code[i] == ")":
                depth -= 1
                if depth == 0:
                    break
            i += 1
        params = " ".join(code[m.end():i].split())
        ret = [t for t in tokens if t not in QUALIFIERS and not INLINE_MACRO.match(t)]
        line = code.count("\n", 0, m.start()) + 1
        found.append((line, name, " ".join(ret).replace(" *", "*"), params))
    return found


def param_kinds(params):
    """Per parameter: (const, number of '*'), the shape without the types."""
    if params.strip() in ("", "void"):
        return []
    kinds = []
    for p in params.split(","):
        words = re.findall(r"[A-Za-z_][A-Za-z0-9_]*|\*", p)
        kinds.append(("const" in words, words.count("*")))
    return kinds


def check(root):
    findings = []
    n = 0
    seen = {}
    headers = sorted(glob.glob(os.path.join(root, "firmware", "kernels", "*", "*.h")))
    for path in headers:
        rel = os.path.relpath(path, root)
        for line, name, ret, params in signatures(path):
            if not qualifies(name):
                continue
            n += 1
            seen[name] = (rel, line, params)
            if ret != "uint32_t":
                findings.append(f"{rel}:{line}: {name} returns '{ret}', not uint32_t "
                                "(init/reset/step return the error bits raised by the call; "
                                "outputs through an out struct or p_ pointers)")
    for name, (rel, line, params) in sorted(seen.items()):
        if "_f32_" not in name:
            continue
        twin = name.replace("_f32_", "_q31_")
        if twin not in seen:
            continue
        trel, tline, tparams = seen[twin]
        if param_kinds(params) != param_kinds(tparams):
            findings.append(f"{trel}:{tline}: {twin}({tparams}) is not the shape of its f32 twin "
                            f"{name}({params}) ({rel}:{line})")
    if n == 0:
        findings.append(f"{root}: no init/reset/step function found under firmware/kernels "
                        "(wrong directory, or the parser no longer sees the declarations)")
    return findings, len(headers), n


def main_check(root, quiet=False):
    findings, n_headers, n = check(root)
    if quiet:
        return 1 if findings else 0
    for f in findings:
        print(f)
    if findings:
        print(f"kernel signatures: {len(findings)} finding(s)", file=sys.stderr)
        return 1
    print(f"kernel signatures: {n} init/reset/step functions in {n_headers} headers, "
          "all return uint32_t, f32 and q31 twins of the same shape")
    return 0


def main_list(root):
    for path in sorted(glob.glob(os.path.join(root, "firmware", "kernels", "*", "*.h"))):
        for line, name, ret, params in signatures(path):
            print(f"{os.path.relpath(path, root)}:{line}: {ret} {name}({params})")
    return 0


BAD_HEADER = """\
#ifndef BAD_H
#define BAD_H
#include <stdint.h>
#define MC_BAD_INLINE static inline
/* a comment naming float mc_bad_f32_step(x) is not a declaration */
void mc_bad_f32_reset(mc_bad_f32_t *st);
float mc_bad_f32_step(mc_bad_f32_t *st, float x);
q31_t
mc_bad_q31_step_ff(mc_bad_q31_t *st,
                   q31_t x, q31_t ff);
static inline float mc_bad_f32_step_lim(mc_bad_f32_t *st, float x)
{
    return x;
}
MC_BAD_INLINE bool mc_bad_f32_init(mc_bad_f32_t *st);
int32_t mc_bad_q31_init(mc_bad_q31_t *st, const mc_bad_q31_cfg_t *cfg);
uint32_t mc_twin_f32_reset(mc_twin_f32_t *st, float z1, float z2);
uint32_t mc_twin_q31_reset(mc_twin_q31_t *st);
uint32_t mc_twin_f32_step(mc_twin_f32_t *st, const mc_twin_f32_in_t *in, float *p_out);
uint32_t mc_twin_q31_step(mc_twin_q31_t *st, mc_twin_q31_in_t *in, q31_t *p_out);
uint32_t mc_twin_f32_init(mc_twin_f32_t *st, const mc_twin_f32_cfg_t *cfg);
uint32_t mc_twin_q31_init(mc_twin_q31_t *st, const mc_twin_q31_cfg_t *cfg);
#endif
"""
BAD_EXPECTED = {"mc_bad_f32_reset", "mc_bad_f32_step", "mc_bad_q31_step_ff",
                "mc_bad_f32_step_lim", "mc_bad_f32_init", "mc_bad_q31_init"}
# mc_bad_*_init differ too (one parameter against two); mc_twin_*_init match
TWIN_EXPECTED = {"mc_twin_q31_reset", "mc_twin_q31_step", "mc_bad_q31_init"}

GOOD_HEADER = """\
#ifndef GOOD_H
#define GOOD_H
#include <stdint.h>
uint32_t mc_good_f32_init(mc_good_f32_t *st, const mc_good_f32_cfg_t *cfg);
uint32_t mc_good_q31_init(mc_good_q31_t *st, const mc_good_q31_cfg_t *cfg);
uint32_t mc_good_f32_reset(mc_good_f32_t *st);
uint32_t mc_good_q31_reset(mc_good_q31_t *st);
uint32_t
mc_good_f32_step_lim(mc_good_f32_t *st, float x, float lo, float hi,
                     float *p_out);
static inline uint32_t mc_good_f32_step(mc_good_f32_t *st, float x, float *p_out)
{
    (void)mc_good_f32_reset(st);
    const float y = mc_good_f32_next(st, x);
    mc_good_f32_reset(st);
    return mc_good_f32_step_lim(st, y, -1.0f, 1.0f, p_out);
}
/* helpers with other verbs may return anything */
float mc_good_f32_next(const mc_good_f32_t *st, float x);
void mc_good_f32_commit(mc_good_f32_t *st, float y);
void mc_stepper_ab_to_dq_f32(float a, float b, float *p_d, float *p_q);
#define MC_GOOD_STEP(st) mc_good_f32_step((st), 0.0f, NULL)
#endif
"""


def self_test():
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        kdir = os.path.join(tmp, "firmware", "kernels", "bad")
        os.makedirs(kdir)
        with open(os.path.join(kdir, "mc_bad.h"), "w", encoding="utf-8") as fh:
            fh.write(BAD_HEADER)
        findings, _nh, n = check(tmp)
        named = {re.search(r": (mc_\w+) returns", f).group(1) for f in findings
                 if " returns " in f}
        twins = {re.search(r": (mc_\w+)\(", f).group(1) for f in findings
                 if "is not the shape" in f}
        if named != BAD_EXPECTED or n != len(BAD_EXPECTED) + 6:
            print(f"self-test: bad header: expected findings {sorted(BAD_EXPECTED)}, "
                  f"got {sorted(named)} ({n} functions seen)")
            ok = False
        if twins != TWIN_EXPECTED:
            print(f"self-test: twins: expected findings {sorted(TWIN_EXPECTED)}, got "
                  f"{sorted(twins)}")
            ok = False
        if main_check(tmp, quiet=True) != 1:
            print("self-test: the check passed a bad header")
            ok = False
        os.remove(os.path.join(kdir, "mc_bad.h"))
        with open(os.path.join(kdir, "mc_good.h"), "w", encoding="utf-8") as fh:
            fh.write(GOOD_HEADER)
        findings, _nh, n = check(tmp)
        if findings or n != 6:
            print(f"self-test: good header: expected no finding and 6 functions, got "
                  f"{findings} ({n} functions seen)")
            ok = False
        os.remove(os.path.join(kdir, "mc_good.h"))
        findings, _nh, n = check(tmp)
        if not findings:
            print("self-test: an empty kernel tree passed")
            ok = False
    print("kernel signatures self-test: " + ("the check fails on every bad declaration"
                                             if ok else "FAILED"))
    return 0 if ok else 1


def main(argv):
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) == 3 and argv[1] == "--list":
        return main_list(argv[2])
    if len(argv) == 2:
        return main_check(argv[1])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
