#!/usr/bin/env python3
"""`mdtool calibrate --cogging` against a simulated drive on the bus its
subprocess uses (the `logbus` plugin of tests/can/logbus.py: every frame
mdtool sends is read here from PREFIX.tx.log; the drive's side, played by
this test, is encoded with cantools from the DBC, independently of mdtool's
codec). The drive's parameter service answers READ / WRITE / APPLY / SAVE
for anticogging (180), cog_status (181), cog_cal_status (183) and
cfg_pending (203) as firmware/app/app/mc_app.c does; its calibration runs on
a compressed clock (a phase every few tenths of a second), with POSITION
frames turning the angle.

Checked, each with the exit code, the named failure on stderr and the
frames mdtool sent:
- success: the progress to 100 % / 1024 angle points each way, DISABLE, then
  WRITE anticogging 1 and APPLY; SAVE only with --save;
- each named failure of cog_cal_status (NO_OFFSET, ROTOR_BLOCKED, MEAS,
  MAP_IMPLAUSIBLE_AMPLITUDE, MAP_IMPLAUSIBLE_DISAGREE, ABORTED, the
  builder's MAP_IMPLAUSIBLE_AMPLITUDE): exit 5, DISABLE the last frame, no
  anticogging 1 written, no SAVE; with a map in use before, anticogging 1
  written back after DISABLE (the drive set 0);
- the refusals before it runs (FAULT, BUSY, PENDING: exit 4, nothing but
  READs sent; the drive refusing SPEED for an unknown angle: NO_OFFSET,
  exit 4, DISABLE last; APPLY refused: NOT_READY, anticogging written back);
- a calibration that never ends: CAL_TIMEOUT, exit 3, DISABLE last;
- READs of cog_cal_status left unanswered: two in a row are sent again
  (the run ends 0), four in a row exit 3 with DISABLE last;
- replies that are not the drive's answer: PARAM_REPLYs of another node,
  for another parameter and of a wrong length are ignored (the run still
  ends on the drive's own DONE, not before), a cog_cal_status no drive
  sends is named and exits 1 with DISABLE last;
- bad options send nothing (exit 2), each with a control that sends;
- the tool's copy of the firmware's constants equals the C headers'.

    test_mdtool_cogging.py --work DIR
"""
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)

import cantools  # noqa: E402
import logbus  # noqa: E402

from mdtool.can import cogging  # noqa: E402  (logbus put tools/mdtool/src on the path)

DBC = os.path.join(ROOT, "tools", "can", "motordrive.dbc")
db = cantools.database.load_file(DBC)
NODE = 1

#: the fake's calibration: each phase's length [s] on its compressed clock
SCHEDULE = [(1, 0.15), (2, 0.6), (3, 0.15), (4, 0.6), (5, 0.15)]
DONE, FAILED = 6, 7


check = logbus.check


def msg_of(can_id):
    for m in db.messages:
        if (m.frame_id & 0x1F) == (can_id & 0x1F):
            return m
    return None


def names(prefix):
    out = []
    for fr in logbus.sent(prefix):
        m = msg_of(fr[2])
        out.append(m.name if m else f"0x{fr[2]:03X}")
    return out


def param_reqs(prefix):
    """(opcode, param_id, value) of every PARAM_REQ sent."""
    m = db.get_message_by_name("PARAM_REQ")
    out = []
    for fr in logbus.sent(prefix):
        if (fr[2] & 0x1F) == (m.frame_id & 0x1F):
            v = m.decode(fr[3], decode_choices=False)
            out.append((int(v["opcode"]), int(v["param_id"]), int(v["value"])))
    return out


class FakeDrive(threading.Thread):
    """The drive's side. script: ok | fail:<err bits> | builder:<st> | hang |
    malformed | foreign | refuse_apply; start: idle | enabled | fault |
    pending | angle_unknown. fail_at: the phase in which a failure is
    reported (NO_OFFSET at once, BLOCKED during the forward turn, ...)."""

    def __init__(self, prefix, script="ok", start="idle", fail_at=2, anticogging=0):
        super().__init__(daemon=True)
        self.prefix, self.script, self.start_state, self.fail_at = prefix, script, start, fail_at
        self.stop = threading.Event()
        self.seq = 0
        self.params = {180: anticogging, 181: 0 if anticogging else 1, 183: 0,
                       203: 1 if start == "pending" else 0}
        self.staged_cog = anticogging
        self.cal_t0 = None
        self.cal_end_t = None
        self.reads_183 = 0  # READs of cog_cal_status since the APPLY

    def emit(self, name, node=NODE, **vals):
        m = db.get_message_by_name(name)
        logbus.reply(self.prefix, (node << 5) | (m.frame_id & 0x1F), m.encode(vals))

    def reply(self, op, pid, status=0, value=0, node=NODE):
        self.emit("PARAM_REPLY", node=node, opcode=op, param_id=pid, status=status, value=value)

    def cal_status(self, now):
        """cog_cal_status from the time since APPLY (the schedule)."""
        if self.cal_t0 is None:
            return self.params[183]
        t = now - self.cal_t0
        if self.script.startswith("fail:") and self.fail_at == 0:
            return FAILED | int(self.script[5:], 0) << 8
        for phase, dur in SCHEDULE:
            if self.script == "hang" and phase == 2:
                return phase
            if self.script.startswith("fail:") and phase == self.fail_at and t > dur / 2:
                return FAILED | int(self.script[5:], 0) << 8
            if t < dur:
                return phase
            t -= dur
        if self.script.startswith("builder:"):
            return FAILED | int(self.script[8:], 0) << 16
        return DONE

    def theta(self, now):
        """The mechanical angle: a turn forward in REC_FWD, back in REC_REV."""
        if self.cal_t0 is None:
            return 0.0
        t = now - self.cal_t0 - SCHEDULE[0][1]
        fwd = min(max(t, 0.0), SCHEDULE[1][1]) / SCHEDULE[1][1]
        t -= SCHEDULE[1][1] + SCHEDULE[2][1]
        rev = min(max(t, 0.0), SCHEDULE[3][1]) / SCHEDULE[3][1]
        return 2.0 * math.pi * 1.01 * (fwd - rev)

    def on_param(self, op, pid, value, now, enabled, control):
        if op == 0:  # READ
            if pid == 183 and self.cal_t0 is not None:
                self.reads_183 += 1
                # drop: the 2nd and 3rd unanswered (a lost frame, a request
                # not served); mute: none answered after the 2nd
                if (self.script == "drop" and self.reads_183 in (2, 3)) or \
                        (self.script == "mute" and self.reads_183 >= 2):
                    return
            if pid not in self.params:
                self.reply(op, pid, status=1)
                return
            v = self.cal_status(now) if pid == 183 else self.params[pid]
            if pid == 183 and self.script == "malformed" and self.cal_t0 is not None \
                    and now - self.cal_t0 > 0.4:
                v = 0x09  # a phase beyond FAILED: no drive sends it
            if pid == 183 and self.script == "foreign" and self.cal_t0 is not None:
                # what is not the answer comes first: another node's DONE,
                # another parameter's reply carrying 6, a frame of a wrong length
                self.reply(0, 183, value=DONE, node=NODE + 1)
                self.reply(0, 181, value=DONE)
                logbus.reply(self.prefix, (NODE << 5) | 25, bytes([0, 183, 0, 0]))
            self.reply(op, pid, value=v)
        elif op == 1:  # WRITE
            if pid != 180 or value > 2:
                self.reply(op, pid, status=2 if pid in self.params else 1)
                return
            self.staged_cog = value
            self.params[203] = 1
            self.reply(op, pid, value=value)
        elif op == 2:  # APPLY
            if self.staged_cog == 2 and (self.script == "refuse_apply" or not enabled or control != 2):
                self.reply(op, 0, status=6, value=1 << 20)
                return
            self.params[203] = 0
            if self.staged_cog == 2:
                self.cal_t0 = now
                self.params[180] = 2
            else:
                self.params[180] = self.staged_cog
            self.reply(op, 0)
        elif op == 3:  # SAVE
            self.reply(op, 0, value=7)

    def run(self):
        control, enabled, seen = 0, 1 if self.start_state == "enabled" else 0, 0
        req = db.get_message_by_name("PARAM_REQ")
        while not self.stop.is_set():
            now = time.monotonic()
            frames = logbus.sent(self.prefix)
            for fr in frames[seen:]:
                m = msg_of(fr[2])
                if m is None:
                    continue
                if m.name == "SET_CONTROL_MODE":
                    control = fr[3][0]
                elif m.name == "SET_ENABLE":
                    if self.start_state == "angle_unknown":
                        self.emit("CMD_ERROR", rejected_cmd=0x10, error=12, rx_len=1, seq=self.seq)
                    else:
                        enabled = fr[3][0]
                elif m.name == "DISABLE":
                    enabled = 0
                elif m.name == "PARAM_REQ":
                    v = req.decode(fr[3], decode_choices=False)
                    self.on_param(int(v["opcode"]), int(v["param_id"]), int(v["value"]), now,
                                  enabled, control)
            seen = len(frames)
            st = self.cal_status(now)
            if self.cal_t0 is not None and (st & 0xFF) in (DONE, FAILED) and self.cal_end_t is None:
                self.cal_end_t = now
                self.params[180] = 1 if (st & 0xFF) == DONE else 0
                self.params[181] = 0 if (st & 0xFF) == DONE else self.params[181]
                self.params[183] = st
            fault = self.start_state == "fault"
            mode = 2 if fault else (3 if enabled else 0)
            self.seq = (self.seq + 1) & 0xFF
            self.emit("HEARTBEAT", mode=mode, control_mode=control, enabled=enabled, stopping=0,
                      can_state=0, stop_reason=0, cfg_status=0, faults=0x10 if fault else 0,
                      last_error=0, last_error_cmd=0, seq=self.seq)
            self.emit("POSITION", theta_m_rad=self.theta(now), theta_e_rad=0.0, sat=0, seq=self.seq)
            time.sleep(0.01)


class Bus:
    def __init__(self, work, env):
        self.prefix = logbus.new_prefix(work)
        self.env = env

    def popen(self, *argv):
        return subprocess.Popen([sys.executable, "-m", "mdtool.cli", "calibrate", *argv, "--interface",
                                 "logbus", "--channel", self.prefix, "--node", str(NODE)],
                                env=self.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def run(self, *argv, drive=None, timeout=120):
        if drive is not None:
            drive.start()
        try:
            t0 = time.monotonic()
            p = self.popen(*argv)
            out, err = p.communicate(timeout=timeout)
            return p.returncode, out, err, time.monotonic() - t0
        finally:
            if drive is not None:
                drive.stop.set()
                drive.join(5)


def success_checks(work, env):
    for save in (False, True):
        b = Bus(work, env)
        d = FakeDrive(b.prefix)
        rc, out, err, _dt = b.run("--cogging", *(["--save"] if save else []), drive=d)
        sent = names(b.prefix)
        reqs = param_reqs(b.prefix)
        i_dis = sent.index("DISABLE") if "DISABLE" in sent else -1
        after = param_reqs_after(b.prefix, i_dis)
        want_after = [(1, 180, 1), (2, 0, 0), (0, 181, 0)] + ([(3, 0, 0)] if save else [])
        check(rc == 0 and "map in use" in out and i_dis > 0 and after == want_after
              and sent.count("DISABLE") == 1 and (1, 180, 2) in reqs,
              f"success{' --save' if save else ''}: exit {rc}, after DISABLE {after} (want "
              f"{want_after}); '{err.strip()[-200:]}'")
        # the last progress line: the whole map seen both ways (by construction
        # exact: DONE sets every bin)
        lines = [ln for ln in out.splitlines() if " % " in ln]
        check(bool(lines) and lines[-1].split()[:6] == ["pass", f"{cogging.CAL_PASSES}/{cogging.CAL_PASSES}",
                                                         "done", "100", "%", "angle"]
              and "1024/1024 forward" in lines[-1] and "1024/1024 back" in lines[-1],
              f"  progress ends at 100 %, 1024 points each way: {lines[-1] if lines else None!r}")
        # between: the forward turn seen part-done (a line with 0 < points < 1024)
        part = [ln for ln in lines if "forward turn" in ln and "/1024 forward" in ln
                and 0 < int(ln.split("points")[1].split("/")[0]) < 1024]
        check(len(part) >= 1, f"  progress during the forward turn: {len(part)} part-done lines")
        check(("saved with the configuration (record 7)" in out) == save,
              f"  SAVE {'sent and reported' if save else 'not sent'} ('{out.strip().splitlines()[-1]}')")


def param_reqs_after(prefix, idx):
    m = db.get_message_by_name("PARAM_REQ")
    out = []
    for fr in logbus.sent(prefix)[idx + 1:]:
        if (fr[2] & 0x1F) == (m.frame_id & 0x1F):
            v = m.decode(fr[3], decode_choices=False)
            out.append((int(v["opcode"]), int(v["param_id"]), int(v["value"])))
    return out


def failure_checks(work, env):
    cases = [("fail:0x02", 0, "NO_OFFSET"), ("fail:0x04", 2, "ROTOR_BLOCKED"), ("fail:0x08", 4, "MEAS"),
             ("fail:0x10", 5, "MAP_IMPLAUSIBLE_AMPLITUDE"), ("fail:0x20", 5, "MAP_IMPLAUSIBLE_DISAGREE"),
             ("fail:0x40", 2, "ABORTED"), ("builder:6", 0, "MAP_IMPLAUSIBLE_AMPLITUDE")]
    for script, at, name in cases:
        b = Bus(work, env)
        rc, _out, err, _dt = b.run("--cogging", "--save", drive=FakeDrive(b.prefix, script, fail_at=at))
        sent = names(b.prefix)
        reqs = param_reqs(b.prefix)
        check(rc == 5 and f"{name} (" in err and sent[-1:] == ["DISABLE"] and (1, 180, 1) not in reqs
              and not any(r[0] == 3 for r in reqs),
              f"{script} (phase {at}): exit {rc} (want 5), named {name}, DISABLE last "
              f"({sent[-1:]}), no anticogging 1, no SAVE: '{err.strip()[-160:]}'")
    # with a map in use before (anticogging 1): the drive sets 0 on the
    # failure; mdtool writes 1 back (after DISABLE), still exit 5, no SAVE
    b = Bus(work, env)
    rc, _out, err, _dt = b.run("--cogging", "--save", drive=FakeDrive(b.prefix, "fail:0x04", anticogging=1))
    sent = names(b.prefix)
    after = param_reqs_after(b.prefix, sent.index("DISABLE") if "DISABLE" in sent else len(sent))
    check(rc == 5 and "ROTOR_BLOCKED (" in err and "anticogging back to 1 (cog_status 0)" in err
          and after == [(1, 180, 1), (2, 0, 0), (0, 181, 0)],
          f"failure with a map in use before: exit {rc}, after DISABLE {after}: '{err.strip()[-120:]}'")


def refusal_checks(work, env):
    for start, want in (("fault", "FAULT:"), ("enabled", "BUSY:"), ("pending", "PENDING:")):
        b = Bus(work, env)
        rc, _out, err, _dt = b.run("--cogging", drive=FakeDrive(b.prefix, start=start))
        sent = names(b.prefix)
        reads_only = all(r[0] == 0 for r in param_reqs(b.prefix)) and set(sent) <= {"PARAM_REQ"}
        check(rc == 4 and want in err and reads_only,
              f"refused, drive {start}: exit {rc} (want 4), '{want}', only READs sent ({sent})")
    b = Bus(work, env)
    rc, _out, err, _dt = b.run("--cogging", drive=FakeDrive(b.prefix, start="angle_unknown"))
    sent = names(b.prefix)
    check(rc == 4 and "NO_OFFSET:" in err and sent[-1:] == ["DISABLE"] and "PARAM_REQ" not in sent[-3:],
          f"refused, angle unknown at enable: exit {rc}, NO_OFFSET, DISABLE last: '{err.strip()[-120:]}'")
    b = Bus(work, env)
    rc, _out, err, _dt = b.run("--cogging", drive=FakeDrive(b.prefix, script="refuse_apply"))
    reqs = param_reqs(b.prefix)
    check(rc == 4 and "NOT_READY:" in err and names(b.prefix)[-1:] == ["DISABLE"]
          and reqs[-2:] == [(2, 0, 0), (1, 180, 0)],
          f"APPLY refused: exit {rc}, NOT_READY, anticogging written back to 0, DISABLE last ({reqs[-2:]})")


def apply_to_disable_s(prefix):
    """Seconds from the APPLY that started the calibration to the DISABLE,
    both stamped by the logbus as mdtool sent them (its process start and
    imports, seconds on a loaded machine, are not in it)."""
    t_apply = t_dis = None
    req = db.get_message_by_name("PARAM_REQ")
    for fr in logbus.sent(prefix):
        m = msg_of(fr[2])
        if m is req and t_apply is None and int(req.decode(fr[3], decode_choices=False)["opcode"]) == 2:
            t_apply = fr[0]
        if m is not None and m.name == "DISABLE" and t_dis is None:
            t_dis = fr[0]
    return None if t_apply is None or t_dis is None else t_dis - t_apply


def timeout_and_foreign_checks(work, env):
    b = Bus(work, env)
    rc, _out, err, _dt = b.run("--cogging", "--cal-timeout", "1.5", drive=FakeDrive(b.prefix, "hang"))
    dt = apply_to_disable_s(b.prefix)
    # at least the timeout (its clock starts at the APPLY's reply); at most
    # 1.5 s more: the APPLY's reply on the fake's 10 ms loop and the follow
    # loop's 20 ms checks, with a wide margin for this loaded machine
    check(rc == 3 and "CAL_TIMEOUT" in err and names(b.prefix)[-1:] == ["DISABLE"]
          and dt is not None and 1.5 <= dt <= 3.0,
          f"never ends: exit {rc} (want 3), APPLY to DISABLE {dt} s (1.5 s asked), CAL_TIMEOUT, DISABLE last")
    b = Bus(work, env)
    rc, out, err, _dt = b.run("--cogging", drive=FakeDrive(b.prefix, "foreign"))
    dt = apply_to_disable_s(b.prefix)
    total = sum(t for _p, t in SCHEDULE)
    # the drive's own DONE comes only after its schedule; a foreign DONE
    # (another node's, or another parameter's 6) taken would end the run at
    # the first poll, well under it
    check(rc == 0 and dt is not None and dt >= total and "map in use" in out,
          f"foreign replies ignored: exit {rc}, APPLY to DISABLE {dt} s (the schedule takes {total:.2f} s): "
          f"'{err.strip()[-160:]}'")
    b = Bus(work, env)
    d = FakeDrive(b.prefix, "drop")
    rc, out, err, _dt = b.run("--cogging", drive=d)
    check(rc == 0 and "map in use" in out and d.reads_183 >= 4,
          f"two READs unanswered in a row: sent again, exit {rc} ({d.reads_183} READs): '{err.strip()[-120:]}'")
    b = Bus(work, env)
    d = FakeDrive(b.prefix, "mute")
    rc, _out, err, _dt = b.run("--cogging", "--timeout", "0.3", drive=d)
    check(rc == 3 and "no PARAM_REPLY to 4 READs of cog_cal_status" in err and d.reads_183 == 5
          and names(b.prefix)[-1:] == ["DISABLE"],
          f"the drive falls silent: exit {rc} (want 3) after {d.reads_183} READs (1 answered, 4 not), "
          f"DISABLE last: '{err.strip()[-120:]}'")
    b = Bus(work, env)
    rc, _out, err, _dt = b.run("--cogging", drive=FakeDrive(b.prefix, "malformed"))
    check(rc == 1 and "is not a value the drive sends" in err and names(b.prefix)[-1:] == ["DISABLE"],
          f"malformed cog_cal_status: exit {rc} (want 1), named, DISABLE last: '{err.strip()[-160:]}'")
    # SIGTERM while it runs: DISABLE last, 143
    b = Bus(work, env)
    d = FakeDrive(b.prefix, "hang")
    d.start()
    try:
        p = b.popen("--cogging")
        t_end = time.monotonic() + 30
        while time.monotonic() < t_end and (0, 183, 0) not in param_reqs(b.prefix)[3:] and p.poll() is None:
            time.sleep(0.02)
        time.sleep(0.3)
        p.send_signal(signal.SIGTERM)
        _out, err = p.communicate(timeout=30)
    finally:
        d.stop.set()
        d.join(5)
    check(p.returncode == 143 and names(b.prefix)[-1:] == ["DISABLE"],
          f"SIGTERM during the calibration: exit {p.returncode}, DISABLE last")


def usage_checks(work, env):
    for bad, why in ((["--cogging", "--cal-timeout", "1e6"], "--cal-timeout: 1e6 is outside"),
                     (["--cogging", "--cal-timeout", "0"], "--cal-timeout: 0 is outside"),
                     (["--cogging", "--i-test", "5"], "takes no --i-test")):
        b = Bus(work, env)
        rc, _out, err, _dt = b.run(*bad)
        check(rc == 2 and why in err and names(b.prefix) == [],
              f"usage {' '.join(bad)}: exit {rc}, nothing sent ({len(names(b.prefix))} frames)")
    b = Bus(work, env)  # control: a valid timeout sends (and runs to the end)
    rc, _out, _err, _dt = b.run("--cogging", "--cal-timeout", "60", drive=FakeDrive(b.prefix))
    check(rc == 0 and names(b.prefix)[:1] == ["PARAM_REQ"], f"  control --cal-timeout 60: exit {rc}")


def define(path, name):
    with open(os.path.join(ROOT, path)) as f:
        m = re.search(rf"#define {name}\s+\(?([0-9.]+)[uf]?", f.read())
    return float(m.group(1)) if m else None


def constants_check():
    app, comm, drv = ("firmware/app/app/mc_app.h", "firmware/app/commission/mc_comm_cog.h",
                      "firmware/app/drive/mc_drive_cog.h")
    pairs = [(app, "MC_APP_COG_CAL_SPEED_RAD_S", cogging.CAL_SPEED_RAD_S),
             (app, "MC_APP_COG_CAL_RAMP_S", cogging.CAL_RAMP_S),
             (app, "MC_APP_COG_CAL_SETTLE_S", cogging.CAL_SETTLE_S),
             (app, "MC_APP_COG_CAL_PASSES", cogging.CAL_PASSES),
             (app, "MC_APP_COG_BOUND_FRAC", cogging.BOUND_FRAC),
             (comm, "MC_COMM_COG_TIME_FACTOR", cogging.TIME_FACTOR),
             (comm, "MC_COMM_COG_MARGIN_BINS", cogging.MARGIN_BINS),
             (drv, "MC_COG_N", cogging.COG_N)]
    for path, name, mine in pairs:
        c = define(path, name)
        check(c == mine, f"constant {name} = {c} in {path}, mdtool's {mine}")
    # the pass in bits 24..31 (mc_app.c): the last pass decodes, one beyond is no drive's
    last = (cogging.CAL_PASSES - 1) << 24
    check(cogging.decode(last | 2) == ("REC_FWD", []) and cogging.pass_of(last | 2) == cogging.CAL_PASSES - 1,
          "cog_cal_status of the last pass decodes")
    try:
        cogging.decode((cogging.CAL_PASSES << 24) | 2)
        check(False, "a pass beyond the last is refused")
    except cogging.ProtocolError:
        check(True, "a pass beyond the last is refused")
    for path, name, bit in ((comm, "MC_COMM_COG_ERR_NO_OFFSET", 0x02), (comm, "MC_COMM_COG_ERR_BLOCKED", 0x04),
                            (comm, "MC_COMM_COG_ERR_MEAS", 0x08), (comm, "MC_COMM_COG_ERR_AMPLITUDE", 0x10),
                            (comm, "MC_COMM_COG_ERR_DISAGREE", 0x20), (comm, "MC_COMM_COG_ERR_ABORTED", 0x40)):
        with open(os.path.join(ROOT, path)) as f:
            m = re.search(rf"#define {name}\s+\(1u << (\d+)\)", f.read())
        check(m is not None and 1 << int(m.group(1)) == bit and bit in cogging.ERRORS,
              f"error bit {name} = {bit:#x} in mdtool's table")


def main():
    work, env = logbus.work_and_env()
    constants_check()
    usage_checks(work, env)
    success_checks(work, env)
    failure_checks(work, env)
    refusal_checks(work, env)
    timeout_and_foreign_checks(work, env)
    return logbus.summary("mdtool calibrate --cogging checks")


if __name__ == "__main__":
    sys.exit(main())
