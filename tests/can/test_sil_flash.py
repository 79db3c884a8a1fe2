#!/usr/bin/env python3
"""The SIL drive keeps its configuration in its flash file across runs
(mcsim run can-telemetry --flash FILE), with every frame encoded and
decoded from the DBC by cantools:

 1. run 1 on a new file: boot EMPTY (summary and HEARTBEAT.cfg_status);
    PARAM_REQ WRITE speed_max_rad_s and tm_currents_hz, APPLY, SAVE: all OK,
    SAVE answers record sequence 1 and from then on the heartbeat says
    STORED (the store's status); the file is a 32 KiB flash image;
 2. run 2 on the same file: boot STORED, the summary names the parameters
    taken from the store, READ gives back both values, the CURRENTS frames
    come at the stored rate, a speed reference above the stored limit is
    refused (CMD_ERROR) while one below it is accepted;
 3. a flipped byte inside the record: boot CORRUPT, said on stderr and in
    the summary and heartbeat; READ gives the scenario's values again;
 4. a file of the wrong size, or --flash on a scenario without flash:
    exit 2, "mcsim: <file>: <reason>", nothing written (file unchanged);
 5. without --flash, SAVE answers STORE (no store) and nothing else changes.

    test_sil_flash.py --mcsim MCSIM --work DIR --repo ROOT
"""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import cantools


def f32_bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def bits_f32(u):
    return struct.unpack("<f", struct.pack("<I", int(u)))[0]


class Sil:
    def __init__(self, args):
        self.mcsim = args.mcsim
        self.work = args.work
        self.db = cantools.database.load_file(
            os.path.join(args.repo, "tools", "can", "motordrive.dbc"))
        meta = json.loads(Path(args.repo, "tools", "config", "params_meta.json").read_text())
        self.pid = {p["name"]: p["id"] for p in meta["params"]}
        self.node = 1

    def frame(self, t, msg, **sig):
        m = self.db.get_message_by_name(msg)
        data = m.encode(sig)
        # the DBC's ids are node 1's (id = node << 5 | cmd)
        return "(%017.6f) can0 %03X#%s" % (t, m.frame_id, data.hex().upper())

    def run(self, name, cmds, flash=None, extra=(), expect_rc=0, duration=0.4):
        out = os.path.join(self.work, name)
        script = os.path.join(self.work, name + ".cmds.log")
        with open(script, "w") as f:
            f.write("\n".join(cmds) + "\n")
        log = os.path.join(self.work, name + ".can.log")
        env = dict(os.environ, MCSIM_CAN_LOG=log, MCSIM_CAN_CMDS=script)
        env.pop("MCSIM_CAN_IF", None)
        argv = [self.mcsim, "run", "can-telemetry", "--out", out, "--duration", str(duration)]
        if flash:
            argv += ["--flash", flash]
        argv += list(extra)
        r = subprocess.run(argv, env=env, capture_output=True, text=True)
        assert r.returncode == expect_rc, (argv, r.returncode, r.stderr)
        if expect_rc != 0:
            return r, None, None
        summary = json.loads(Path(out, "can-telemetry.json").read_text())
        return r, summary, self.decode(log)

    def decode(self, log):
        frames = []
        for line in Path(log).read_text().splitlines():
            ts, _, rest = line.split()
            can_id, data = rest.split("#")
            can_id = int(can_id, 16)
            if can_id >> 5 != self.node:
                continue
            try:
                m = self.db.get_message_by_frame_id(can_id)
            except KeyError:
                continue
            frames.append((float(ts.strip("()")), m.name,
                           m.decode(bytes.fromhex(data), decode_choices=False)))
        return frames


def replies(frames):
    return [s for _, n, s in frames if n == "PARAM_REPLY"]


def cfg_status(frames):
    hb = [s["cfg_status"] for _, n, s in frames if n == "HEARTBEAT"]
    assert hb, "no HEARTBEAT"
    assert len(set(hb)) == 1, hb
    return hb[0]


def report(fails):
    """The exit code of a checks-list test: 0 when no check failed."""
    if fails:
        print(f"{len(fails)} check(s) failed")
        return 1
    print("all checks passed")
    return 0


def setup():
    """--mcsim --work --repo, a fresh work directory, and the Sil on them."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--repo", required=True)
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    return args, Sil(args)


def main():
    args, sil = setup()
    boot = {"STORED": 0, "MIGRATED": 1, "EMPTY": 2, "CORRUPT": 3}
    flash = os.path.join(args.work, "drive.flash")
    SPEED_MAX, CURRENTS_HZ = 123.5, 50
    id_speed, id_cur = sil.pid["speed_max_rad_s"], sil.pid["tm_currents_hz"]
    read_both = [sil.frame(0.10, "PARAM_REQ", opcode=0, param_id=id_speed, value=0),
                 sil.frame(0.11, "PARAM_REQ", opcode=0, param_id=id_cur, value=0)]

    # 1. write, apply, save on a new flash file
    r, s, fr = sil.run("run1", [
        sil.frame(0.10, "PARAM_REQ", opcode=1, param_id=id_speed, value=f32_bits(SPEED_MAX)),
        sil.frame(0.11, "PARAM_REQ", opcode=1, param_id=id_cur, value=CURRENTS_HZ),
        sil.frame(0.12, "PARAM_REQ", opcode=2, param_id=0, value=0),
        sil.frame(0.13, "PARAM_REQ", opcode=3, param_id=0, value=0)], flash=flash)
    rep = replies(fr)
    assert [x["opcode"] for x in rep] == [1, 1, 2, 3], rep
    assert all(x["status"] == 0 for x in rep), rep
    assert rep[3]["value"] == 1, rep  # SAVE: record sequence number
    assert s["cfg_boot_status"] == "EMPTY" and s["cfg_saves"] == 1, s
    # the heartbeat reports the store: EMPTY until the SAVE at 0.13 s, then
    # STORED (the first heartbeat after it is at most one period, 0.1 s, later)
    hb = [(t, v["cfg_status"]) for t, n, v in fr if n == "HEARTBEAT"]
    before, after = [c for t, c in hb if t < 0.13], [c for t, c in hb if t > 0.13]
    assert before and set(before) == {boot["EMPTY"]}, hb
    assert after and set(after) == {boot["STORED"]}, hb
    assert os.path.getsize(flash) == 32768
    assert not os.path.exists(flash + ".tmp")
    print("run 1: EMPTY, write/apply/save OK, seq 1, the heartbeat STORED after the save")

    # 2. the next run boots with it
    r, s, fr = sil.run("run2", read_both + [
        sil.frame(0.15, "SET_CONTROL_MODE", control_mode=2),
        sil.frame(0.16, "SET_ENABLE", enable=1),
        sil.frame(0.17, "SET_SPEED_REF", omega_ref_rad_s=SPEED_MAX + 10.0),
        sil.frame(0.18, "SET_SPEED_REF", omega_ref_rad_s=SPEED_MAX - 10.0),
        sil.frame(0.19, "SET_ENABLE", enable=0)], flash=flash)
    assert s["cfg_boot_status"] == "STORED", s
    assert s["cfg_boot_code"] == boot["STORED"] and s["cfg_store_seq"] == 1, s
    assert set(s["cfg_from_store"].split(",")) == {str(id_speed), str(id_cur)}, s
    assert cfg_status(fr) == boot["STORED"]
    rep = replies(fr)
    assert [(x["param_id"], x["status"]) for x in rep] == [(id_speed, 0), (id_cur, 0)], rep
    assert bits_f32(rep[0]["value"]) == SPEED_MAX and rep[1]["value"] == CURRENTS_HZ, rep
    t_cur = [t for t, n, _ in fr if n == "CURRENTS"]
    rate = (len(t_cur) - 1) / (t_cur[-1] - t_cur[0])
    assert abs(rate - CURRENTS_HZ) < 1.0, rate
    errs = [x for _, n, x in fr if n == "CMD_ERROR"]
    spd_id = sil.db.get_message_by_name("SET_SPEED_REF").frame_id & 0x1F
    assert [e["rejected_cmd"] for e in errs] == [spd_id], errs
    print("run 2: STORED, read back %.1f rad/s and %d Hz, limit in force" % (SPEED_MAX, CURRENTS_HZ))

    # 3. a flipped byte inside the record
    img = bytearray(Path(flash).read_bytes())
    img[4 * 5] ^= 0x01  # first entry's value word, inside the CRC
    Path(flash).write_bytes(img)
    r, s, fr = sil.run("run3", read_both, flash=flash)
    assert s["cfg_boot_status"] == "CORRUPT" and s["cfg_from_store"] == "", s
    assert "CORRUPT" in r.stderr and flash in r.stderr, r.stderr
    assert cfg_status(fr) == boot["CORRUPT"]
    rep = replies(fr)
    assert bits_f32(rep[0]["value"]) == 150.0 and rep[1]["value"] == 200, rep  # scenario's
    assert Path(flash).read_bytes() == bytes(img)  # booting writes nothing
    print("run 3: CORRUPT, scenario's settings, file untouched")

    # 4. refusals: exit 2, the file named, nothing written
    bad = os.path.join(args.work, "short.flash")
    Path(bad).write_bytes(b"\xff" * 1000)
    r, _, _ = sil.run("run4", [], flash=bad, expect_rc=2)
    assert r.stderr.startswith("mcsim: " + bad + ": ") and "1000" in r.stderr, r.stderr
    assert not os.path.exists(os.path.join(args.work, "run4"))
    assert Path(bad).read_bytes() == b"\xff" * 1000
    r = subprocess.run([args.mcsim, "run", "foc-current-step", "--out",
                        os.path.join(args.work, "run5"), "--flash", flash],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "has no flash" in r.stderr, r.stderr
    r, _, _ = sil.run("run6", [], flash=flash, extra=["--set", "rate_heartbeat_hz=500"],
                      expect_rc=2)
    assert "valid parameter set" in r.stderr, r.stderr
    print("refusals: wrong size, scenario without flash, settings outside the table")

    # 5. without --flash: the service runs, SAVE has no store
    r, s, fr = sil.run("run7", [sil.frame(0.10, "PARAM_REQ", opcode=3, param_id=0, value=0)])
    rep = replies(fr)
    assert [(x["opcode"], x["status"]) for x in rep] == [(3, 7)], rep
    assert "cfg_boot_status" not in s and cfg_status(fr) == boot["EMPTY"], s
    print("no --flash: SAVE answers STORE")
    return 0


if __name__ == "__main__":
    sys.exit(main())
