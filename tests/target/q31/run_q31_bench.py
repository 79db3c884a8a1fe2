#!/usr/bin/env python3
"""run_q31_bench.py QEMU MACHINE ELF [--out JSON]

Runs the q31/f32 twin instruction-count image under QEMU (-icount shift=0),
checks that every case reported a plausible count (> 0, q31 and f32 both
present for each kernel) and prints the table. With --out, writes the
results as JSON (used for the README table)."""
import json
import subprocess
import sys
import tempfile
import os


def main():
    args = sys.argv[1:]
    out = None
    if "--out" in args:
        i = args.index("--out")
        out = args[i + 1]
        del args[i:i + 2]
    qemu, machine, elf = args
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "sh.txt")
        cmd = [qemu, "-M", machine, "-nographic", "-monitor", "none", "-serial", "null",
               "-icount", "shift=0", "-chardev", f"file,id=sh0,path={path}",
               "-semihosting-config", "enable=on,target=native,chardev=sh0", "-kernel", elf]
        rc = subprocess.run(cmd, timeout=300).returncode
        with open(path) as f:
            text = f.read()
    if rc != 0:
        print(text)
        print(f"FAIL: image exited {rc}")
        return 1
    rows = [json.loads(ln) for ln in text.splitlines() if ln.startswith("{")]
    cases = [r for r in rows if "name" in r]
    byk = {}
    for r in cases:
        byk.setdefault(r["name"], {})[r["format"]] = r
    ok = True
    print(f"{machine}: instructions per call (min / mean / max), overhead "
          f"{rows[0].get('overhead_instr')} subtracted")
    print(f"{'kernel':18s} {'q31':>22s} {'f32':>22s}")
    for name, d in byk.items():
        cells = []
        for fmt in ("q31", "f32"):
            r = d.get(fmt)
            if r is None or not (0 < r["instr_min"] <= r["instr_mean"] <= r["instr_max"] < 200000):
                ok = False
                cells.append("MISSING/BAD")
            else:
                cells.append(f"{r['instr_min']}/{r['instr_mean']}/{r['instr_max']}")
        print(f"{name:18s} {cells[0]:>22s} {cells[1]:>22s}")
    if len(byk) < 8:
        ok = False
    if out:
        with open(out, "w") as f:
            json.dump({"machine": machine, "cases": cases}, f, indent=1)
    print("PASS" if ok else "FAIL: a case is missing or implausible")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
