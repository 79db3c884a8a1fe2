"""A python-can bus on two candump files, shared between processes, so a
test sees every frame a `mdtool` subprocess sends (python-can's `virtual`
bus does not cross processes: a listener in the test process never sees a
subprocess's frames, so a "nothing sent" check on it cannot fail).

Channel PREFIX: the process's frames are appended to PREFIX.tx.log, one
candump -L line each, written and flushed in `send` before it returns; the
frames it receives are read from PREFIX.rx.log as lines are appended to it
(by the test, playing the drive's side).

The bus is a python-can plugin (entry point group `can.interface`, name
`logbus`): `plugin_env(DIR)` writes a distribution's metadata into DIR and
returns the environment in which an unmodified `python -m mdtool.cli ...
--interface logbus --channel PREFIX` finds it, exactly as python-can finds
an installed interface package.
"""
import argparse
import os
import shutil
import sys
import time

import can

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "mdtool", "src")
sys.path.insert(0, os.path.normpath(SRC))

from mdtool.can.log import format_candump_line, parse_candump_line  # noqa: E402

POLL_S = 0.002  # how often recv looks for new lines of PREFIX.rx.log
#: Command ids (low 5 bits) whose frames `send` refuses with a CanOperationError,
#: as a bus that cannot transmit would: MC_LOGBUS_REFUSE_CMDS="0x00" (DISABLE).
_REFUSE = {int(c, 0) for c in os.environ.get("MC_LOGBUS_REFUSE_CMDS", "").split(",") if c}


class LogBus(can.BusABC):
    def __init__(self, channel, **kwargs):
        self.prefix = str(channel)
        self._tx = open(self.prefix + ".tx.log", "a", encoding="ascii")  # noqa: SIM115 (closed in shutdown)
        self._rx_path = self.prefix + ".rx.log"
        self._rx = None
        self._partial = ""
        super().__init__(channel=channel, **kwargs)
        self.channel_info = f"logbus {self.prefix}"

    def send(self, msg, timeout=None):
        if (msg.arbitration_id & 0x1F) in _REFUSE:
            raise can.CanOperationError(f"logbus: frame 0x{msg.arbitration_id:03X} refused "
                                        "(MC_LOGBUS_REFUSE_CMDS)")
        self._tx.write(format_candump_line(time.time(), "logbus", msg.arbitration_id,
                                           bytes(msg.data)) + "\n")
        self._tx.flush()

    def _next_line(self):
        if self._rx is None:
            if not os.path.exists(self._rx_path):
                return None
            self._rx = open(self._rx_path, encoding="ascii")  # noqa: SIM115 (closed in shutdown)
        got = self._rx.readline()
        if not got:
            return None
        self._partial += got
        if not self._partial.endswith("\n"):
            return None  # the writer is half-way through a line: the rest comes later
        line, self._partial = self._partial, ""
        return line

    def _recv_internal(self, timeout):
        t_end = None if timeout is None else time.monotonic() + timeout
        while True:
            line = self._next_line()
            fr = parse_candump_line(line) if line else None
            if fr is not None:
                t_s, _iface, can_id, data, flags = fr
                return can.Message(timestamp=t_s, arbitration_id=can_id, data=data,
                                   is_extended_id="ext" in flags, is_rx=True), False
            if line:
                continue  # a comment or a blank line
            left = None if t_end is None else t_end - time.monotonic()
            if left is not None and left <= 0:
                return None, False
            time.sleep(POLL_S if left is None else min(POLL_S, left))

    def shutdown(self):
        self._tx.close()
        if self._rx is not None:
            self._rx.close()
        super().shutdown()


#: the checks that failed in this process (check)
FAILS = []
_buses = [0]


def check(ok, what):
    """One check of a test script: printed, and kept in FAILS when it fails."""
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        FAILS.append(what)


def summary(name):
    """The script's last line and exit status from FAILS."""
    print(f"{name}: {'FAILED: ' + str(len(FAILS)) if FAILS else 'passed'}")
    return 1 if FAILS else 0


def new_prefix(work):
    """A fresh bus (its PREFIX) under the work folder."""
    _buses[0] += 1
    return os.path.join(work, f"bus{_buses[0]:02d}")


def work_and_env():
    """The common start of the scripts that run mdtool on this bus: the
    --work folder emptied, and the environment whose python-can knows
    `logbus` (plugin_env)."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    return a.work, plugin_env(os.path.join(a.work, "plugin"))


def plugin_env(folder, env=None):
    """The environment for a subprocess whose python-can knows `logbus`."""
    dist = os.path.join(folder, "mc_logbus-0.dist-info")
    os.makedirs(dist, exist_ok=True)
    with open(os.path.join(dist, "METADATA"), "w") as f:
        f.write("Metadata-Version: 2.1\nName: mc-logbus\nVersion: 0\n")
    with open(os.path.join(dist, "entry_points.txt"), "w") as f:
        f.write("[can.interface]\nlogbus = logbus:LogBus\n")
    env = dict(os.environ if env is None else env)
    here = os.path.dirname(os.path.abspath(__file__))
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [folder, here, os.path.normpath(SRC),
                                                      env.get("PYTHONPATH")]))
    return env


def sent(prefix):
    """Every frame the process on PREFIX sent: (t_s, iface, id, data, flags)."""
    path = prefix + ".tx.log"
    if not os.path.exists(path):
        return []
    with open(path, encoding="ascii") as f:
        return [fr for fr in (parse_candump_line(ln) for ln in f) if fr is not None]


def reply(prefix, can_id, data):
    """Append one frame to what the process on PREFIX receives."""
    with open(prefix + ".rx.log", "a", encoding="ascii") as f:
        f.write(format_candump_line(time.time(), "logbus", can_id, bytes(data)) + "\n")
