#!/usr/bin/env python3
"""Telemetry for any motor, through the real firmware (mcsim run
can-telemetry --motor FILE --board FILE) and two host decoders: cantools on
the DBC, and `mdtool decode` (the CLI, CSV per message). The motor is the
ODrive D5065 (270 KV, 65 A; sim/motors/odrive-d5065.toml) on the ODrive
v3.6 56 V board (sim/motors/odrive-v36-56v.toml): the 60 A class whose 40 A
version 1 logged as 16.382 A and whose 1290 rad/s it logged as 655.34 rad/s.

 1. a current step to 40 A (CURRENT mode; a flywheel of 0.05 kg m^2 on the
    shaft keeps the rotor slow): CURRENT_REFS carries 40.000 A, CURRENTS the
    measured 40 A, both decoders give the SIL's value to half a step, the
    measured current is the plant's, every sat bit is clear;
 2. a speed step to 1290 rad/s (SPEED mode, the motor's own rotor, PWM at
    48 kHz: see speed_step for why not the board's 24 kHz): SPEED
    carries it (both decoders to half a step, the plant's speed), sat clear;
    the multi-turn POSITION follows the plant's angle over 100+ turns in the
    same run (4 turns between two POSITION frames at 50 Hz);
 3. a reference past a signal's range: SET_SPEED_REF 9000 rad/s (allowed by
    speed_max_rad_s 9000; SPEED's 24-bit field ends at 8388.607 rad/s):
    SPEED.omega_ref_rad_s is sent clamped at 8388.607 with sat = 1 (a wrap
    would read -7777.216), and the drive counts the frames
    (tm_frames_saturated);
 4. the host falls silent at 200 rad/s in SPEED mode: the command timeout's
    controlled stop never turns the rotor backwards (speed_timeout_stop).

    test_sil_any_motor.py --mcsim MCSIM --work DIR --repo ROOT
"""
import csv
import itertools
import os
import subprocess
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_sil_flash import report, setup

fails = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)


def rows_of(out):
    with open(os.path.join(out, "can-telemetry.csv")) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


SLOT = {"CURRENTS": 1, "SPEED": 3, "POSITION": 4, "CURRENT_REFS": 8}


def mdtool_decode(repo, log, out):
    """`mdtool decode LOG --out DIR` (this tree's package): {message: [row]}."""
    src = os.path.join(repo, "tools", "mdtool", "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")])))
    r = subprocess.run([sys.executable, "-m", "mdtool.cli", "decode", log, "--out", out],
                       capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    got = {}
    for name in SLOT:
        path = os.path.join(out, name + ".csv")
        if os.path.exists(path):
            with open(path) as f:
                got[name] = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return got


def against_sil(name, rows, cantools_frames, md_rows, db):
    """Each decoded frame of `name` (cantools and mdtool decode) against the
    SIL's value for it (the CSV row where the frame was generated, in order).
    Tolerance: half the signal's step (the packer rounds to nearest) plus
    1e-6 relative (float32 arithmetic of the firmware's packer), the DBC's
    clamp applied to the SIL value (the packer saturates). Returns the
    (row, cantools values) pairs."""
    sent = [r for r in rows if (int(r["tm_sent_mask"]) >> SLOT[name]) & 1]
    ct = [v for _t, n, v in cantools_frames if n == name]
    md = md_rows.get(name, [])
    check(len(ct) == len(sent) == len(md),
          f"{name}: {len(sent)} frames generated, cantools {len(ct)}, mdtool decode {len(md)}")
    msg = db.get_message_by_name(name)
    worst = 0.0
    for row, a, b in zip(sent, ct, md, strict=False):  # lengths checked above
        for s in msg.signals:
            want = min(max(row[f"{name}.{s.name}"], s.minimum), s.maximum)
            tol = 0.5 * s.scale + 1e-6 * max(1.0, abs(want))
            for who, got in (("cantools", a[s.name]), ("mdtool", b[s.name])):
                err = abs(got - want)
                worst = max(worst, err / tol)
                if err > tol:
                    check(False, f"{name}.{s.name} at {row['t']:.4f} s: {who} {got!r}, SIL {want!r}")
                    return list(zip(sent, ct, strict=False))
    check(worst <= 1.0, f"{name}: {len(ct)} frames, both decoders within half a step of the SIL "
          f"(worst {worst:.3f} x tolerance)")
    return list(zip(sent, ct, strict=False))


def motor_args(repo):
    # The 56 V board's description (odrive36) gives a 48 V nominal supply:
    # the bus at 52 V, as this test's speeds need, below the version's 56 V
    # limit (the drive's trip there: vbus_board_max_v; its divider reads
    # 62.7 V).
    return ["--motor", os.path.join(repo, "sim", "motors", "odrive-d5065.toml"),
            "--board", os.path.join(repo, "sim", "motors", "odrive-v36-56v.toml"),
            "--set", "board.vbus_v=52"]


def current_step(sil, repo):
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=1),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.10, "SET_CURRENT_REF", i_d_ref_a=0.0, i_q_ref_a=40.0),
            sil.frame(0.45, "SET_CURRENT_REF", i_d_ref_a=0.0, i_q_ref_a=0.0)]
    cmds += [sil.frame(0.1 * k + 0.005, "HOST_HEARTBEAT", counter=k) for k in range(1, 6)]
    # a flywheel on the shaft: 40 A x 0.0307 N m/A accelerates 0.05 kg m^2 at
    # 25 rad/s^2, so the run stays far from the voltage limit
    _r, s, frames = sil.run("current", sorted(cmds), duration=0.5,
                            extra=motor_args(repo) + ["--set", "motor.j_kgm2=0.05"])
    out = os.path.join(sil.work, "current")
    rows = rows_of(out)
    md = mdtool_decode(repo, os.path.join(sil.work, "current.can.log"), os.path.join(out, "md"))
    cur = against_sil("CURRENTS", rows, frames, md, sil.db)
    refs = against_sil("CURRENT_REFS", rows, frames, md, sil.db)
    step = [v["i_q_ref_a"] for r, v in refs if 0.11 <= r["t"] <= 0.45]
    check(step and all(abs(x - 40.0) <= 0.0005 for x in step),
          f"CURRENT_REFS.i_q_ref_a during the step: {sorted(set(step))[:3]} (40 A to half a mA)")
    # the measured current after the rise (10-90 % in about 1 ms at the
    # derived 1920 rad/s bandwidth; from 20 ms on): the 12-bit +-80 A sensor's
    # 39 mA step and the current loop's residual error against the rising
    # back-EMF stay below 0.2 A; the plant's current at the same tick (the
    # firmware's sample is half a period older) within 0.5 A
    held = [(r, v) for r, v in cur if 0.12 <= r["t"] <= 0.44]
    err_ref = max(abs(v["i_q_a"] - 40.0) for _r, v in held)
    err_true = max(abs(v["i_q_a"] - r["i_q_true_a"]) for r, v in held)
    check(err_ref <= 0.2, f"CURRENTS.i_q_a during the step within {err_ref:.3f} A of 40 A (<= 0.2 A)")
    check(err_true <= 0.5, f"CURRENTS.i_q_a within {err_true:.3f} A of the plant's i_q (<= 0.5 A)")
    sat = [(n, t) for t, n, v in frames if n in SLOT and v["sat"] != 0]
    check(not sat and s["tm_frames_saturated"] == 0,
          f"sat bits clear (frames with sat: {sat[:3]}, drive count {s['tm_frames_saturated']})")
    check(s["final_faults"] == 0 and s["cmd_rejected"] == 0,
          f"faults {s['final_faults']}, rejected commands {s['cmd_rejected']}")
    print(f"current step: 40 A logged as {min(v['i_q_a'] for _r, v in held):.3f} .. "
          f"{max(v['i_q_a'] for _r, v in held):.3f} A ({len(held)} CURRENTS frames)")


def speed_step(sil, repo):
    w_ref = 1290.0
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=2),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.07, "SET_SPEED_REF", omega_ref_rad_s=w_ref),
            sil.frame(1.20, "SET_SPEED_REF", omega_ref_rad_s=9000.0),
            sil.frame(1.24, "SET_SPEED_REF", omega_ref_rad_s=w_ref)]
    cmds += [sil.frame(0.1 * k + 0.005, "HOST_HEARTBEAT", counter=k) for k in range(1, 14)]
    # motor.speed_max_rad_s: the library file's 650 rad/s is this motor on
    # the 24 V board (270 KV x 24 V = 679 rad/s no-load); on 56 V it turns
    # 1583 rad/s no-load, and the drive's overspeed trip is 1.5x this value.
    # speed_max_rad_s 9000: the CAN limit, so that item 3's reference passes
    # the command check and reaches the telemetry. speed_ramp_rad_s2 4100:
    # the speed reference's ramp (what 20 A gives the bare rotor).
    # board.pwm_hz 48000: at the board's 24 kHz the firmware's current loop,
    # which does not compensate the rotation of the rotor frame during its
    # one-period computation delay (1.5 omega_e T = 0.56 rad at 1290 rad/s
    # and 7 pole pairs), oscillates from about 1000 rad/s and trips
    # OVERCURRENT (measured: 1030 rad/s); at 48 kHz the angle is halved.
    _r, s, frames = sil.run("speed", sorted(cmds), duration=1.4,
                            extra=motor_args(repo) + ["--set", "board.pwm_hz=48000",
                                                      "--set", "motor.speed_max_rad_s=1400",
                                                      "--set", "speed_max_rad_s=9000",
                                                      "--set", "speed_ramp_rad_s2=4100"])
    out = os.path.join(sil.work, "speed")
    rows = rows_of(out)
    md = mdtool_decode(repo, os.path.join(sil.work, "speed.can.log"), os.path.join(out, "md"))
    spd = against_sil("SPEED", rows, frames, md, sil.db)
    pos = against_sil("POSITION", rows, frames, md, sil.db)
    held = [(r, v) for r, v in spd if 0.8 <= r["t"] <= 1.2]
    check(held and all(abs(v["omega_ref_rad_s"] - w_ref) <= 0.0005 for _r, v in held),
          "SPEED.omega_ref_rad_s carries 1290 rad/s to half a step")
    # the encoder tracking loop's speed at 1290 rad/s: the 8192-count encoder
    # moves 35 counts per 48 kHz period, so its quantisation is 3 % of a
    # period's step, which the PLL (1000 rad/s) averages to well under 0.5 %;
    # the speed PI holds the reference to the same (no load but the
    # 1e-5 N m s/rad friction)
    err = max(abs(v["omega_m_rad_s"] - w_ref) for _r, v in held)
    err_true = max(abs(v["omega_m_rad_s"] - r["omega_m_true_rad_s"]) for r, v in held)
    check(err <= 0.005 * w_ref, f"SPEED.omega_m_rad_s within {err:.3f} rad/s of 1290 (<= 0.5 %)")
    check(err_true <= 0.005 * w_ref,
          f"SPEED.omega_m_rad_s within {err_true:.3f} rad/s of the plant's speed (<= 0.5 %)")
    # multi-turn position: the encoder angle sampled at the start of the PWM
    # period against the plant's at its end: one period of rotation
    # (1290 / 48000 = 0.027 rad; 1.5x for the speed's overshoot above the
    # reference) plus one count (7.7e-4 rad) and float32's 6e-8 relative
    th = [(r, v) for r, v in pos if r["t"] <= 1.2]
    turns = th[-1][1]["theta_m_rad"] / 6.283185307179586
    tol = 1.5 * 1290.0 / 48000.0 + 7.7e-4
    err_th = max(abs(v["theta_m_rad"] - r["theta_m_true_rad"]) - 6e-8 * abs(r["theta_m_true_rad"])
                 for r, v in th)
    check(turns > 100, f"POSITION multi-turn: {turns:.1f} turns by 1.2 s")
    check(err_th <= tol, f"POSITION.theta_m_rad within {err_th:.4f} rad of the plant's angle "
          f"over {turns:.0f} turns (<= {tol:.4f} rad)")
    steps = [b[1]["theta_m_rad"] - a[1]["theta_m_rad"] for a, b in itertools.pairwise(th)]
    check(max(steps) > 4 * 6.283, f"the angle moved {max(steps) / 6.283:.2f} turns between frames")
    sat_ok = [(r, v) for r, v in spd + pos if r["t"] < 1.2]
    check(all(v["sat"] == 0 for _r, v in sat_ok), "sat clear in SPEED and POSITION up to 1.2 s")

    # 3. past the range: clamped at the end of the range, sat set, not wrapped
    over = [v for r, v in spd if 1.205 <= r["t"] <= 1.235]
    top = 8388.607
    check(len(over) >= 2 and all(abs(v["omega_ref_rad_s"] - top) <= 0.0005 and v["sat"] == 1
                                 for v in over),
          f"9000 rad/s sent as {[v['omega_ref_rad_s'] for v in over]} with sat "
          f"{[v['sat'] for v in over]} (clamped at {top}, sat 1)")
    check(s["tm_frames_saturated"] >= len(over),
          f"the drive counted {s['tm_frames_saturated']} saturated frames ({len(over)} seen)")
    after = [v for r, v in spd if r["t"] >= 1.25]
    check(after and all(v["sat"] == 0 for v in after), "sat clear again once the reference fits")
    check(s["final_faults"] == 0 and s["cmd_rejected"] == 0,
          f"faults {s['final_faults']}, rejected commands {s['cmd_rejected']}")
    print(f"speed step: 1290 rad/s logged within {err:.3f} rad/s; {turns:.0f} turns tracked to "
          f"{err_th * 1e3:.1f} mrad; 9000 rad/s sent as {over[0]['omega_ref_rad_s'] if over else None}")


def speed_timeout_stop(sil, repo):
    """The host falls silent while the rotor turns at 200 rad/s in SPEED
    mode: the drive's controlled stop ramps the speed law's reference to 0
    at stop_decel_rad_s2 and opens the bridge at rest. It never turns the
    rotor backwards (before the rule, a stop like this one drove a U8-class
    rotor to -18.7 rad/s): the bridge opens in the PWM period whose encoder
    speed crosses zero, so the plant's speed goes below zero by at most two
    periods of the deceleration (the period of the crossing, the one its
    current still acts in)."""
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=2),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.07, "SET_SPEED_REF", omega_ref_rad_s=200.0)]
    cmds += [sil.frame(0.1 * k + 0.005, "HOST_HEARTBEAT", counter=k) for k in range(1, 5)]
    _r, s, _frames = sil.run("speed_timeout", sorted(cmds), duration=1.5,
                             extra=motor_args(repo))
    rows = rows_of(os.path.join(sil.work, "speed_timeout"))
    t_last = 0.405  # the last heartbeat
    before = [r["omega_m_true_rad_s"] for r in rows if 0.3 <= r["t"] <= t_last]
    check(before and min(before) > 190.0, f"at speed before the silence: {min(before):.1f} rad/s")
    check(s["final_stop_reason"] == 1 and s["final_mode"] == 0 and s["final_faults"] == 0,
          f"stopped for CMD_TIMEOUT in IDLE without a fault: reason {s['final_stop_reason']}, "
          f"mode {s['final_mode']}, faults {s['final_faults']}")
    decel = s["param.stop_decel_rad_s2"]
    # the board file names the description (odrive36): its PWM rate
    with open(os.path.join(repo, "firmware", "targets", "stm32f405", "boards", "odrive36",
                           "board.toml"), "rb") as f:
        pwm_hz = tomllib.load(f)["pwm"]["frequency_hz"]
    bound = 2.0 * decel / pwm_hz
    back = max(-r["omega_m_true_rad_s"] for r in rows if r["t"] >= t_last)
    check(decel > 0.0 and back <= bound,
          f"largest backward speed during the stop {back:.4f} rad/s (<= 2 decel T = {bound:.4f})")
    print(f"speed timeout stop from 200 rad/s at {decel:.0f} rad/s^2: backward {back:.4f} rad/s")


def main():
    args, sil = setup()
    current_step(sil, args.repo)
    speed_step(sil, args.repo)
    speed_timeout_stop(sil, args.repo)
    return report(fails)


if __name__ == "__main__":
    sys.exit(main())
