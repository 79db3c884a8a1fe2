"""The drive over any python-can bus (socketcan, slcan, pcan, virtual, ...):
heartbeats, commands, the parameter service (PARAM_REQ / PARAM_REPLY) and a
run with the keep-alive sent for you.

Every wait has a timeout (NoReply); a refusal carries the drive's reason
decoded from the DBC (PARAM_REPLY.status, CMD_ERROR.error).
"""
import math
import time

from .dbc import CMD_MASK, by_cmd, cmd_of, decode_signals, encode_signals, frame_id, node_of
from .errors import CanToolError, NoReply, Refused, UsageError

OPS = {"READ": 0, "WRITE": 1, "APPLY": 2, "SAVE": 3, "LOAD_DEFAULTS": 4, "CONFIRM": 5}
#: What a PARAM_REPLY status means (firmware/app/config/README.md).
STATUS_HELP = {
    "UNKNOWN_ID": "no parameter with this id on the drive",
    "READONLY": "the parameter is computed by the drive",
    "RANGE": "value out of range or not finite",
    "RUNNING": "not while the bridge is on: disable the drive first",
    "FAULT": "a fault is latched: clear it first",
    "INVALID": "the staged set fails validation as a whole",
    "STORE": "the drive has no parameter store (or writing it failed)",
    "OPCODE": "unknown operation",
    "NEEDS_CONFIRM": "a new node id or bit rate needs PARAM_REQ CONFIRM as the very next request",
    "NOT_CONFIRMED": "CONFIRM without its WRITE right before it (or another value, or too late)",
    "RATE_LIMIT": "SAVE is rate-limited (4, then one per 120 s)",
}
ERROR_HELP = {"UNSUPPORTED": "this drive does not offer it (e.g. no parameter service attached)",
              "LIMITED": "not served: the drive's reply rate limit (wait for each reply)"}


def named(msg, vals):
    """Signal values with the DBC's names for enumerated ones."""
    out = {}
    for s in msg.signals:
        v = vals[s.name]
        if s.choices and int(v) in s.choices:
            out[s.name] = str(s.choices[int(v)])
        elif s.scale == 1 and s.offset == 0 and not s.is_float:
            out[s.name] = int(v)
        else:
            out[s.name] = v
    return out


class Drive:
    def __init__(self, bus, db, node=1, timeout=1.0):
        self.bus, self.db, self.node, self.timeout = bus, db, node, timeout
        self.table = by_cmd(db)
        self.hb_counter = 0
        frame_id(node, 0)

    # -------------------------------------------------------------- frames
    def frame(self, name, **values):
        """The can.Message of `name` for our node (UsageError for a value
        the DBC cannot carry: nothing is sent)."""
        import can
        msg = self.db.get_message_by_name(name)
        data = encode_signals(msg, values)
        return can.Message(arbitration_id=frame_id(self.node, cmd_of(msg)), data=data,
                           is_extended_id=False)

    def send(self, name, **values):
        self.bus.send(self.frame(name, **values))

    def disable(self, attempts=3):
        """Send DISABLE (cmd 0x00), with SIGINT and SIGTERM held off while it
        goes out (a second Ctrl-C must not stop it half-way) and up to
        `attempts` tries on a bus error (a full transmit queue). CanToolError
        when it could not be sent: the drive then stops only on its own
        command timeout (can_timeout_s)."""
        import signal
        import threading
        main = threading.current_thread() is threading.main_thread()
        held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM}) if main else None
        try:
            for k in range(attempts):
                try:
                    self.send("DISABLE")
                    return
                except Exception as e:  # python-can raises CanError or OSError
                    if k == attempts - 1:
                        raise CanToolError(
                            f"DISABLE could not be sent to node {self.node} ({e}): the drive may "
                            f"still be enabled until its command timeout (can_timeout_s) stops it") from e
                    time.sleep(0.01)
        finally:
            if main:
                signal.pthread_sigmask(signal.SIG_SETMASK, held)

    def decode(self, m, node=None, names=True):
        """(message name, values) of a frame of `node` (default: ours), else
        None. Enumerated signals carry their DBC names, unless names=False
        (every value a number, e.g. to plot it)."""
        if m is None or m.is_extended_id or m.is_error_frame or m.is_remote_frame:
            return None
        if node_of(m.arbitration_id) != (self.node if node is None else node):
            return None
        msg = self.table.get(m.arbitration_id & CMD_MASK)
        if msg is None or len(m.data) != msg.length:
            return None
        vals = decode_signals(msg, m.data)
        return msg.name, (named(msg, vals) if names else vals)

    def wait_for(self, pred, timeout, what):
        """The first decoded frame of our node for which pred(name, values)
        holds; CMD_ERROR frames for `what`'s command raise Refused."""
        t_end = time.monotonic() + timeout
        while True:
            left = t_end - time.monotonic()
            if left <= 0:
                raise NoReply(f"no {what} from node {self.node} within {timeout:g} s "
                              f"(is the drive on this bus, with this node id and bit rate?)")
            d = self.decode(self.bus.recv(min(left, 0.1)))
            if d is None:
                continue
            if pred(*d):
                return d

    def check_cmd_error(self, name, vals, cmd_name):
        if name == "CMD_ERROR":
            rejected = self.table.get(int(vals["rejected_cmd"]))
            if rejected is not None and rejected.name == cmd_name:
                err = vals["error"]
                raise Refused(f"the drive refused {cmd_name}: {err}"
                              + (f" ({ERROR_HELP[err]})" if err in ERROR_HELP else ""), status=err)

    # ---------------------------------------------------------- heartbeats
    def heartbeat(self, timeout=None):
        return self.wait_for(lambda n, v: n == "HEARTBEAT", timeout or self.timeout, "HEARTBEAT")[1]

    def host_heartbeat(self):
        self.send("HOST_HEARTBEAT", counter=self.hb_counter)
        self.hb_counter = (self.hb_counter + 1) & 0xFF

    # ------------------------------------------------------------ params
    def param(self, op, pid=0, raw=0, timeout=None):
        """One PARAM_REQ; returns the reply's raw value, or raises Refused
        with the drive's reason, NoReply after the timeout."""
        self.send("PARAM_REQ", opcode=OPS[op], param_id=pid, value=raw)

        def match(name, vals):
            self.check_cmd_error(name, vals, "PARAM_REQ")
            return name == "PARAM_REPLY" and vals["opcode"] == op and int(vals["param_id"]) == pid
        _n, vals = self.wait_for(match, timeout or self.timeout, f"PARAM_REPLY to {op}")
        if vals["status"] != "OK":
            st = vals["status"]
            why = STATUS_HELP.get(st, "") + (f"; {int(vals['value'])} s to wait" if st == "RATE_LIMIT" else "")
            raise Refused(f"the drive refused {op}: {st}" + (f" ({why})" if why else ""),
                          status=st, value=int(vals["value"]))
        return int(vals["value"])

    # --------------------------------------------------------------- run
    def run(self, mode, setpoint, duration, i_d=0.0, period=0.05, on_frame=None,
            settle=None, settle_timeout=30.0, settle_frames=3):
        """Select `mode` (current: setpoint = i_q [A]; speed: rad/s), enable,
        hold the setpoint for `duration` s with the keep-alive every
        `period` s, then disable. Returns the last heartbeat seen.

        Every argument is checked, and every frame of the run encoded, before
        the first frame is sent (UsageError: nothing sent): mode, setpoint
        and i_d within their DBC signals and finite, `duration` and `period`
        and `settle_timeout` within RUN_LIMITS. Once the first frame is out,
        DISABLE is sent on every way out: the end, a refusal, a fault, no
        reply, an exception, Ctrl-C or SIGTERM (Interrupted).

        With `settle` (same unit as the setpoint), hold on after `duration`
        until `settle_frames` telemetry frames in a row (SPEED.omega_m_rad_s
        or CURRENTS.i_q_a) lie within `settle` of the setpoint, for at most
        `settle_timeout` s more; then disable. Not settled by then: NoReply
        (the drive is disabled all the same). The criterion counts frames, not
        seconds, so it holds however slowly the drive's clock runs against
        this host's (a simulated drive on a busy machine)."""
        mode = mode.upper()
        if mode not in ("CURRENT", "SPEED", "POSITION"):
            raise UsageError(f"mode {mode.lower()!r}: current, speed or position")
        if settle is not None and not (settle > 0 and math.isfinite(settle)):
            raise UsageError(f"settle {settle!r}: a tolerance > 0")
        for name, v in (("duration", duration), ("keepalive", period), ("settle_timeout", settle_timeout)):
            check_limit(name, v)
        code = {"CURRENT": 1, "SPEED": 2, "POSITION": 3}[mode]
        meas = {"SPEED": ("SPEED", "omega_m_rad_s"), "CURRENT": ("CURRENTS", "i_q_a"),
                "POSITION": ("POSITION", "theta_m_rad")}[mode]
        # every frame of the run, encoded now: a setpoint the DBC cannot carry
        # (1e6 rad/s, nan) is refused before anything reaches the bus
        try:
            if mode == "CURRENT":
                ref_frame = self.frame("SET_CURRENT_REF", i_d_ref_a=i_d, i_q_ref_a=setpoint)
            elif mode == "SPEED":
                ref_frame = self.frame("SET_SPEED_REF", omega_ref_rad_s=setpoint)
            else:  # multi-turn target [rad], in POSITION.theta_m_rad's frame
                ref_frame = self.frame("SET_POSITION_REF", theta_ref_rad=setpoint)
        except UsageError as e:
            raise UsageError(f"{mode.lower()} setpoint refused: {e}; nothing sent") from None
        mode_frame = self.frame("SET_CONTROL_MODE", control_mode=code)
        enable_frame = self.frame("SET_ENABLE", enable=1)
        self.frame("DISABLE")
        last_hb = None
        self.last_measured = None
        inside = 0
        try:
            self.bus.send(mode_frame)
            self.wait_for(lambda n, v: self.check_cmd_error(n, v, "SET_CONTROL_MODE") or
                          (n == "HEARTBEAT" and v["control_mode"] == mode), self.timeout,
                          f"HEARTBEAT in control mode {mode}")
            # a reference is refused while disabled (it would be a step on
            # enable): enable starts from the present state, then the setpoint
            self.bus.send(enable_frame)
            self.host_heartbeat()
            self.bus.send(ref_frame)
            t0 = time.monotonic()
            t_next = t0

            def holding():
                el = time.monotonic() - t0
                if el < duration:
                    return True
                if settle is None or inside >= settle_frames:
                    return False
                if el < duration + settle_timeout:
                    return True
                raise NoReply(f"{meas[0]}.{meas[1]} did not settle within {settle:g} of {setpoint:g} "
                              f"in {duration + settle_timeout:g} s (last {self.last_measured})")
            while holding():
                now = time.monotonic()
                if now >= t_next:
                    self.host_heartbeat()
                    self.bus.send(ref_frame)
                    t_next = now + period
                d = self.decode(self.bus.recv(max(0.0, min(t_next - time.monotonic(), 0.02))))
                if d is None:
                    continue
                name, vals = d
                for c in ("SET_ENABLE", "SET_CURRENT_REF", "SET_SPEED_REF", "SET_POSITION_REF"):
                    self.check_cmd_error(name, vals, c)
                if name == "HEARTBEAT":
                    last_hb = vals
                    if vals["mode"] == "FAULT":
                        raise Refused(f"the drive faulted (faults 0x{vals['faults']:04X})", status="FAULT")
                if name == meas[0]:
                    self.last_measured = vals[meas[1]]
                    inside = inside + 1 if abs(vals[meas[1]] - setpoint) <= (settle or 0.0) else 0
                if on_frame:
                    on_frame(name, vals)
        finally:
            self.disable()
        return last_hb


#: Bounds of `run`'s times [s] (lowest, highest): the keep-alive period at
#: least 10 ms (HOST_HEARTBEAT and the setpoint: 200 frames/s, 2.7 % of a
#: 1 Mbit/s bus at 135 bits a frame) and at most 1 s (below the drive's
#: command timeout: keep it under half of can_timeout_s, default 0.5 s); a
#: run of up to a day; a settle hold of up to an hour.
RUN_LIMITS = {"duration": (0.0, 86400.0), "keepalive": (0.01, 1.0), "settle_timeout": (0.0, 3600.0)}


def check_limit(name, v, limits=RUN_LIMITS):
    """UsageError unless v is a finite number within limits[name]."""
    lo, hi = limits[name]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and lo <= v <= hi):
        raise UsageError(f"{name} {v!r}: a number of seconds in [{lo:g}, {hi:g}]")
    return v


def scan(bus, db, timeout=1.0):
    """{node: heartbeat values} of every node whose HEARTBEAT arrives within timeout."""
    hb = db.get_message_by_name("HEARTBEAT")
    found = {}
    t_end = time.monotonic() + timeout
    while True:
        left = t_end - time.monotonic()
        if left <= 0:
            return found
        m = bus.recv(min(left, 0.1))
        if m is None or m.is_extended_id or m.is_error_frame or len(m.data) != hb.length:
            continue
        if m.arbitration_id & CMD_MASK == cmd_of(hb):
            found[node_of(m.arbitration_id)] = named(hb, decode_signals(hb, m.data))
