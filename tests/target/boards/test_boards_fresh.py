#!/usr/bin/env python3
"""The boards' pins.csv and board.toml are the single source of truth:
 1. `mc_boards.py gen --root WORK` writes files byte-identical to the
    committed ones (each board's mc_board_<name>_gen.c/.h and the tables of
    boards/README.md), and `mc_boards.py check` agrees;
 2. the generator refuses a broken board with exit code 2 and a message that
    names the fault: a pin used twice, a missing signal, a wrong alternate
    function or pin for a signal, a debug pin, an ADC signal on a pin without
    an ADC channel, a gate enable that starts enabled, a DRV8301 gain that is
    not the sense scaling's, a malformed commit, an OC_ADJ_SET code out of
    range, and for the second axis's m1_* signals the same faults plus an
    incomplete set and a gate input that is neither TIM8's nor held low.
"""
import argparse
import filecmp
import os
import re
import shutil
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
GEN = os.path.join(ROOT, "tools", "boards", "mc_boards.py")
sys.path.insert(0, os.path.dirname(GEN))
import mc_boards  # noqa: E402

fails = []


def check(cond, what):
    if not cond:
        fails.append(what)


def run(*args):
    return subprocess.run([sys.executable, GEN, *args], capture_output=True, text=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)

    r = run("gen", "--root", a.work)
    check(r.returncode == 0, f"gen failed: {r.stderr}")
    boards = mc_boards.load_all()
    check({b["name"] for b in boards} == {"example", "odrive36", "odrive36_24v", "vesc6"},
          f"boards found: {[b['name'] for b in boards]}")
    rels = [mc_boards.README_REL]
    for b in boards:
        d = f"{mc_boards.BOARDS_REL}/{b['name']}"
        rels += [f"{d}/mc_board_{b['name']}_gen.c", f"{d}/mc_board_{b['name']}_gen.h"]
    for rel in rels:
        check(filecmp.cmp(os.path.join(a.work, rel), os.path.join(ROOT, rel), shallow=False),
              f"{rel} is stale: run tools/boards/mc_boards.py gen and commit")
    r = run("check")
    check(r.returncode == 0, f"mc_boards.py check: {r.stderr}")

    src = os.path.join(ROOT, mc_boards.BOARDS_REL, "odrive36")
    with open(os.path.join(src, "pins.csv")) as f:
        pins = f.read()
    with open(os.path.join(src, "board.toml")) as f:
        toml = f.read()

    def sub(text, old, new):
        out = re.sub(old, new, text, count=1, flags=re.M)
        check(out != text, f"mutation '{old}' did not apply")
        return out

    bad = {
        "used twice": ("pins", sub(pins, r"^drv_spi_cs,PC13,", "drv_spi_cs,PC0,")),
        "missing": ("pins", sub(pins, r"^can_tx,.*\n", "")),
        "must be af 1": ("pins", sub(pins, r"^pwm_ah,PA8,af,1,", "pwm_ah,PA8,af,2,")),
        "must be af 2 on one of": ("pins", sub(pins, r"^enc_a,PB4,", "enc_a,PA15,")),
        "SWDIO": ("pins", sub(pins, r"^m1_drv_spi_cs,PC14,", "m1_drv_spi_cs,PA13,")),
        "no ADC channel": ("pins", sub(pins, r"^adc_vbus,PA6,", "adc_vbus,PB2,")),
        # the second axis (M1): TIM4's encoder inputs, TIM8's outputs or held low, all or none
        "m1_enc_a must be af 2 on one of": ("pins", sub(pins, r"^m1_enc_a,PB6,", "m1_enc_a,PA15,")),
        "m1_pwm_ah must be af 3 on one of ['PC6', 'PI5'] (or an output held low)":
            ("pins", sub(pins, r"^(m1_pwm_ah,PC6,output,,none,pp,low,)0", r"\g<1>1")),
        "a second axis needs all of its signals; missing: m1_adc_ib":
            ("pins", sub(pins, r"^m1_adc_ib,.*\n", "")),
        "m1_adc_temp_fet on PB2, which has no ADC channel":
            ("pins", sub(pins, r"^m1_adc_temp_fet,PA4,", "m1_adc_temp_fet,PB2,")),
        "m1_enc_z (the index, an EXTI line) must be an input":
            ("pins", sub(pins, r"^m1_enc_z,PC15,input,,down,,,", "m1_enc_z,PC15,output,,none,pp,low,0")),
        "start disabled": ("pins", sub(pins, r"^(gate_enable,PB12,output,,none,pp,low,)0",
                                       r"\g<1>1")),
        "must be sense.amp_gain_v_per_v": ("toml", sub(toml, r"^gain_v_per_v = 40",
                                                       "gain_v_per_v = 20")),
        "40 hex digits": ("toml", sub(toml, r'^commit = "f9b5', 'commit = "zz')),
        "oc_adj_set is 0..31": ("toml", sub(toml, r"^oc_adj_set = 21", "oc_adj_set = 32")),
        # a Hall input may share an encoder pin, nothing else
        "not on an encoder pin": ("pins", sub(pins, r"^hall_c,PC9,", "hall_c,PC4,")),
        "used twice (pwm_ah": ("pins", sub(pins, r"^hall_a,PB4,", "hall_a,PA8,")),
        "need all of": ("pins", sub(pins, r"^hall_b,.*\n", "")),
        "enc_z (the index, an EXTI line) must be an input":
            ("pins", sub(pins, r"^enc_z,PC9,input,,down,,,", "enc_z,PC9,output,,none,pp,low,0")),
        "must be an output starting high (released)":
            ("pins", sub(pins, r"^(enc_spi_cs,PA0,output,,none,pp,low,)1", r"\g<1>0")),
        "encoder.type is one of": ("toml", sub(toml, r'^type = "abi"', 'type = "resolver"')),
        # an absolute encoder's counts are the chip's (8192 left from the A/B one)
        "counts_per_rev must be the as5047p's 16384":
            ("toml", sub(toml, r'^type = "abi"', 'type = "as5047p"')),
        # the PWM rate, the supply and the brake chopper (issue 29)
        "pwm.frequency_hz must be 5000..60000":
            ("toml", sub(toml, r"^frequency_hz = 24000", "frequency_hz = 70000")),
        "supply.nominal_v must lie inside": ("toml", sub(toml, r"^nominal_v = 48.0",
                                                         "nominal_v = 60.0")),
        "a brake chopper needs the brake_l and brake_h pins": ("pins", sub(pins, r"^brake_h,.*\n",
                                                                           "")),
        "'present' must be true or false": ("toml", sub(toml, r"^present = true",
                                                        'present = "yes"')),
    }
    for what, (which, text) in bad.items():
        d = os.path.join(a.work, "bad", "odrive36")
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(src, d)
        with open(os.path.join(d, "pins.csv" if which == "pins" else "board.toml"), "w") as f:
            f.write(text)
        r = run("validate", d)
        check(r.returncode == 2, f"{what}: generator exit {r.returncode}, want 2")
        check(what in r.stderr, f"{what}: message was {r.stderr.strip()!r}")
    # a variant whose base is missing
    d = os.path.join(a.work, "bad", "variant")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "board.toml"), "w") as f:
        f.write('base = "nosuch"\n')
    r = run("validate", d)
    check(r.returncode == 2 and "base 'nosuch' is not a board folder" in r.stderr,
          f"variant without base: exit {r.returncode}, {r.stderr.strip()!r}")
    for b in boards:
        r = run("validate", os.path.join(ROOT, mc_boards.BOARDS_REL, b["name"]))
        check(r.returncode == 0, f"{b['name']} does not validate: {r.stderr}")

    for f in fails:
        print("FAIL:", f)
    print(f"{len(boards)} boards, {len(bad)} refusals, {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
