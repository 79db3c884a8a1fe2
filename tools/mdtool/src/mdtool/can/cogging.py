"""The anticogging calibration over CAN (`mdtool calibrate --cogging`).

The drive runs it (firmware/app/commission/mc_comm_cog.h, driven by
firmware/app/app/mc_app.c): with the drive enabled in SPEED at rest and its
angle known, the parameter `anticogging` (180) = 2 applied starts a turn
forward and a turn back at MC_APP_COG_CAL_SPEED_RAD_S under the drive's own
speed loop, MC_APP_COG_CAL_PASSES times (each pass after the first runs
on the map of the one before and learns what it left); the parameter
`cog_cal_status` (183) tells the phase (bits 0..7), the MC_COMM_COG_ERR_*
bits of a refusal (8..15), the map builder's MC_COG_ST_* refusal (16..23)
and the pass (24..31, 0 first). When it ends the drive runs with
`anticogging` 1 and the new map (0 when refused); SAVE stores the map with
the configuration.

The host's part (calibrate_cogging): check what it can read first (the
drive idle and without a fault, no calibration running, no written value
waiting for APPLY: the APPLY that starts the calibration would apply it
too), enable SPEED at 0, start, follow cog_cal_status with the keep-alive,
DISABLE on every way out, and on success set anticogging 1 (APPLY) and
with `save` SAVE; on a named failure the anticogging value of before is
written back (the drive sets 0; its map is unchanged, or, when a later
pass failed, the map of the pass before it, which that pass ran on).

The constants below mirror the firmware's (tests/can/test_mdtool_cogging.py
checks them against the C headers): they give the calibration's own time
bound, from which the host's timeout is derived.
"""
import math
import time

from .errors import CanToolError, NoReply, Refused, UsageError

#: parameter ids (tools/config/params.toml)
P_ANTICOGGING, P_COG_STATUS, P_COG_CAL_STATUS, P_CFG_PENDING = 180, 181, 183, 203

#: firmware/app/app/mc_app.h, firmware/app/commission/mc_comm_cog.h,
#: firmware/app/drive/mc_drive_cog.h
CAL_SPEED_RAD_S = 0.1
CAL_RAMP_S = 0.5
CAL_SETTLE_S = 1.0
CAL_PASSES = 2
BOUND_FRAC = 0.5
TIME_FACTOR = 2.0
MARGIN_BINS = 8
COG_N = 1024

#: the angle one recording covers [rad]: a turn and the margin's bins
TURN_RAD = 2.0 * math.pi * (1.0 + MARGIN_BINS / COG_N)
#: the calibration's nominal time [s]: per pass three ramps with their settles, two turns at
#: the speed
NOMINAL_S = CAL_PASSES * (3.0 * (CAL_RAMP_S + CAL_SETTLE_S) + 2.0 * TURN_RAD / CAL_SPEED_RAD_S)
#: its own bound [s]: each recording fails BLOCKED beyond TIME_FACTOR times its turn's time
BOUND_S = CAL_PASSES * (3.0 * (CAL_RAMP_S + CAL_SETTLE_S) +
                        2.0 * TIME_FACTOR * TURN_RAD / CAL_SPEED_RAD_S)
#: the host's longest wait over the bound: the drive's clock against the
#: host's (a crystal's few 1e-4, a simulated drive on a loaded machine a few
#: percent) and the status polls' latency; 10 % covers both
TIMEOUT_MARGIN = 1.10
DEFAULT_TIMEOUT_S = math.floor(10.0 * TIMEOUT_MARGIN * BOUND_S) / 10.0  # to 0.1 s, not above

PHASES = {0: "IDLE", 1: "RAMP_FWD", 2: "REC_FWD", 3: "RAMP_REV", 4: "REC_REV", 5: "STOP",
          6: "DONE", 7: "FAILED"}
PHASE_TEXT = {"IDLE": "idle", "RAMP_FWD": "ramp forward", "REC_FWD": "forward turn",
              "RAMP_REV": "ramp back", "REC_REV": "back turn", "STOP": "stop", "DONE": "done",
              "FAILED": "failed"}
#: MC_COMM_COG_ERR_* (bits 8..15) -> name, what to do
ERRORS = {
    0x01: ("CFG", "the drive refused the calibration's configuration (pwm_hz / slow_loop_div give a "
                  "step too slow for the calibration speed): a firmware or configuration fault"),
    0x02: ("NO_OFFSET", "no encoder offset: the drive's angle is not known; commission the motor "
                        "(mdtool calibrate --save) or let it find its angle first"),
    0x04: ("ROTOR_BLOCKED", "a turn was not covered in twice its time: free the rotor (no load, no "
                            "brake, no end stop) and check the speed gains"),
    0x08: ("MEAS", "an angle or current sample not finite, or a bin not seen (the rotor jumped): "
                   "check the encoder and its wiring"),
    0x10: ("MAP_IMPLAUSIBLE_AMPLITUDE", "the map's amplitude is beyond half of i_max_a: a load that "
                                        "depends on the angle, or the speed gains; uncouple the load"),
    0x20: ("MAP_IMPLAUSIBLE_DISAGREE", "the two directions disagree: a load or friction that depends "
                                       "on the angle one way only, or noise; uncouple the load, retry"),
    0x40: ("ABORTED", "the drive left SPEED or was disabled (a fault, a command timeout, DISABLE)"),
}
#: MC_COG_ST_* of the map builder (bits 16..23) -> name, what to do
BUILDER = {
    1: ("MAP_EMPTY", "no map"),
    2: ("MAP_LAYOUT", "the map's layout is refused"),
    3: ("MAP_CRC", "the map's CRC"),
    4: ("MAP_ENCODER", "the encoder's identity is refused (no encoder, counts, pole pairs)"),
    5: ("MAP_IMPLAUSIBLE_NONFINITE", "an entry of the map is not finite"),
    6: ("MAP_IMPLAUSIBLE_AMPLITUDE", "an entry beyond half of i_max_a: uncouple the load"),
    7: ("MAP_ARG", "the builder refused its arguments (i_max_a, the encoder)"),
    8: ("MAP_FLASH", "the map could not be stored or read"),
}


class CalibrationFailed(Refused):
    """The calibration ran and the drive reports a named failure (exit code 5)."""

    exit_code = 5


class ProtocolError(CanToolError):
    """A reply that cannot be the drive's answer (exit code 1)."""


def decode(st):
    """cog_cal_status -> (phase name, [(failure name, help)]). ProtocolError
    for a value no drive sends (a phase beyond FAILED, a pass beyond the
    last, an unknown error bit or builder status)."""
    st = int(st)
    phase, err, bld = st & 0xFF, (st >> 8) & 0xFF, (st >> 16) & 0xFF
    if (pass_of(st) >= CAL_PASSES or phase not in PHASES or err & ~sum(ERRORS) or
            (bld and bld not in BUILDER)):
        raise ProtocolError(f"cog_cal_status 0x{st:08X} is not a value the drive sends "
                            "(a foreign or corrupted reply)")
    fails = [v for b, v in ERRORS.items() if err & b]
    if bld:
        fails.append(BUILDER[bld])
    return PHASES[phase], fails


def pass_of(st):
    """The calibration's pass (0 first) a cog_cal_status tells."""
    return (int(st) >> 24) & 0xFF


class Progress:
    """Bins done per direction in the pass that runs: from the drive's
    POSITION frames when it sends them (the angle covered since the recording
    began), else from the time in the recording at the calibration speed."""

    def __init__(self):
        self.phase, self.t0, self.theta0, self.theta = None, None, None, None
        self.done = [0, 0]
        self.pass_no = 0

    def position(self, theta):
        self.theta = theta
        if self.theta0 is None and self.phase in ("REC_FWD", "REC_REV"):
            self.theta0 = theta

    def update(self, phase, now, pass_no=0):
        if phase == "DONE":  # the drive's DONE carries no pass: the last one ended
            pass_no = self.pass_no = CAL_PASSES - 1
        if pass_no != self.pass_no:  # a new pass: its turns begin again
            self.pass_no, self.done, self.phase = pass_no, [0, 0], None
        if phase != self.phase:
            if self.phase == "REC_FWD":
                self.done[0] = COG_N
            if self.phase == "REC_REV":
                self.done[1] = COG_N
            self.phase, self.t0, self.theta0 = phase, now, self.theta
        if phase in ("REC_FWD", "REC_REV"):
            if self.theta0 is not None and self.theta is not None:
                travel = abs(self.theta - self.theta0)
            else:
                travel = (now - self.t0) * CAL_SPEED_RAD_S
            k = 0 if phase == "REC_FWD" else 1
            self.done[k] = min(COG_N, int(travel / (2.0 * math.pi / COG_N)))
        if phase == "DONE":
            self.done = [COG_N, COG_N]

    @property
    def percent(self):
        if self.phase == "DONE":
            return 100
        return int(100 * (2 * COG_N * self.pass_no + self.done[0] + self.done[1]) /
                   (2 * COG_N * CAL_PASSES))


def _read(drive, pid):
    return drive.param("READ", pid)


def preconditions(drive):
    """What the host can read before it sends anything that acts. Raises
    Refused with a named status: FAULT, BUSY (enabled, stopping, not IDLE, or
    a calibration running), PENDING (written values wait for APPLY)."""
    hb = drive.heartbeat()
    if hb["mode"] == "FAULT":
        raise Refused(f"FAULT: the drive has a latched fault (faults 0x{int(hb['faults']):04X}): "
                      "find its cause, CLEAR_FAULTS, then calibrate", status="FAULT")
    if hb["enabled"] or hb["stopping"] or hb["mode"] != "IDLE":
        raise Refused(f"BUSY: the drive is not idle (mode {hb['mode']}, enabled {hb['enabled']}, "
                      f"stopping {hb['stopping']}): disable it first; the calibration enables it "
                      "itself in SPEED at rest", status="BUSY")
    phase, _ = decode(_read(drive, P_COG_CAL_STATUS))
    if phase not in ("IDLE", "DONE", "FAILED"):
        raise Refused(f"BUSY: an anticogging calibration already runs (phase {phase})", status="BUSY")
    if _read(drive, P_CFG_PENDING):
        raise Refused("PENDING: written values wait for APPLY; the APPLY that starts the calibration "
                      "would apply them too: APPLY or reload them (mdtool config) first", status="PENDING")
    return hb


def _enable_speed_at_rest(drive, keepalive):
    drive.send("SET_CONTROL_MODE", control_mode=2)
    drive.wait_for(lambda n, v: drive.check_cmd_error(n, v, "SET_CONTROL_MODE") or
                   (n == "HEARTBEAT" and v["control_mode"] == "SPEED"), drive.timeout,
                   "HEARTBEAT in control mode SPEED")
    drive.send("SET_ENABLE", enable=1)
    drive.host_heartbeat()
    t_end = time.monotonic() + drive.timeout
    t_hb = time.monotonic()
    while True:
        if time.monotonic() >= t_end:
            raise NoReply(f"no HEARTBEAT showing node {drive.node} enabled in SPEED within "
                          f"{drive.timeout:g} s")
        if time.monotonic() - t_hb >= keepalive:
            drive.host_heartbeat()
            t_hb = time.monotonic()
        d = drive.decode(drive.bus.recv(min(keepalive, 0.05)))
        if d is None:
            continue
        name, vals = d
        if name == "CMD_ERROR" and vals["error"] == "ANGLE_UNKNOWN":
            raise Refused("NO_OFFSET: the drive refused SPEED: its angle is not known (encoder offset "
                          "not commissioned): run `mdtool calibrate --save` first", status="NO_OFFSET")
        drive.check_cmd_error(name, vals, "SET_ENABLE")
        if name == "HEARTBEAT":
            if vals["mode"] == "FAULT":
                raise Refused(f"FAULT: the drive faulted at enable (faults 0x{int(vals['faults']):04X})",
                              status="FAULT")
            if vals["enabled"] and vals["mode"] == "CTRL" and not vals["stopping"]:
                drive.send("SET_SPEED_REF", omega_ref_rad_s=0.0)  # at rest, as the start asks
                return


#: READs of cog_cal_status left unanswered in a row before NoReply: a frame
#: lost on the bus, or a request the drive did not serve (its one held reply
#: slot busy: LIMITED) must not end a run of minutes; four in a row is a
#: drive that is gone
POLL_MISSES = 4


class _Poller:
    """cog_cal_status read without blocking the keep-alive: one READ out at a
    time, its reply taken from the frames the follow loop decodes; a READ
    unanswered within the reply timeout is sent again, up to POLL_MISSES in
    a row."""

    def __init__(self, drive, period):
        self.drive, self.period = drive, period
        self.t_sent = None
        self.t_next = 0.0
        self.misses = 0

    def tick(self, now):
        if self.t_sent is not None:
            if now - self.t_sent <= self.drive.timeout:
                return
            self.misses += 1
            if self.misses >= POLL_MISSES:
                raise NoReply(f"no PARAM_REPLY to {POLL_MISSES} READs of cog_cal_status in a row from node "
                              f"{self.drive.node} (each waited {self.drive.timeout:g} s)")
            self.t_sent = None
            self.t_next = now
        if now >= self.t_next:
            self.drive.send("PARAM_REQ", opcode=0, param_id=P_COG_CAL_STATUS, value=0)
            self.t_sent = now

    def reply(self, vals, now):
        """The status when vals answers our READ, else None (another reply)."""
        if self.t_sent is None or vals["opcode"] != "READ" or int(vals["param_id"]) != P_COG_CAL_STATUS:
            return None
        if vals["status"] != "OK":
            raise Refused(f"the drive refused READ cog_cal_status: {vals['status']}", status=vals["status"])
        self.t_sent, self.t_next, self.misses = None, now + self.period, 0
        return int(vals["value"])


def follow(drive, timeout_s, keepalive=0.05, poll=0.25, on_progress=None):
    """Keep the drive alive and read cog_cal_status until DONE or FAILED.
    Returns the last status; NoReply (CAL_TIMEOUT) after timeout_s."""
    prog = Progress()
    poller = _Poller(drive, poll)
    t0 = t_hb = time.monotonic()
    while True:
        now = time.monotonic()
        if now - t0 > timeout_s:
            raise NoReply(f"CAL_TIMEOUT: the calibration did not end within {timeout_s:g} s (its own "
                          f"bound is {BOUND_S:.0f} s; last phase {prog.phase})")
        if now - t_hb >= keepalive:
            drive.host_heartbeat()
            t_hb = now
        poller.tick(now)
        d = drive.decode(drive.bus.recv(min(keepalive, 0.02)))
        if d is None:
            continue
        name, vals = d
        drive.check_cmd_error(name, vals, "PARAM_REQ")
        if name == "POSITION":
            prog.position(float(vals["theta_m_rad"]))
        elif name == "HEARTBEAT" and vals["mode"] == "FAULT":
            raise CalibrationFailed(f"FAULT: the drive faulted during the calibration (faults "
                                    f"0x{int(vals['faults']):04X}); it aborted it", status="FAULT")
        elif name == "PARAM_REPLY":
            st = poller.reply(vals, time.monotonic())
            if st is None:
                continue
            phase, fails = decode(st)
            if phase == "IDLE":
                raise ProtocolError("cog_cal_status reads IDLE after the APPLY that starts the "
                                    "calibration: the drive did not start it")
            prog.update(phase, time.monotonic(), pass_of(st))
            if on_progress:
                on_progress(phase, prog)
            if phase in ("DONE", "FAILED"):
                return st, phase, fails


def calibrate_cogging(drive, timeout_s=DEFAULT_TIMEOUT_S, save=False, keepalive=0.05,
                      on_progress=None, say=print):
    """The whole calibration (module docstring). Returns a summary dict;
    raises Refused (exit 4), CalibrationFailed (5), NoReply (3),
    ProtocolError (1)."""
    if not (math.isfinite(timeout_s) and 0.0 < timeout_s <= DEFAULT_TIMEOUT_S):
        raise UsageError(f"--cal-timeout {timeout_s!r}: (0, {DEFAULT_TIMEOUT_S:.0f}] s (the "
                         f"calibration's own bound {BOUND_S:.0f} s plus {100 * (TIMEOUT_MARGIN - 1):.0f} %)")
    preconditions(drive)
    old = _read(drive, P_ANTICOGGING)
    enabled = False
    t0 = time.monotonic()
    try:
        enabled = True  # from the first SET_* frame on, DISABLE on the way out
        _enable_speed_at_rest(drive, keepalive)
        drive.host_heartbeat()  # each request waits for its reply: keep-alive first
        drive.param("WRITE", P_ANTICOGGING, 2)
        drive.host_heartbeat()
        try:
            drive.param("APPLY")
        except Refused as e:
            drive.param("WRITE", P_ANTICOGGING, old)  # nothing left staged
            if e.status == "INVALID":
                raise Refused("NOT_READY: the drive refused anticogging 2 (MC_PARAMS_ERR_COG_CAL: not "
                              "enabled in SPEED at rest with its angle known, e.g. still finding its "
                              "angle)", status="NOT_READY") from None
            raise
        st, phase, fails = follow(drive, timeout_s, keepalive, on_progress=on_progress)
    finally:
        if enabled:
            drive.disable()
    t_cal = time.monotonic() - t0
    drive.wait_for(lambda n, v: n == "HEARTBEAT" and not v["enabled"], drive.timeout,
                   "HEARTBEAT showing the drive disabled")
    if phase == "FAILED":
        names = [n for n, _h in fails] or ["UNKNOWN"]
        # the drive set anticogging 0 and kept its map: the value before, back
        after = "anticogging reads 0 (no map acts)"
        if old:
            drive.param("WRITE", P_ANTICOGGING, old)
            drive.param("APPLY")
            after = f"anticogging back to {old} (cog_status {_read(drive, P_COG_STATUS)})"
        # a later pass failed: the drive holds the map of the pass before it
        # (the one that pass ran on), not the map it had before
        kept = ("map is unchanged" if pass_of(st) == 0 else
                f"map is pass {pass_of(st)}'s of {CAL_PASSES} (not saved)")
        raise CalibrationFailed("anticogging calibration failed: " + "; ".join(
            f"{n} ({h})" for n, h in fails) + f" [cog_cal_status 0x{st:08X}]; {after}, the drive's "
            + kept, status="|".join(names))
    drive.param("WRITE", P_ANTICOGGING, 1)
    drive.param("APPLY")
    cog = _read(drive, P_COG_STATUS)
    if cog != 0:
        raise CalibrationFailed(f"MAP_NOT_IN_USE: the calibration ended DONE but cog_status reads {cog} "
                                "(not 0 OK)", status="MAP_NOT_IN_USE")
    say(f"anticogging calibration done in {t_cal:.1f} s: map in use (anticogging 1, cog_status 0)")
    seq = None
    if save:
        seq = drive.param("SAVE")
        say(f"saved with the configuration (record {seq})")
    else:
        say("not saved: the map is lost at power-off; `mdtool config save` (or --save) stores it")
    return {"cog_cal_status": st, "time_s": t_cal, "saved_record": seq}
