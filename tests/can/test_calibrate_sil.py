#!/usr/bin/env python3
"""Commissioning over CAN against the SIL firmware (mcsim can-telemetry,
frames through a candump log and a command script, the drive's
configuration in a flash file), decoded with mdtool's own code
(mdtool.can.calibrate.Collector, the code `mdtool calibrate` runs):

1. READ the configuration in use (the scenario's motor: the truth), START
   commissioning, then SET_ENABLE and a second START while it runs (both
   refused MODE); progress statuses through the steps to DONE with the
   results staged; every result within the issue's accuracy bounds of the
   truth; APPLY (the whole-set check) and SAVE answered OK.
2. A second boot from that flash file: the stored configuration holds the
   measured values, bit for bit as COMMISSION_RESULT carried them.
3. START while enabled: CMD_ERROR MODE, no commissioning status at all.

    test_calibrate_sil.py --mcsim MCSIM --work DIR --repo ROOT
"""
import argparse
import json
import math
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools", "mdtool", "src"))

from mdtool.can import calibrate, dbc  # noqa: E402
from mdtool.can.client import named  # noqa: E402

fails = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)


def bits_f32(u):
    return struct.unpack("<f", struct.pack("<I", int(u) & 0xFFFFFFFF))[0]


class Sil:
    def __init__(self, mcsim, work):
        self.mcsim, self.work = mcsim, work
        self.db = dbc.load_db(os.path.join(ROOT, "tools", "can", "motordrive.dbc"))
        meta = json.loads(Path(ROOT, "tools", "config", "params_meta.json").read_text())
        self.pid = {p["name"]: p["id"] for p in meta["params"]}
        self.ptype = {p["name"]: p["type"] for p in meta["params"]}

    def frame(self, t, msg, **sig):
        m = self.db.get_message_by_name(msg)
        return "(%017.6f) can0 %03X#%s" % (t, m.frame_id, m.encode(sig).hex().upper())

    def read(self, t, name):
        return self.frame(t, "PARAM_REQ", opcode=0, param_id=self.pid[name], value=0)

    def run(self, name, cmds, duration, flash):
        script = os.path.join(self.work, name + ".cmds.log")
        Path(script).write_text("\n".join(cmds) + "\n")
        log = os.path.join(self.work, name + ".can.log")
        env = dict(os.environ, MCSIM_CAN_LOG=log, MCSIM_CAN_CMDS=script)
        env.pop("MCSIM_CAN_IF", None)
        argv = [self.mcsim, "run", "can-telemetry", "--out", os.path.join(self.work, name),
                "--duration", str(duration), "--flash", flash,
                # the motor without the scenario's 0.05 kg m^2 flywheel (commissioning
                # turns the rotor to and fro at the test current; a heavy
                # flywheel rings for seconds: commission/README.md, Limits)
                "--set", "J_kgm2=0.002"]
        r = subprocess.run(argv, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"mcsim failed ({r.returncode}): {r.stderr}")
        out = []
        table = dbc.by_cmd(self.db)
        for line in Path(log).read_text().splitlines():
            ts, _, rest = line.split()
            can_id, data = rest.split("#")
            can_id, data = int(can_id, 16), bytes.fromhex(data)
            msg = table.get(can_id & dbc.CMD_MASK)
            if dbc.node_of(can_id) != 1 or msg is None or len(data) != msg.length:
                continue
            out.append((float(ts.strip("()")), msg.name, named(msg, dbc.decode_signals(msg, data))))
        return out

    def value(self, name, raw):
        return int(raw) if self.ptype[name] == "u32" else bits_f32(raw)


def replies(frames):
    return [v for _t, n, v in frames if n == "PARAM_REPLY"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    sil = Sil(a.mcsim, a.work)
    flash = os.path.join(a.work, "drive.flash")
    truth_names = ["r_ohm", "ld_h", "lq_h", "flux_wb", "pole_pairs", "encoder_offset_rad",
                   "encoder_reversed", "i_offset_a_a", "i_offset_b_a"]

    # ---- 1. commission, apply, save
    cmds = [sil.read(0.01 + 0.001 * i, n) for i, n in enumerate(truth_names)]
    cmds += [sil.frame(0.05, "COMMISSION_CMD", action=1, i_test_a=0, v_test_max_v=0, speed_max_m_rad_s=0),
             sil.frame(0.30, "SET_CONTROL_MODE", control_mode=1),
             sil.frame(0.31, "SET_ENABLE", enable=1),
             sil.frame(0.32, "COMMISSION_CMD", action=1, i_test_a=0, v_test_max_v=0, speed_max_m_rad_s=0),
             sil.frame(11.0, "PARAM_REQ", opcode=2, param_id=0, value=0),
             sil.frame(11.1, "PARAM_REQ", opcode=3, param_id=0, value=0)]
    # the host's keep-alive while commissioning runs (without it the drive
    # aborts the sequence timeout_s after START)
    cmds += [sil.frame(0.06 + 0.1 * k, "HOST_HEARTBEAT", counter=k % 256) for k in range(110)]
    fr = sil.run("run1", sorted(cmds), 11.3, flash)
    rep = replies(fr)
    truth = {r["param_id"]: r for r in rep if r["opcode"] == "READ"}
    truth = {n: sil.value(n, truth[sil.pid[n]]["value"]) for n in truth_names if sil.pid[n] in truth}
    check(len(truth) == len(truth_names), f"the configuration in use read back: {truth}")
    errs = [(v["rejected_cmd"], v["error"]) for _t, n, v in fr if n == "CMD_ERROR"]
    check(errs == [(0x10, "MODE"), (0x1C, "MODE")] or errs == [(0x11, "MODE"), (0x10, "MODE"), (0x1C, "MODE")],
          f"while it runs: enable and a second START refused MODE: {errs}")
    col = calibrate.Collector()
    for _t, n, v in fr:
        if n.startswith("COMMISSION_"):
            col.feed(n, v)
    s = col.summary()
    steps = []
    for st in col.statuses:
        if not steps or steps[-1] != st["step"]:
            steps.append(st["step"])
    check(steps[:1] == ["OFFSETS"] and steps[-1] == "DONE" and "FLUX" in steps,
          f"progress through the steps: {steps}")
    pct = [int(st["progress_pct"]) for st in col.statuses]
    check(pct == sorted(pct) and pct[-1] == 100, f"progress rises to 100 %: {pct[:3]} ... {pct[-3:]}")
    t_done = next(t for t, n, v in fr if n == "COMMISSION_STATUS" and v["step"] == "DONE")
    check(t_done < 10.05, f"done in {t_done - 0.05:.2f} s simulated (the issue: under 10 s)")
    check(s["staged"] and s["error_bits"] == 0, f"done, results staged: {s}")
    res = s["results"]
    print("COMMISSION_CAN " + json.dumps({"results": res, "truth": truth, "done_s": t_done - 0.05}))

    def rel(k):
        return abs(res[k] - truth[k]) / abs(truth[k])
    # Accuracy bounds of issue 18 (the board's 12-bit currents and noise):
    check(rel("r_ohm") < 0.02, f"R {res['r_ohm']:.5g} vs {truth['r_ohm']:.5g} ohm within 2 %")
    check(rel("ld_h") < 0.05, f"Ld {res['ld_h']:.5g} vs {truth['ld_h']:.5g} H within 5 %")
    check(rel("lq_h") < 0.05, f"Lq {res['lq_h']:.5g} vs {truth['lq_h']:.5g} H within 5 %")
    check(rel("flux_wb") < 0.03, f"flux {res['flux_wb']:.5g} vs {truth['flux_wb']:.5g} Wb within 3 %")
    check(res["pole_pairs"] == truth["pole_pairs"], f"pole pairs {res['pole_pairs']} exact")
    d_off = math.remainder(res["encoder_offset_rad"] - truth["encoder_offset_rad"], 2 * math.pi)
    check(abs(d_off) < math.radians(1.0), f"encoder offset {math.degrees(d_off):+.3f} deg el. within 1 deg")
    check(res["encoder_direction"] == (-1 if truth["encoder_reversed"] else 1), "encoder direction")
    # This plant's current sensors have no offset: the measured ones are
    # the quantisation of a 12-bit +-20 A reading averaged (one LSB, 9.8 mA).
    for k in ("i_offset_a_a", "i_offset_b_a"):
        check(abs(res[k] - truth[k]) < 0.0098, f"{k} {res[k]:+.5f} A within one LSB of {truth[k]}")
    apply_ = [r for r in rep if r["opcode"] == "APPLY"]
    save = [r for r in rep if r["opcode"] == "SAVE"]
    check(len(apply_) == 1 and apply_[0]["status"] == "OK", f"APPLY of the staged results: {apply_}")
    check(len(save) == 1 and save[0]["status"] == "OK", f"SAVE: {save}")

    # ---- 2. the next boot runs the measured values
    stored_names = ["r_ohm", "ld_h", "lq_h", "flux_wb", "pole_pairs", "encoder_offset_rad"]
    fr2 = sil.run("run2", [sil.read(0.01 + 0.001 * i, n) for i, n in enumerate(stored_names)], 0.05, flash)
    got = {r["param_id"]: r for r in replies(fr2)}
    for n in stored_names:
        v = sil.value(n, got[sil.pid[n]]["value"]) if sil.pid[n] in got else None
        want = int(res[n]) if n == "pole_pairs" else res[n]
        check(v == want, f"after the reboot {n} = {v} (measured {want})")

    # ---- 3. START while enabled
    fr3 = sil.run("run3", [sil.frame(0.02, "SET_CONTROL_MODE", control_mode=1),
                           sil.frame(0.03, "SET_ENABLE", enable=1),
                           sil.frame(0.04, "COMMISSION_CMD", action=1, i_test_a=0, v_test_max_v=0,
                                     speed_max_m_rad_s=0),
                           sil.frame(0.05, "SET_ENABLE", enable=0)], 0.1, flash)
    errs3 = [(v["rejected_cmd"], v["error"]) for _t, n, v in fr3 if n == "CMD_ERROR"]
    check(errs3 == [(0x1C, "MODE")], f"START while enabled: CMD_ERROR MODE: {errs3}")
    check(not any(n == "COMMISSION_STATUS" for _t, n, _v in fr3), "and no commissioning started")
    print("calibrate SIL checks: " + ("FAILED" if fails else "passed"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
