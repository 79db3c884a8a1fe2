#!/usr/bin/env python3
"""Public kernel functions follow the naming convention of the design notes
(section 2, after ARM CMSIS-DSP): mc_<capability>_<format>_<verb>.

    check_kernel_names.py <source-dir>     check firmware/kernels/**/*.h
    check_kernel_names.py --self-test      prove the check can fail
    check_kernel_names.py --list <source-dir>   print every public name and its verdict

A public function is one declared or defined at file scope of a header under
firmware/kernels/ (prototypes and static inline bodies alike; what a body
calls is not a declaration). Two rules:

  Kernels (every folder but math/ and transforms/):
      mc_<capability>_<format>_<verb>[_<detail>]
    capability  one or more lower-case words, none of them a format
                (pi, foc, spdpll, csmc_hgo, ident_avg, ...)
    format      f32 | q31 | q15
    verb        one of VERBS below, optionally followed by a detail
                (step_ff, step_dq, set_gains, get_offset_a, ...)

  Stateless primitives (math/, transforms/: fast math, fixed-point
  arithmetic, Clarke/Park/SVPWM; the CMSIS-DSP form arm_sqrt_f32,
  arm_clarke_q31): mc_<words>, where one word names the number format
  (f32, q31, q15, q46, u64), e.g. mc_sqrt_f32, mc_park_q31, mc_q46_mul.

  Control-law plug-ins (firmware/app/ctrl/mc_ctrl_*.h, the drive's CTRL mode):
      mc_ctrl_<law>[_q31]_<verb>[_<detail>]
    law         one word (pi2d, sls, pos, csmc)
    format      none for the float plug-in, q31 for its fixed-point twin
                (the files: mc_ctrl_<x>.h and mc_ctrl_<x>_q31.h)
    verb        one of PLUGIN_VERBS: init, ops (the table for
                mc_drive_attach_ctrl), reset and fast (the table's
                functions, when exported), step (the fast step without the
                drive), set_<field>, get_<field>

Names that broke a rule when the check was written are listed in ALLOWED
(issue 22): each is still reported in --list, a new violation fails, and
an entry that no longer names a public function fails too, so the list
only shrinks.

Exit status 0 with a one-line summary, 1 with one line per finding.
"""
import os
import re
import sys
import tempfile

KERNEL_DIR = "firmware/kernels"
PRIMITIVE_DIRS = ("math", "transforms")
KERNEL_FORMATS = ("f32", "q31", "q15")
PRIMITIVE_FORMATS = ("f32", "q31", "q15", "q46", "u64")
# The verbs a kernel offers (design section 2 names init, reset, step and
# their return convention; the others are the few a kernel needs besides).
VERBS = {
    "init": "validate a config and derive its coefficients",
    "validate": "check a config as init does, changing nothing (returns its error bits)",
    "reset": "return the state to its initial value",
    "step": "advance one sample (step_<detail>: the same step for another input form)",
    "set": "set_<field>: change one part of the config at run time, validated as init does",
    "get": "get[_<field>]: read a result or the state, changing nothing",
    "eval": "evaluate a plan at a given time, changing nothing",
    "plan": "compute a plan (a trajectory) from limits and a target",
    "commit": "second half of a step split in two (compute, then commit the state)",
    "track": "make an integrator follow an output set from outside (bumpless transfer)",
}

PLUGIN_DIR = "firmware/app/ctrl"
PLUGIN_VERBS = {
    "init": "validate a config, set up the state and the ops table",
    "ops": "the plug-in table for mc_drive_attach_ctrl (one name for every law)",
    "reset": "the table's reset, exported for direct use",
    "fast": "the table's fast step, exported for direct use",
    "step": "step[_<detail>]: the fast step on measurements in the law's frame (for a loop "
            "without the drive), or one part of it",
    "set": "set_<field>: a reference or setting, validated",
    "get": "get_<field>: read telemetry or the state, changing nothing",
}

# Today's violations (issue 22, "one shape per capability"): renaming them
# touches firmware/app/ and the kernel files being moved, so they are
# renamed with that move, not here. Remove an entry when its name is fixed.
ALLOWED = {
    # csmc/: the CSMC loop and its helpers
    "mc_csmc_f32_err_from_state",
    "mc_linalg_expm_f32", "mc_linalg_hurwitz_f32", "mc_linalg_poly_from_roots_f32",
    "mc_csvc_f32_advance", "mc_csvc_f32_advance_m0", "mc_csvc_f32_advance_m1",
    "mc_csvc_f32_advance_m2", "mc_csvc_f32_force_dense", "mc_csvc_f32_integrator",
    "mc_csvc_f32_place", "mc_csvc_f32_sigma", "mc_csvc_f32_term", "mc_csvc_f32_term_m0",
    "mc_csvc_f32_term_m1", "mc_csvc_f32_term_m2", "mc_csvc_f32_update",
    "mc_csvc_q31_term_q46", "mc_csvc_q31_update",
    "mc_hgo_f32_advance", "mc_hgo_f32_advance_run", "mc_hgo_f32_advance_start",
    "mc_stepper_ab_to_dq_f32", "mc_stepper_ab_to_dq_sc_f32", "mc_stepper_dq_to_ab_f32",
    "mc_stepper_dq_to_ab_sc_f32", "mc_stepper_theta_e_f32",
    # filters/
    "mc_ddiff_f32_next",
    # foc/, fw/
    "mc_foc_f32_gains_from_bandwidth",
    "mc_fw_f32_mtpa_id",
    # ident/
    "mc_ident_l_square_wave_f32", "mc_ident_r_two_level_f32",
    # observer/
    "mc_fluxobs_f32_critical_speed", "mc_fluxobs_f32_gamma_for_critical_speed",
    "mc_fluxobs_f32_time_scale",
    # pi/
    "mc_pi_q31_cfg_from_f32",
    "mc_pi_f32_core", "mc_pi_f32_core_in", "mc_pi_f32_core_sat",
    # pi2d/
    "mc_pi2d_f32_certify",
    # traj/
    "mc_traj_f32_shift", "mc_traj_f32_stop",
    # transforms/: the limit-mode check the f32 and q31 SVPWM share names
    # no format (it has none); a private helper of the two files
    "mc_svpwm_limit_ok",
}

NOT_FUNCTIONS = {"sizeof", "defined", "_Static_assert", "static_assert", "_Alignas",
                 "alignas", "_Alignof", "alignof", "__attribute__", "__declspec",
                 "__asm__", "asm", "typeof", "__typeof__", "_Generic", "if", "while",
                 "for", "switch", "return"}


def strip_code(text):
    """Comments, string and character literals and preprocessor lines out;
    newlines kept so positions map to line numbers."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if at_line_start and c == "#":   # a directive, with its continuations
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("\n")
                    i += 2
                elif text.startswith("/*", i):   # a comment may run past the line
                    j = text.find("*/", i + 2)
                    j = n if j < 0 else j + 2
                    out.append("\n" * text.count("\n", i, j))
                    i = j
                else:
                    i += 1
            continue
        at_line_start = False
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(" ")
            i = j + 1
        else:
            out.append(c)
            if c == "\n":
                at_line_start = True
            i += 1
    return "".join(out)


def public_functions(text):
    """(name, line) of every function declared or defined at file scope."""
    code = strip_code(text)
    found = []
    depth = 0          # braces that are not an extern "C" block
    stack = []         # per open brace: counts for depth or not
    parens = 0
    i = 0
    while i < len(code):
        c = code[i]
        if c == "{":
            # extern "C" { (the literal is blanked): no scope of its own
            linkage = re.search(r"\bextern\s*$", code[max(0, i - 40):i]) is not None
            stack.append(not linkage)
            depth += 0 if linkage else 1
        elif c == "}":
            if stack and stack.pop():
                depth -= 1
        elif c == "(":
            if depth == 0 and parens == 0:
                # the identifier that ends right before this parenthesis
                j = i - 1
                while j >= 0 and code[j] in " \t\n":
                    j -= 1
                k = j
                while k >= 0 and (code[k].isalnum() or code[k] == "_"):
                    k -= 1
                name = code[k + 1:j + 1]
                after = code[i + 1:i + 40].lstrip()
                # "type (*name)(...)": a pointer declarator, not a function
                if after.startswith("*"):
                    name = ""
                if name and not name[0].isdigit() and name not in NOT_FUNCTIONS \
                        and not name.isupper() and not name.startswith("__"):
                    found.append((name, code.count("\n", 0, i) + 1))
            parens += 1
        elif c == ")":
            parens -= 1
        i += 1
    return found


def verdict(name, folder):
    """None when the name follows its rule, else the reason."""
    if not name.startswith("mc_"):
        return "not in the mc_ name space"
    words = name[3:].split("_")
    if not all(re.fullmatch(r"[a-z0-9]+", w) for w in words):
        return "not lower-case words joined by single underscores"
    if folder in PRIMITIVE_DIRS:
        if not any(w in PRIMITIVE_FORMATS for w in words):
            return f"a primitive names its number format ({'|'.join(PRIMITIVE_FORMATS)})"
        return None
    fmt = [k for k, w in enumerate(words) if w in KERNEL_FORMATS]
    if not fmt:
        return f"no format word ({'|'.join(KERNEL_FORMATS)})"
    k = fmt[0]
    if k == 0:
        return "no capability before the format"
    if k + 1 >= len(words):
        return "no verb after the format (mc_<capability>_<format>_<verb>)"
    if words[k + 1] not in VERBS:
        return f"'{words[k + 1]}' is not a kernel verb ({', '.join(VERBS)})"
    if words[k + 1] == "set" and k + 2 >= len(words):
        return "set needs the field it sets (set_<field>)"
    return None


def plugin_verdict(name):
    """None when a plug-in function follows mc_ctrl_<law>[_q31]_<verb>, else why."""
    words = name.split("_")
    if len(words) < 4 or words[0] != "mc" or words[1] != "ctrl":
        return "not mc_ctrl_<law>_<verb>"
    if not all(re.fullmatch(r"[a-z0-9]+", w) for w in words):
        return "not lower-case words joined by single underscores"
    k = 4 if words[3] == "q31" else 3
    if words[3] in KERNEL_FORMATS and words[3] != "q31":
        return f"'{words[3]}': a float plug-in names no format (its twin: q31)"
    if k >= len(words):
        return "no verb after the law"
    if words[k] not in PLUGIN_VERBS:
        return f"'{words[k]}' is not a plug-in verb ({', '.join(PLUGIN_VERBS)})"
    if words[k] in ("set", "get") and k + 1 >= len(words):
        return f"{words[k]} needs the field (<verb>_<field>)"
    if words[k] not in ("set", "get", "step") and k + 1 < len(words):
        return f"'{words[k]}' takes no detail"
    return None


def scan_plugins(root):
    """{name: (rel_path, line)} over the plug-in headers."""
    names = {}
    base = os.path.join(root, PLUGIN_DIR)
    for f in sorted(os.listdir(base)) if os.path.isdir(base) else []:
        if not (f.startswith("mc_ctrl_") and f.endswith(".h")):
            continue
        path = os.path.join(base, f)
        with open(path, encoding="utf-8", errors="replace") as fh:
            text = fh.read()
        for name, line in public_functions(text):
            names.setdefault(name, (os.path.relpath(path, root), line))
    return names


def check_plugins(root):
    """Findings over the plug-in headers (no allow-list: every name follows)."""
    return [f"{rel}:{line}: {name}: {why}"
            for name, (rel, line) in sorted(scan_plugins(root).items(), key=lambda kv: kv[1])
            for why in [plugin_verdict(name)] if why is not None]


def scan(root):
    """{name: (rel_path, line, folder)} over the kernel headers."""
    names = {}
    base = os.path.join(root, KERNEL_DIR)
    for dirpath, dirs, files in os.walk(base):
        dirs.sort()
        for f in sorted(files):
            if not f.endswith(".h"):
                continue
            path = os.path.join(dirpath, f)
            rel = os.path.relpath(path, root)
            folder = os.path.relpath(path, base).split(os.sep)[0]
            with open(path, encoding="utf-8", errors="replace") as fh:
                text = fh.read()
            for name, line in public_functions(text):
                names.setdefault(name, (rel, line, folder))
    return names


def check(root, allowed):
    names = scan(root)
    findings, allowed_hits = [], []
    for name, (rel, line, folder) in sorted(names.items(), key=lambda kv: kv[1]):
        why = verdict(name, folder)
        if why is None:
            if name in allowed:
                findings.append(f"{rel}:{line}: {name} follows the rule now: remove it from ALLOWED")
            continue
        if name in allowed:
            allowed_hits.append(f"{rel}:{line}: {name}: {why}")
        else:
            findings.append(f"{rel}:{line}: {name}: {why}")
    for name in sorted(set(allowed) - set(names)):
        findings.append(f"ALLOWED names {name}, which is no public kernel function: remove it")
    return findings, names, allowed_hits


def main_check(root, list_all=False):
    findings, names, allowed_hits = check(root, ALLOWED)
    if list_all:
        for name, (rel, line, folder) in sorted(names.items(), key=lambda kv: kv[1]):
            why = verdict(name, folder)
            print(f"{'ok ' if why is None else 'BAD'} {rel}:{line}: {name}" + (f": {why}" if why else ""))
    plugins = scan_plugins(root)
    if list_all:
        for name, (rel, line) in sorted(plugins.items(), key=lambda kv: kv[1]):
            why = plugin_verdict(name)
            print(f"{'ok ' if why is None else 'BAD'} {rel}:{line}: {name}" + (f": {why}" if why else ""))
    findings = findings + check_plugins(root)
    for f in findings:
        print(f)
    if not names or not plugins:
        print("kernel names: no public functions found (wrong source directory?)", file=sys.stderr)
        return 1
    if findings:
        print(f"kernel names: {len(findings)} finding(s); the rule is in {os.path.basename(__file__)}",
              file=sys.stderr)
        return 1
    print(f"kernel names: {len(names)} public functions, {len(names) - len(allowed_hits)} follow "
          f"the rule, {len(allowed_hits)} known violations allowed (issue 22); "
          f"{len(plugins)} plug-in functions follow mc_ctrl_<law>[_q31]_<verb>")
    return 0


SELF_TEST_GOOD = """\
/* mc_not_a_decl(x) in a comment, "mc_nor_in_a_string(" */
#ifndef MC_X_H
#define MC_X_H(a) mc_macro_body(a)
#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif
#define MC_X_ERR_NONE 0u
typedef uint32_t (*mc_x_hook_fn)(void *ctx);
typedef struct {
    float kp;
    uint32_t (*cb)(int bad_name_in_a_member);
} mc_x_f32_cfg_t;
uint32_t mc_x_f32_init(const mc_x_f32_cfg_t *cfg,
                       float (*f)(float not_a_decl));
uint32_t mc_x_f32_reset(void);
static inline uint32_t mc_x_q31_step(int32_t e)
{
    return helper_call(e) + mc_other_thing(e);
}
void mc_x_f32_step_ff(void);
void mc_x_f32_set_gains(float kp);
float mc_x_f32_get(void);
float mc_x_hgo_f32_get_z1(void);
__attribute__((always_inline)) static inline float mc_x_f32_eval(float t) { return t; }
_Static_assert(sizeof(float) == 4, "f32");
#ifdef __cplusplus
}
#endif
#endif
"""
SELF_TEST_PRIMITIVES = """\
static inline float mc_sqrt_f32(float x) { return x; }
static inline int32_t mc_q31_add_sat(int32_t a, int32_t b) { return a + b; }
int64_t mc_q46_mul(int64_t a, int64_t b);
"""
SELF_TEST_BAD = [
    ("pi", "float pi_f32_step(float e);"),                 # no mc_ prefix
    ("pi", "uint32_t mc_pi_f32_update(void);"),             # not a verb
    ("pi", "uint32_t mc_pi_step_f32(void);"),               # format after the verb
    ("pi", "uint32_t mc_pi_init(void);"),                   # no format
    ("pi", "uint32_t mc_f32_pi_init(void);"),               # no capability
    ("pi", "uint32_t mc_pi_f32(void);"),                    # no verb
    ("pi", "uint32_t mc_pi_f32_set(float k);"),             # set without a field
    ("pi", "uint32_t mc_pi_F32_step(void);"),               # upper case
    ("pi", "uint32_t mc_pi_f32__step(void);"),              # double underscore
    ("pi", "static inline uint32_t\nmc_pi_f32_run(void)\n{\n    return 0u;\n}"),
    ("pi", 'extern "C" {\nvoid mc_pi_f32_go(void);\n}'),   # inside a linkage block
    ("math", "static inline float mc_fast_sqrt(float x) { return x; }"),  # no format
]


def self_test():
    failures = 0

    def tree(tmp, extra_folder=None, extra=None):
        for folder, text in (("pi", SELF_TEST_GOOD), ("math", SELF_TEST_PRIMITIVES)):
            d = os.path.join(tmp, KERNEL_DIR, folder)
            os.makedirs(d, exist_ok=True)
            with open(os.path.join(d, f"mc_{folder}.h"), "w", encoding="utf-8") as fh:
                fh.write(text)
        for folder in ("pi", "math"):
            bad = os.path.join(tmp, KERNEL_DIR, folder, "mc_bad.h")
            if os.path.exists(bad):
                os.remove(bad)
        if extra is not None:
            bad = os.path.join(tmp, KERNEL_DIR, extra_folder, "mc_bad.h")
            with open(bad, "w", encoding="utf-8") as fh:
                fh.write("#pragma once\n" + extra + "\n")

    with tempfile.TemporaryDirectory() as tmp:
        tree(tmp)
        findings, names, _ = check(tmp, set())
        want = {"mc_x_f32_init", "mc_x_f32_reset", "mc_x_q31_step", "mc_x_f32_step_ff",
                "mc_x_f32_set_gains", "mc_x_f32_get", "mc_x_hgo_f32_get_z1", "mc_x_f32_eval",
                "mc_sqrt_f32", "mc_q31_add_sat", "mc_q46_mul"}
        if findings or set(names) != want:
            print("self-test: the clean tree gave", findings, "names", sorted(set(names) ^ want))
            failures += 1
        for folder, text in SELF_TEST_BAD:
            tree(tmp, folder, text)
            findings, _, _ = check(tmp, set())
            if len(findings) != 1:
                print(f"self-test: {text!r} in {folder}/ gave {len(findings)} findings, want 1: {findings}")
                failures += 1
            # the allow-list lets exactly that name through
            bad_name = public_functions(text)[0][0]
            findings, _, hits = check(tmp, {bad_name})
            if findings or len(hits) != 1:
                print(f"self-test: allowing {bad_name} gave {findings}, {hits}")
                failures += 1
        tree(tmp)
        # an allow-list entry that names nothing, or a name that now passes, fails
        for stale in ("mc_gone_f32_step", "mc_x_f32_init"):
            findings, _, _ = check(tmp, {stale})
            if len(findings) != 1:
                print(f"self-test: stale allow-list entry {stale} gave {findings}, want 1 finding")
                failures += 1
    # plug-ins: the names of firmware/app/ctrl pass, each bad form fails
    for good in ("mc_ctrl_pi2d_init", "mc_ctrl_pi2d_q31_ops", "mc_ctrl_sls_set_speed_ref",
                 "mc_ctrl_sls_q31_get_tm_f32", "mc_ctrl_sls_fast"):
        if plugin_verdict(good) is not None:
            print(f"self-test: plug-in name {good} refused: {plugin_verdict(good)}")
            failures += 1
    for bad in ("mc_ctrl_sls_table", "mc_ctrl_pi2d_f32_init", "mc_ctrl_pi2d_set",
                "mc_ctrl_pi2d_ops_x", "mc_ctrl_pi2d", "mc_pi2d_ctrl_init", "mc_ctrl_sls_q31_flux_wb"):
        if plugin_verdict(bad) is None:
            print(f"self-test: bad plug-in name {bad} passed")
            failures += 1
    if failures:
        print(f"self-test: {failures} case(s) wrong", file=sys.stderr)
        return 1
    print(f"self-test: clean tree passes, all {len(SELF_TEST_BAD)} bad names, 2 stale "
          "allow-list entries and 7 bad plug-in names caught")
    return 0


if __name__ == "__main__":
    args = sys.argv[1:]
    if args == ["--self-test"]:
        sys.exit(self_test())
    if len(args) == 2 and args[0] == "--list":
        sys.exit(main_check(args[1], list_all=True))
    if len(args) == 1 and not args[0].startswith("-"):
        sys.exit(main_check(args[0]))
    print(__doc__, file=sys.stderr)
    sys.exit(2)
