#!/usr/bin/env python3
"""Check one run of `mcsim run can-telemetry` against the CAN frames recorded
from it (a candump -L log), with the DBC as the only description of the
frames. Used by the log-file test (simulated time stamps, commands from a
script) and by the SocketCAN test (vcan0, candump -L, cansend).

    check_can_run.py --csv RUN.csv --json RUN.json --log CAN.log
                     [--logger-log REC.log] [--cmds SCRIPT.log] [--timed]
                     [--iq-cmd-a A] [--node N]

Asserts, each with the reason of its tolerance:
 1. every telemetry frame the SIL generated is in the log, in order, with the
    values of the SIL's own CSV (the frames as the firmware's generated codec
    decodes them) within half a quantisation step of the DBC (the CSV's
    values are already on the grid; +1e-6 relative for float32 arithmetic);
    sequence counters equal, so zero sequence gaps at the configured rates;
 2. frames per message = rate x duration within one frame (phase
    accumulator: the count is exact up to the partial period at each end);
 3. a SET_CURRENT_REF command changed the reference (CSV and decoded frames);
 4. a malformed command (SET_CURRENT_REF with 3 bytes) got CMD_ERROR LENGTH
    and changed nothing;
 5. the host's silence stopped the drive: HEARTBEAT shows stop_reason
    CMD_TIMEOUT, IDLE, disabled; with --timed (simulated time stamps) also
    the time: timeout after the last accepted command plus the ramp;
 6. python-can's candump reader + cantools decode every frame as the logger
    does (values equal to 1e-9: both compute raw * scale + offset in double);
 7. with --logger-log: the logger's own recording has the same frames as
    candump's, each CAN id's in the same order; with --logger-report: the kernel dropped none of them on the
    logger's socket (SO_RXQ_OVFL counter), so a loss can never be silent.
Exit 0 when all hold; prints each failure and exits 1 otherwise.
"""
import argparse
import csv
import json
import math
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools", "can"))
import mc_can  # noqa: E402

SLOTS = ["HEARTBEAT", "CURRENTS", "VOLTAGES", "SPEED", "POSITION", "OBSERVER", "CONTROLLER",
         "STEPPER"]
ERR_LENGTH = 2
STOP_CMD_TIMEOUT = 1
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
    return cond


def load_csv(path):
    with open(path, newline="") as f:
        r = csv.reader(f)
        head = next(r)
        rows = [[float(x) for x in row] for row in r]
    return head, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--csv", required=True)
    ap.add_argument("--json", required=True)
    ap.add_argument("--log", required=True)
    ap.add_argument("--logger-log")
    ap.add_argument("--logger-report", help="the logger's --report JSON (kernel drop counter)")
    ap.add_argument("--cmds", help="command script the SIL replayed (else commands are in the log)")
    ap.add_argument("--timed", action="store_true", help="log time stamps are simulated time")
    ap.add_argument("--iq-cmd-a", type=float, default=1.0, help="an i_q reference a command set")
    ap.add_argument("--node", type=int, default=1)
    a = ap.parse_args()

    db = mc_can.load_db()
    with open(a.json) as f:
        summ = json.load(f)
    head, rows = load_csv(a.csv)
    col = {h: i for i, h in enumerate(head)}
    frames = mc_can.read_candump(a.log)
    decoded, _skipped = mc_can.decode_log(db, frames, a.node)
    per = {}
    for msg, t_s, vals in decoded:
        per.setdefault(msg.name, []).append((t_s, vals))
    duration = summ["t_end_s"]  # the run may end early (end_after_stop_s)

    # 1. + 2. telemetry equals the SIL's CSV, no gaps, counts match the rates
    for slot, name in enumerate(SLOTS):
        rate = summ[f"param.rate_{name.lower()}_hz"]
        sent_rows = [r for r in rows if (int(r[col["tm_sent_mask"]]) >> slot) & 1]
        got = per.get(name, [])
        if rate == 0 or name in ("OBSERVER", "CONTROLLER", "STEPPER"):
            check(len(got) == 0, f"{name}: {len(got)} frames although not produced")
            continue
        check(abs(len(sent_rows) - rate * duration) <= 1.0,
              f"{name}: {len(sent_rows)} frames generated for {rate} Hz x {duration} s")
        if not check(len(got) == len(sent_rows),
                     f"{name}: {len(got)} frames in the log, the SIL generated {len(sent_rows)}"):
            continue
        msg = db.get_message_by_name(name)
        worst = 0.0
        for k, (row, (_t, vals)) in enumerate(zip(sent_rows, got, strict=True)):
            for s in msg.signals:
                want = row[col[f"{name}.{s.name}"]]
                want_q = min(max(want, s.minimum), s.maximum)  # the packer saturates
                tol = 0.5 * s.scale + 1e-6 * max(1.0, abs(want_q))
                err = abs(vals[s.name] - want_q)
                worst = max(worst, err / tol)
                if err > tol:
                    check(False, f"{name}[{k}].{s.name}: decoded {vals[s.name]!r}, SIL {want!r}"
                                 f" (tolerance {tol:g})")
                    break
        print(f"{name}: {len(got)} frames, worst |decoded - SIL| = {worst:.3f} x tolerance")
    st = mc_can.stats_of(db, frames, a.node, 1e6)
    check(st["lost_total"] == 0, f"sequence gaps: {st['lost_total']} frames lost")
    print(f"frames lost (sequence gaps): {st['lost_total']}; bus load {100 * st['bus_load']:.2f} %")

    # 3. a command changed the setpoint
    iq_tol = 0.5 * 0.001 + 1e-6  # CURRENT_REFS.i_q_ref_a quantisation
    iq_rows = [r for r in rows if abs(r[col["CURRENT_REFS.i_q_ref_a"]] - a.iq_cmd_a) < 1e-6]
    check(len(iq_rows) > 0, f"the SIL never had i_q_ref = {a.iq_cmd_a} A (command not applied)")
    iq_frames = [v for _t, v in per.get("CURRENT_REFS", []) if abs(v["i_q_ref_a"] - a.iq_cmd_a) <= iq_tol]
    check(len(iq_frames) > 0, f"no CURRENT_REFS frame with i_q_ref_a = {a.iq_cmd_a} A")

    # 4. the malformed command was rejected with an error reply
    errs = [v for _t, v in per.get("CMD_ERROR", [])]
    check(any(int(v["rejected_cmd"]) == 0x12 and int(v["error"]) == ERR_LENGTH and int(v["rx_len"]) == 3
              for v in errs), f"no CMD_ERROR LENGTH reply for the 3-byte SET_CURRENT_REF: {errs}")
    check(any(int(v["last_error"]) == ERR_LENGTH and int(v["last_error_cmd"]) == 0x12
              for _t, v in per.get("HEARTBEAT", [])), "HEARTBEAT never reported the rejection")
    check(summ["cmd_rejected"] >= 1, "the SIL counted no rejected command")
    # nothing changed: the reference before and after the bad frame is a commanded one
    # (the CSV holds the last CURRENT_REFS frame's values: empty before the first)
    refs = sorted({round(r[col["CURRENT_REFS.i_q_ref_a"]], 6) for r in rows
                   if not math.isnan(r[col["CURRENT_REFS.i_q_ref_a"]])})
    check(all(any(abs(x - c) < 1e-6 for c in (0.0, 0.5, a.iq_cmd_a)) or
              0.0 < x < a.iq_cmd_a for x in refs),  # values between are the stop ramp
          f"unexpected i_q references {refs[:10]}")

    # 5. stopped heartbeat -> safe stop with reason CMD_TIMEOUT
    hb = per.get("HEARTBEAT", [])
    stop_frames = [(t, v) for t, v in hb if int(v["stop_reason"]) == STOP_CMD_TIMEOUT
                   and int(v["mode"]) == 0 and int(v["enabled"]) == 0]
    check(len(stop_frames) > 0, "no HEARTBEAT reporting a CMD_TIMEOUT stop in IDLE")
    check(summ["final_stop_reason"] == STOP_CMD_TIMEOUT and summ["final_mode"] == 0,
          f"final state: mode {summ['final_mode']}, stop_reason {summ['final_stop_reason']}")
    check(summ["final_faults"] == 0, f"drive faulted: bits {summ['final_faults']}")
    last = rows[-1]
    check(last[col["CURRENT_REFS.i_q_ref_a"]] == 0.0, "i_q reference not zero after the stop")
    if a.timed:
        cmd_frames = mc_can.read_candump(a.cmds) if a.cmds else frames
        cmd_times = [t for t, _i, cid, d, fl in cmd_frames
                     if (cid >> 5) == a.node and (cid & 31) == 0x17]
        t_last = max(cmd_times)
        t_stop = next(r[col["t"]] for r in rows
                      if r[col["HEARTBEAT.stop_reason"]] == STOP_CMD_TIMEOUT)
        timeout = summ["param.timeout_s"]
        ramp = a.iq_cmd_a / summ["param.stop_ramp_a_per_s"]
        tick = 1.0 / summ["tick_hz"]
        hb_period = 1.0 / summ["param.rate_heartbeat_hz"]
        # the stop begins timeout after the last accepted command (to one
        # tick) and ends when the ramp reaches zero (to one tick); the CSV
        # holds the last HEARTBEAT frame's values, so the first one that
        # shows the stop comes up to one heartbeat period after its end
        check(timeout + ramp - 2 * tick <= t_stop - t_last <= timeout + ramp + 2 * tick + hb_period,
              f"stop at {t_stop:.4f} s, last command at {t_last:.4f} s: expected "
              f"{timeout + ramp:.4f} s later")
        print(f"safe stop {t_stop - t_last:.4f} s after the last heartbeat "
              f"(timeout {timeout} s + ramp {ramp:.3f} s)")

    # 6. cross-check with python-can + cantools
    import can
    import cantools
    cdb = cantools.database.load_file(os.path.join(ROOT, "tools", "can", "motordrive.dbc"))
    ours = iter(decoded)
    n = 0
    for m in can.CanutilsLogReader(a.log):
        if m.is_error_frame or m.is_extended_id or (m.arbitration_id >> 5) != a.node:
            continue
        try:
            dm = cdb.get_message_by_frame_id(m.arbitration_id)
        except KeyError:
            continue
        if len(m.data) != dm.length:
            continue
        vals = cdb.decode_message(m.arbitration_id, bytes(m.data), decode_choices=False)
        msg, _t, mine = next(ours)
        if not check(msg.name == dm.name, f"frame {n}: logger says {msg.name}, cantools {dm.name}"):
            break
        for k, v in vals.items():
            if not check(math.isclose(v, mine[k], rel_tol=0, abs_tol=1e-9),
                         f"frame {n} {dm.name}.{k}: cantools {v}, logger {mine[k]}"):
                break
        n += 1
    check(n == len(decoded), f"python-can read {n} frames of node {a.node}, the logger {len(decoded)}")
    print(f"python-can + cantools agree with the logger on {n} frames")

    # 7. the logger's own recording equals candump's. Compared per CAN id:
    # frames from different senders (the SIL's socket and cansend's) may
    # reach two receiving sockets in different orders when the kernel
    # delivers them on two CPUs at once (measured in the 2-CPU VM: a host
    # heartbeat one frame earlier in one log than in the other), while one
    # sender's frames, and so each id's, keep their order in every socket.
    if a.logger_log:
        rec = mc_can.read_candump(a.logger_log)

        def per_id(frs):
            out = {}
            for _t, _if, i, d, _fl in frs:
                out.setdefault(i, []).append(d)
            return out
        mine, theirs = per_id(rec), per_id(frames)
        check(len(rec) == len(frames), f"logger recorded {len(rec)} frames, candump {len(frames)}")
        for i in sorted(set(mine) | set(theirs)):
            x, y = theirs.get(i, []), mine.get(i, [])
            if x != y:
                first = next((k for k, (u, v) in enumerate(zip(x, y, strict=False)) if u != v), min(len(x), len(y)))
                check(False, f"id 0x{i:03X}: candump {len(x)} frames, logger {len(y)};"
                             f" first difference at its frame {first}")
        print(f"logger recording: {len(rec)} frames, each id's frames the same and in the same"
              " order as candump's")
    if a.logger_report:
        with open(a.logger_report) as f:
            rep = json.load(f)
        check(rep["kernel_dropped"] == 0,
              f"the kernel dropped {rep['kernel_dropped']} frames on the logger's socket")
        check(rep["frames"] == len(mc_can.read_candump(a.logger_log or a.log)),
              "the logger's report and its log disagree on the frame count")
        print(f"logger: kernel drop counter {rep['kernel_dropped']}, receive buffer "
              f"{rep['rcvbuf_bytes']} B")

    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
