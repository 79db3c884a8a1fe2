"""Commissioning over CAN (firmware/app/commission/mc_comm_can.h):
COMMISSION_CMD starts it, COMMISSION_STATUS tells its progress,
COMMISSION_RESULT carries one measured value per frame (IEEE 754 single in
the raw 32 bits of `value`). When the run is done the drive has staged the
results in its parameter table; PARAM_REQ APPLY (the whole-set check) puts
them into effect and SAVE stores them.
"""
import struct
import time

from .errors import NoReply, Refused

#: COMMISSION_RESULT.item -> (result name, parameter it goes to, unit)
#: (the results keep the drive's conventions; PARAM_VALUE converts one to the
#: parameter's where they differ)
ITEMS = {
    "R_OHM": ("r_ohm", "r_ohm", "ohm"),
    "LD_H": ("ld_h", "ld_h", "H"),
    "LQ_H": ("lq_h", "lq_h", "H"),
    "FLUX_WB": ("flux_wb", "flux_wb", "Wb"),
    "POLE_PAIRS": ("pole_pairs", "pole_pairs", ""),
    "ENCODER_OFFSET_RAD": ("encoder_offset_rad", "encoder_offset_rad", "rad"),
    "ENCODER_DIRECTION": ("encoder_direction", "encoder_reversed", ""),
    "ADC_OFFSET_A_A": ("i_offset_a_a", "i_offset_a_a", "A"),
    "ADC_OFFSET_B_A": ("i_offset_b_a", "i_offset_b_a", "A"),
    "ADC_OFFSET_C_A": ("i_offset_c_a", "i_offset_c_a", "A"),
    "J_KGM2": ("j_kgm2", "j_kgm2", "kg.m^2"),
    "B_NM_S_RAD": ("b_nm_s_rad", "b_nm_s_rad", "N.m.s/rad"),
}
#: result -> its value in the parameter's convention: the drive reports the
#: encoder's direction (+1: counts up for a positive rotation, -1: down),
#: the parameter encoder_reversed is 1 when it counts down (as the firmware
#: stages it, mc_comm_can.c)
PARAM_VALUE = {"encoder_direction": lambda d: 1 if d < 0 else 0}


#: COMMISSION_STATUS.valid (MC_COMM_HAVE_*, mc_commission.h): the encoder's
#: offset and direction, J and B; SENSORLESS: measured without an encoder
VALID_ENCODER, VALID_MECH, VALID_SENSORLESS = 1 << 3, 1 << 5, 1 << 6
#: the results a valid bit stands for (not measured: no row)
VALID_OF = {"encoder_offset_rad": VALID_ENCODER, "encoder_direction": VALID_ENCODER,
            "j_kgm2": VALID_MECH, "b_nm_s_rad": VALID_MECH}


def rows(results, present, table, valid=None):
    """The calibrate table: one row per parameter a result goes to, the
    measured value and the one in use in the same (the parameter's)
    convention. (parameter, measured, unit, in use or None, change text).
    With `valid` (COMMISSION_STATUS.valid) a result the run did not
    measure (without an encoder the offset, direction, J and B) has no row."""
    out = []
    for res, pname, unit in ITEMS.values():
        if valid is not None and res in VALID_OF and not valid & VALID_OF[res]:
            continue
        v = PARAM_VALUE.get(res, lambda x: x)(results[res])
        p = table.get(pname)
        old = present.get(pname)
        ch = ""
        if old is not None and p["type"] == "f32" and old != 0:
            ch = f"{100.0 * (v - old) / abs(old):+.1f} %"
        elif old is not None:
            ch = "same" if v == old else "new"
        out.append((pname, v, unit, old, ch))
    return out


#: MC_COMM_ERR_* bit names (firmware/app/commission/mc_commission.h)
ERROR_BITS = ["OFFSET", "NO_MOTOR", "OPEN_PHASE", "ENCODER_NO_MOTION", "ROTOR_BLOCKED",
              "WRONG_DIRECTION", "ENCODER_BAD", "OVERCURRENT", "VOLTAGE", "RANGE", "MEAS", "ABORTED",
              "HOST_LOST", "ENCODER_COARSE", "HALL_CODES", "HALL_ORDER"]
ERROR_HELP = {
    "OFFSET": "a current-sensor offset is implausible (sensor broken?)",
    "NO_MOTOR": "no current flows on any axis: is a motor connected?",
    "OPEN_PHASE": "one phase carries no current: check the wiring",
    "ENCODER_NO_MOTION": "the rotor turned but the encoder did not count",
    "ROTOR_BLOCKED": "the rotor did not turn: free it (no load, no brake)",
    "WRONG_DIRECTION": "the rotor turned against the torque",
    "ENCODER_BAD": "encoder counts inconsistent (no whole pole-pair count)",
    "OVERCURRENT": "a phase current above 1.5 i_test",
    "VOLTAGE": "a step needs more than v_test_max",
    "RANGE": "a measured value is not plausible (or the parameter table refused it)",
    "MEAS": "no encoder sample, or a non-finite one",
    "ABORTED": "stopped (ABORT, disable, or the drive stopped it)",
    "HOST_LOST": "the host's keep-alive (HOST_HEARTBEAT) stopped: the drive aborted it",
    "ENCODER_COARSE": "fewer than 12 encoder counts per electrical turn (a Hall-class"
                      " sensor): the flux step cannot measure the speed; give the motor's"
                      " values (flux from its KV) instead",
    "HALL_CODES": "Hall table: a code 000 or 111, or fewer than six codes: a Hall sensor is"
                  " stuck, unpowered or disconnected",
    "HALL_ORDER": "Hall table: the codes do not change one sensor at a time round one cycle"
                  " (wiring), or not in the order of the table in force",
}


def error_names(bits):
    return [n for i, n in enumerate(ERROR_BITS) if bits >> i & 1] or (["UNKNOWN"] if bits else [])


#: COMMISSION_STATUS.detail (MC_COMM_DETAIL_*): the reasons the error field has
#: no bit for; the field then carries RANGE
DETAILS = ["NONE", "FLUX_SPEEDS", "MECH_FIT", "MECH_SPIN_COAST", "IF_SYNC"]
DETAIL_HELP = {
    "FLUX_SPEEDS": "the coast's two speed bands gave fluxes further apart than the encoder's"
                   " and the voltage's resolution allows: the speed or voltage reading is off",
    "MECH_FIT": "the coast's speed is not the viscous model's line (a load that changes,"
                " a speed that jumps): J and B would be off",
    "MECH_SPIN_COAST": "J from the spin-up's two halves disagree: the friction is not viscous"
                       " (Coulomb friction, a load); uncouple the load or enter J and B by hand",
    "IF_SYNC": "without an encoder: the rotor did not follow the I-f spin (stalled, blocked or"
               " out of step under a load): free the rotor, uncouple the load, check pole_pairs",
}


def detail_name(v):
    """The detail signal decoded (its DBC name, or the number) by name."""
    if isinstance(v, str):
        return v
    i = int(v or 0)
    return DETAILS[i] if 0 <= i < len(DETAILS) else "UNKNOWN"


def f32_of(raw):
    return struct.unpack("<f", struct.pack("<I", int(raw) & 0xFFFFFFFF))[0]


class Collector:
    """Status and results from decoded frames (name, values) of one node."""

    def __init__(self):
        self.status = None
        self.statuses = []
        self.results = {}

    def feed(self, name, vals):
        if name == "COMMISSION_STATUS":
            self.status = vals
            self.statuses.append(vals)
        elif name == "COMMISSION_RESULT" and vals["item"] in ITEMS:
            self.results[ITEMS[vals["item"]][0]] = f32_of(vals["value"])

    @property
    def ended(self):
        return self.status is not None and self.status["step"] in ("DONE", "FAILED")

    @property
    def complete(self):
        if not self.ended:
            return False
        return self.status["step"] == "FAILED" or len(self.results) == len(ITEMS)

    def summary(self):
        st = self.status or {}
        return {"step": st.get("step"), "error": error_names(int(st.get("error", 0))),
                "detail": detail_name(st.get("detail", 0)),
                "error_bits": int(st.get("error", 0)), "valid": int(st.get("valid", 0)),
                "sensorless": bool(int(st.get("valid", 0)) & VALID_SENSORLESS),
                "staged": bool(st.get("staged", 0)), "results": dict(self.results)}


def calibrate(drive, i_test_a=0.0, v_test_max_v=0.0, speed_max_m_rad_s=0.0, timeout=30.0,
              on_status=None, abort_on_exit=False, keepalive=0.05):
    """Start commissioning on `drive` (mdtool.can.client.Drive) and wait
    until it ends and every result arrived, sending the keep-alive
    (HOST_HEARTBEAT every `keepalive` s: the drive aborts a run whose host
    falls silent, error HOST_LOST). Raises Refused when the drive refuses
    the command, NoReply when it falls silent for `timeout` s. With
    `abort_on_exit`, leaving before the drive ended it (no progress, an
    exception, Ctrl-C / SIGTERM) sends ABORT first."""
    col = Collector()
    start = drive.frame("COMMISSION_CMD", action=1, i_test_a=i_test_a, v_test_max_v=v_test_max_v,
                        speed_max_m_rad_s=speed_max_m_rad_s)
    drive.bus.send(start)
    drive.host_heartbeat()
    refused = False
    try:
        _follow(drive, col, timeout, on_status, keepalive)
    except Refused:
        refused = True  # the start was refused: nothing runs to abort
        raise
    finally:
        if abort_on_exit and not col.ended and not refused:
            abort(drive)
    return col.summary()


def _follow(drive, col, timeout, on_status, keepalive):
    last = t_hb = time.monotonic()
    while not col.complete:
        if time.monotonic() - t_hb >= keepalive:
            drive.host_heartbeat()
            t_hb = time.monotonic()
        if time.monotonic() - last > timeout:
            raise NoReply(f"no commissioning progress from node {drive.node} within {timeout:g} s")
        d = drive.decode(drive.bus.recv(min(0.1, keepalive)))
        if d is None:
            continue
        name, vals = d
        drive.check_cmd_error(name, vals, "COMMISSION_CMD")
        if name not in ("COMMISSION_STATUS", "COMMISSION_RESULT"):
            continue
        last = time.monotonic()
        col.feed(name, vals)
        if name == "COMMISSION_STATUS" and on_status:
            on_status(vals)


def abort(drive):
    drive.send("COMMISSION_CMD", action=0, i_test_a=0, v_test_max_v=0, speed_max_m_rad_s=0)


def check_failed(summary):
    if summary["step"] == "FAILED":
        errs = list(summary["error"])
        detail = summary.get("detail", "NONE")
        help_ = dict(ERROR_HELP)
        if detail != "NONE":  # the reason RANGE stands for
            errs = [detail if e == "RANGE" else e for e in errs]
            help_[detail] = DETAIL_HELP.get(detail, "")
        raise Refused("commissioning failed: " + ", ".join(
            f"{e} ({help_.get(e, '')})" for e in errs) + "; nothing staged, bridge off",
            status="|".join(errs))
