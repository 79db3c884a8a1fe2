#!/usr/bin/env python3
"""What `mdtool` sends, observed on the bus its subprocess uses (the
`logbus` python-can plugin of tests/can/logbus.py: every frame the
subprocess sends is in PREFIX.tx.log before its send returns; the drive's
side is played by this test through PREFIX.rx.log, its frames encoded with
cantools from the DBC, independently of mdtool's codec):

- a value refused before sending sends nothing: `run speed 1e6` / nan,
  `--keepalive 0`, `--duration -1` / 1e300, `--settle 0`, `--id nan`,
  `config set r_ohm=1e9`, `config load /dev/zero` / an empty file, an
  unwritable `config export` file, `calibrate --i-test 1e6`. Each of these
  checks has a control: the same command with a valid value, whose frames
  the same observer sees (so the check fails when something is sent);
- `run` sends DISABLE last on every way out: the end (exit 0), the drive
  faulting (4), enable refused (4), no reply (3), not settled (3), SIGTERM
  (143) and SIGINT (130) sent to the subprocess while it runs, and a DISABLE
  the bus refuses to carry is reported (exit 1), never silently;
- `calibrate` interrupted by SIGTERM sends ABORT.

    test_mdtool_bus.py --work DIR
"""
import os
import signal
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import cantools  # noqa: E402
import logbus  # noqa: E402

DBC = os.path.join(HERE, "..", "..", "tools", "can", "motordrive.dbc")
db = cantools.database.load_file(DBC)
NODE = 1


check = logbus.check


def cmd_name(can_id):
    for m in db.messages:
        if (m.frame_id & 0x1F) == (can_id & 0x1F):
            return m.name
    return f"0x{can_id:03X}"


def names(prefix):
    return [cmd_name(fr[2]) for fr in logbus.sent(prefix)]


class Bus:
    """One bus (a PREFIX) and the mdtool subprocesses on it."""
    def __init__(self, work, env):
        self.prefix = logbus.new_prefix(work)
        self.env = env

    def args(self):
        return ["--interface", "logbus", "--channel", self.prefix, "--node", str(NODE)]

    def popen(self, *argv, extra_env=None):
        env = dict(self.env, **(extra_env or {}))
        return subprocess.Popen([sys.executable, "-m", "mdtool.cli", *argv, *self.args()], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def run(self, *argv, extra_env=None, timeout=120):
        p = self.popen(*argv, extra_env=extra_env)
        out, err = p.communicate(timeout=timeout)
        return p.returncode, out, err

    def sent(self):
        return names(self.prefix)


class FakeDrive(threading.Thread):
    """The drive's side: a HEARTBEAT every 10 ms that follows the commands
    mdtool sent (control mode, enabled), SPEED frames at `speed`; optionally
    a fault once enabled, or a CMD_ERROR refusing SET_ENABLE."""

    def __init__(self, prefix, fault=False, refuse_enable=False, speed=0.0, no_params=False):
        super().__init__(daemon=True)
        self.prefix, self.fault, self.refuse_enable, self.speed = prefix, fault, refuse_enable, speed
        self.no_params = no_params  # PARAM_REQ answered CMD_ERROR UNSUPPORTED (no parameter service)
        self.stop = threading.Event()
        self.seq = 0

    def emit(self, name, **vals):
        m = db.get_message_by_name(name)
        logbus.reply(self.prefix, (NODE << 5) | (m.frame_id & 0x1F), m.encode(vals))

    def run(self):
        control, enabled, seen, refused = 0, 0, 0, False
        while not self.stop.is_set():
            frames = logbus.sent(self.prefix)
            for fr in frames[seen:]:
                name = cmd_name(fr[2])
                if name == "SET_CONTROL_MODE":
                    control = fr[3][0]
                elif name == "SET_ENABLE":
                    if self.refuse_enable and not refused:
                        self.emit("CMD_ERROR", rejected_cmd=0x10, error=4, rx_len=1, seq=self.seq)
                        refused = True
                    else:
                        enabled = fr[3][0]
                elif name == "DISABLE":
                    enabled = 0
                elif name == "PARAM_REQ" and self.no_params:
                    self.emit("CMD_ERROR", rejected_cmd=0x18, error=7, rx_len=8, seq=self.seq)
            seen = len(frames)
            mode = 2 if (self.fault and enabled) else (3 if enabled else 0)
            self.seq = (self.seq + 1) & 0xFF
            self.emit("HEARTBEAT", mode=mode, control_mode=control, enabled=enabled, stopping=0,
                      can_state=0, stop_reason=0, cfg_status=0, faults=0x10 if mode == 2 else 0,
                      last_error=0, last_error_cmd=0, seq=self.seq)
            self.emit("SPEED", omega_m_rad_s=self.speed, omega_ref_rad_s=0.0, sat=0, seq=self.seq)
            time.sleep(0.01)


def with_drive(bus, fn, **kw):
    drive = FakeDrive(bus.prefix, **kw)
    drive.start()
    try:
        return fn()
    finally:
        drive.stop.set()
        drive.join(5)


def nothing_sent_checks(work, env):
    """Each refused command sends nothing; its control sends frames."""
    empty = os.path.join(work, "empty.toml")
    open(empty, "w").close()
    one = os.path.join(work, "one.toml")
    with open(one, "w") as f:
        f.write("[motor]\nr_ohm = 0.5\n")
    t = ["--timeout", "0.3"]
    cases = [
        # (refused argv, what stderr says, control argv, the control's first frame, its exit code)
        (["run", "speed", "1e6"], "outside [-10000, 10000]",
         ["run", "speed", "20", "--duration", "0.05"], "SET_CONTROL_MODE", 0),
        (["run", "speed", "nan"], "not a finite number",
         ["run", "speed", "20", "--duration", "0.05"], "SET_CONTROL_MODE", 0),
        (["run", "speed", "20", "--keepalive", "0"], "--keepalive: 0 is outside [0.01, 1] s",
         ["run", "speed", "20", "--keepalive", "0.01", "--duration", "0.05"], "SET_CONTROL_MODE", 0),
        (["run", "speed", "20", "--duration", "-1"], "--duration: -1 is outside [0, 86400] s",
         ["run", "speed", "20", "--duration", "0"], "SET_CONTROL_MODE", 0),
        (["run", "speed", "20", "--duration", "1e300"], "--duration: 1e300 is outside",
         ["run", "speed", "20", "--duration", "0.05"], "SET_CONTROL_MODE", 0),
        (["run", "speed", "20", "--settle", "0"], "a tolerance > 0",
         ["run", "speed", "0", "--settle", "0.5", "--duration", "0"], "SET_CONTROL_MODE", 0),
        (["run", "current", "1", "--id", "nan"], "i_d_ref_a=nan: not a finite number",
         ["run", "current", "1", "--id", "0", "--duration", "0.05"], "SET_CONTROL_MODE", 0),
        (["config", "set", "r_ohm=1e9", *t], "outside its range [0.0, 100.0] ohm",
         ["config", "set", "r_ohm=0.5", *t], "PARAM_REQ", 3),
        (["config", "load", "/dev/zero", *t], "/dev/zero: more than 1048576 bytes",
         ["config", "load", one, *t], "PARAM_REQ", 3),
        (["config", "load", empty, *t], "no parameter in it",
         ["config", "load", one, *t], "PARAM_REQ", 3),
        (["config", "export", os.path.join(work, "no", "such", "x.toml"), *t], "no folder",
         ["config", "export", os.path.join(work, "x.toml"), *t], "PARAM_REQ", 3),
        (["calibrate", "--i-test", "1e6", *t], "COMMISSION_CMD.i_test_a=1000000.0 outside",
         ["calibrate", "--i-test", "5", *t], "PARAM_REQ", 3),
    ]
    for bad, why, good, first, good_rc in cases:
        b = Bus(work, env)
        rc, _out, err = b.run(*bad)
        frames = b.sent()
        check(rc == 2 and why in err and frames == [],
              f"mdtool {' '.join(bad)}: exit {rc}, {len(frames)} frames on its bus, '{err.strip()}'")
        g = Bus(work, env)
        rc, _out, err = with_drive(g, lambda g=g, good=good: g.run(*good))
        frames = g.sent()
        check(rc == good_rc and frames[:1] == [first],
              f"  control: mdtool {' '.join(good)}: exit {rc}, its bus carried "
              f"{', '.join(frames[:4])}{' ...' if len(frames) > 4 else ''} ({len(frames)} frames)"
              + (f" '{err.strip()}'" if rc != good_rc else ""))


def disable_checks(work, env):
    """DISABLE is the last frame of `run` on every way out."""
    def last_is_disable(b, what, rc, want_rc, err, expect=""):
        frames = b.sent()
        check(rc == want_rc and frames[-1:] == ["DISABLE"] and expect in err,
              f"run, {what}: exit {rc} (want {want_rc}), {len(frames)} frames, the last "
              f"{frames[-1] if frames else None}: '{err.strip()[-160:]}'")
        return frames

    b = Bus(work, env)
    rc, out, err = with_drive(b, lambda: b.run("run", "speed", "20", "--duration", "0.3"))
    frames = last_is_disable(b, "the end", rc, 0, err)
    check(frames.count("DISABLE") == 1 and "SET_SPEED_REF" in frames and "HOST_HEARTBEAT" in frames
          and "ran speed 20" in out, "run's frames: mode, enable, keep-alive, setpoint, one DISABLE")
    b = Bus(work, env)
    rc, _out, err = with_drive(b, lambda: b.run("run", "speed", "20", "--duration", "5"), fault=True)
    last_is_disable(b, "the drive faults", rc, 4, err, "the drive faulted")
    b = Bus(work, env)
    rc, _out, err = with_drive(b, lambda: b.run("run", "speed", "20", "--duration", "5"),
                               refuse_enable=True)
    last_is_disable(b, "enable refused", rc, 4, err, "refused SET_ENABLE: MODE")
    b = Bus(work, env)
    rc, _out, err = b.run("run", "speed", "20", "--timeout", "0.3")
    frames = last_is_disable(b, "no drive answers", rc, 3, err, "no HEARTBEAT in control mode SPEED")
    check(frames == ["SET_CONTROL_MODE", "DISABLE"], f"  no reply: only the mode and DISABLE ({frames})")
    b = Bus(work, env)
    rc, _out, err = with_drive(b, lambda: b.run("run", "speed", "20", "--duration", "0.1", "--settle",
                                                "0.5", "--settle-timeout", "0.3"))
    last_is_disable(b, "never settles", rc, 3, err, "did not settle")
    for sig, want in ((signal.SIGTERM, 143), (signal.SIGINT, 130)):
        b = Bus(work, env)

        def interrupted(b=b, sig=sig):
            p = b.popen("run", "speed", "20", "--duration", "60")
            t_end = time.monotonic() + 60
            while time.monotonic() < t_end and "SET_SPEED_REF" not in b.sent() and p.poll() is None:
                time.sleep(0.02)
            time.sleep(0.2)  # inside the hold loop, keep-alives going out
            p.send_signal(sig)
            out, err = p.communicate(timeout=60)
            return p.returncode, out, err
        rc, _out, err = with_drive(b, interrupted)
        frames = last_is_disable(b, f"{sig.name} while running", rc, want, err, f"interrupted by {sig.name}")
        check(frames.count("SET_SPEED_REF") >= 2, f"  {sig.name} came during the hold "
              f"({frames.count('SET_SPEED_REF')} setpoints sent before it)")
    # The bus refuses DISABLE (a full transmit queue, bus off): said, exit 1.
    b = Bus(work, env)
    rc, _out, err = with_drive(b, lambda: b.run("run", "speed", "20", "--duration", "0.1",
                                                extra_env={"MC_LOGBUS_REFUSE_CMDS": "0x00"}))
    frames = b.sent()
    check(rc == 1 and "DISABLE could not be sent" in err and "DISABLE" not in frames,
          f"run, DISABLE refused by the bus: exit {rc}, '{err.strip()[-160:]}'")


def calibrate_abort_check(work, env):
    b = Bus(work, env)

    def interrupted():
        p = b.popen("calibrate", "--timeout", "0.3", "--progress-timeout", "60")
        t_end = time.monotonic() + 60
        while time.monotonic() < t_end and "COMMISSION_CMD" not in b.sent() and p.poll() is None:
            time.sleep(0.02)
        time.sleep(0.2)
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=60)
        return p.returncode, out, err
    rc, _out, err = with_drive(b, interrupted, no_params=True)
    frames = logbus.sent(b.prefix)
    cmds = [fr[3][0] for fr in frames if cmd_name(fr[2]) == "COMMISSION_CMD"]
    check(rc == 143 and cmds == [1, 0] and cmd_name(frames[-1][2]) == "COMMISSION_CMD",
          f"calibrate, SIGTERM while it runs: exit {rc}, COMMISSION_CMD actions {cmds} "
          f"(START then ABORT, the last frame): '{err.strip()[-120:]}'")


def main():
    work, env = logbus.work_and_env()
    nothing_sent_checks(work, env)
    disable_checks(work, env)
    calibrate_abort_check(work, env)
    return logbus.summary("mdtool bus checks")


if __name__ == "__main__":
    sys.exit(main())
