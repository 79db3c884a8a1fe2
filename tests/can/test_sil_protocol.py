#!/usr/bin/env python3
"""The protocol's guards on the SIL drive (mcsim run can-telemetry, the
firmware's command handler and telemetry), every frame encoded and decoded
from the DBC by cantools, commands from a candump script at simulated time:

 1. a command timeout in SPEED mode decelerates to standstill at the
    configured deceleration before the bridge opens (this scenario's drive
    has no controlled stop of its own: the CAN layer ramps the speed
    reference and waits for rest): the measured deceleration, and the speed
    when the HEARTBEAT first shows IDLE (protocol 1 opened it at 7.8 rad/s,
    the speed loop's lag behind the ramp);
 1b. the same in POSITION mode during a 40-turn move (the position law's
    stop op re-plans a stop at that deceleration);
 2. one HOST_HEARTBEAT repeated (the same counter) is no keep-alive: the
    drive stops timeout_s after the first, answering the repeats STALE, at
    most the rate limit's burst + 50 per second;
 3. SET_TM_RATE HEARTBEAT 0 Hz is refused HEARTBEAT_MIN, and the HEARTBEAT
    keeps coming at its rate;
 4. position mode over CAN with a multi-turn target: 10 turns
    (62.8319 rad) reached and held (the POSITION telemetry's multi-turn
    angle), the target echoed in POSITION_REF;
 5. a flood at 100 % bus load from another node (1 Mbit/s of the shortest
    frames, 21277 per second, delivered at their simulated time) during a
    SPEED run costs no keep-alive: the drive stays enabled while the host's
    heartbeats come, every foreign frame is dropped in the receive
    interrupt (before the ring and the command handler), no own frame is
    lost, a period takes only its own frames, and the run (plant,
    telemetry, frames) is identical to the same run without the flood;
 6. enabling SPEED mode into the rotor commissioning left coasting, at
    several delays after DONE: no fault (the ASan failure of
    can.mdtool_vcan after calibrate).

    test_sil_protocol.py --mcsim MCSIM --work DIR --repo ROOT
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_sil_flash import report, setup

fails = []


def check(ok, what):
    if not ok:
        fails.append(what)
        print("FAIL:", what)


def rows_of(out):
    with open(os.path.join(out, "can-telemetry.csv")) as f:
        r = csv.DictReader(f)
        return [{k: float(v) for k, v in row.items()} for row in r]


def hb_frames(frames):
    return [(t, s) for t, n, s in frames if n == "HEARTBEAT"]


# The CSV holds the last HEARTBEAT frame's values: the runs that time the
# stop from HEARTBEAT.stopping / .mode send it at the table's highest rate
# (100 Hz), and the first row that shows the stop comes up to one heartbeat
# period after it (HB_PERIOD_S added to those tolerances).
HB_FAST = ["--set", "rate_heartbeat_hz=100"]
HB_PERIOD_S = 0.01


def stop_profile(rows):
    """The stop of a run: (start time, speed then, deceleration between 80 %
    and 20 % of it, the first row with the bridge open)."""
    t_stop = next(r["t"] for r in rows if r["HEARTBEAT.stopping"] == 1.0)
    w0 = next(r["omega_m_true_rad_s"] for r in rows if r["t"] >= t_stop)
    a = next(r for r in rows if r["t"] > t_stop and r["omega_m_true_rad_s"] <= 0.8 * w0)
    b = next(r for r in rows if r["t"] > t_stop and r["omega_m_true_rad_s"] <= 0.2 * w0)
    meas = (a["omega_m_true_rad_s"] - b["omega_m_true_rad_s"]) / (b["t"] - a["t"])
    idle = next(r for r in rows if r["t"] > t_stop and r["HEARTBEAT.mode"] == 0.0)
    return t_stop, w0, meas, idle


def timeout_stop_in_speed_mode(sil):
    # J 0.005 kg m^2: the speed PI's 3 A accelerate it at 0.66 * 3 / 0.005 = 396 rad/s^2
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=2),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.07, "SET_SPEED_REF", omega_ref_rad_s=100.0)]
    t_hb = [0.1 * k for k in range(1, 11)]
    cmds += [sil.frame(t, "HOST_HEARTBEAT", counter=k) for k, t in enumerate(t_hb)]
    # speed PI at 60 rad/s: it follows the 200 rad/s^2 ramp closely
    _r, s, frames = sil.run("stop", cmds, duration=2.5,
                            extra=["--set", "J_kgm2=0.005", "--set", "stop_decel_rad_s2=200",
                                   "--set", "speed_bw_rad_s=60", *HB_FAST])
    rows = rows_of(os.path.join(sil.work, "stop"))
    decel = s["param.stop_decel_rad_s2"]
    t_stop, w0, meas, idle = stop_profile(rows)
    tick = 1.0 / s["tick_hz"]
    # the stop begins timeout_s after the last heartbeat, to one tick, and
    # shows in the next HEARTBEAT frame
    check(-2 * tick <= t_stop - (t_hb[-1] + s["param.timeout_s"]) <= 2 * tick + HB_PERIOD_S,
          f"stop began at {t_stop:.4f} s, last heartbeat {t_hb[-1]:.3f} s")
    check(abs(w0 - 100.0) < 2.0, f"speed at the stop {w0:.2f} rad/s, not the 100 rad/s commanded")
    # deceleration between 80 % and 20 % of the initial speed (the ramp's
    # straight part): within 10 % of the configured rate (the speed loop
    # follows the ramp with a lag that settles; the load is the inertia only)
    check(abs(meas - decel) <= 0.1 * decel, f"deceleration {meas:.1f} rad/s^2, configured {decel:g}")
    # the bridge opens at standstill: the first IDLE row has the rotor at rest
    # (the CAN layer's 0.5 rad/s, plus the speed estimate's lag: 2 rad/s)
    check(abs(idle["omega_m_true_rad_s"]) < 2.0,
          f"bridge opened at {idle['omega_m_true_rad_s']:.2f} rad/s (coasting)")
    t_ramp = w0 / decel
    check(abs((idle["t"] - t_stop) - t_ramp) < 0.1 * t_ramp + 0.02,
          f"stop took {idle['t'] - t_stop:.3f} s, the ramp {t_ramp:.3f} s")
    check(s["final_stop_reason"] == 1 and s["final_faults"] == 0,
          f"stop reason {s['final_stop_reason']}, faults {s['final_faults']}")
    check(any(v["stopping"] == 1 for _t, v in hb_frames(frames)), "no HEARTBEAT showed the stop")
    print(f"timeout stop in SPEED: {w0:.1f} rad/s, deceleration {meas:.1f} rad/s^2 "
          f"(configured {decel:g}), bridge open at {idle['omega_m_true_rad_s']:.3f} rad/s "
          f"after {idle['t'] - t_stop:.3f} s")


def timeout_stop_in_position_mode(sil):
    # a 40-turn move whose host falls silent at 0.5 s: the stop begins at
    # 1.0 s, cruising at 150 rad/s (reached at 0.82 s, 56 rad), and the
    # position law decelerates
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=3),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.07, "SET_POSITION_REF", theta_ref_rad=251.3274)]
    cmds += [sil.frame(0.1 * k, "HOST_HEARTBEAT", counter=k) for k in range(1, 6)]
    _r, s, _frames = sil.run("posstop", sorted(cmds), duration=2.5,
                             extra=["--set", "J_kgm2=0.005", "--set", "stop_decel_rad_s2=200",
                                    *HB_FAST])
    rows = rows_of(os.path.join(sil.work, "posstop"))
    decel = s["param.stop_decel_rad_s2"]
    t_stop, w0, meas, idle = stop_profile(rows)
    check(w0 > 100.0, f"speed at the stop {w0:.1f} rad/s: the move should be cruising")
    # the law's stop trapezoid followed by the cascade: within 10 %
    check(abs(meas - decel) <= 0.1 * decel, f"position stop: deceleration {meas:.1f} rad/s^2")
    # at rest: the CAN layer's threshold (0.5 rad/s) plus a tick's change
    check(abs(idle["omega_m_true_rad_s"]) < 2.0,
          f"position stop: bridge opened at {idle['omega_m_true_rad_s']:.2f} rad/s")
    check(s["final_stop_reason"] == 1 and s["final_faults"] == 0,
          f"stop reason {s['final_stop_reason']}, faults {s['final_faults']}")
    print(f"timeout stop in POSITION: {w0:.1f} rad/s, deceleration {meas:.1f} rad/s^2, "
          f"bridge open at {idle['omega_m_true_rad_s']:.3f} rad/s after {idle['t'] - t_stop:.3f} s")


def stale_heartbeat(sil):
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=1),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.07, "SET_CURRENT_REF", i_d_ref_a=0.0, i_q_ref_a=0.5)]
    cmds += [sil.frame(0.08 + 0.05 * k, "HOST_HEARTBEAT", counter=5) for k in range(30)]
    _r, s, frames = sil.run("stale", cmds, duration=1.6, extra=HB_FAST)
    rows = rows_of(os.path.join(sil.work, "stale"))
    t_stop = next(r["t"] for r in rows if r["HEARTBEAT.stopping"] == 1.0)
    # the last accepted command is the first heartbeat (0.08 s)
    check(-2.0 / s["tick_hz"] <= t_stop - (0.08 + s["param.timeout_s"])
          <= 2.0 / s["tick_hz"] + HB_PERIOD_S,
          f"stale heartbeats kept it running: stop at {t_stop:.4f} s")
    stale = [v for _t, n, v in frames if n == "CMD_ERROR" and v["error"] == 9]
    check(len(stale) >= 1, "no CMD_ERROR STALE")
    check(s["cmd_rejected"] >= 29, f"{s['cmd_rejected']} rejected, 29 repeats sent")
    print(f"stale heartbeat: stop at {t_stop:.3f} s; {len(stale)} STALE replies, "
          f"{int(s['cmd_rejected'])} rejected")


def heartbeat_min(sil):
    cmds = [sil.frame(0.05, "SET_TM_RATE", tm_cmd=1, rate_hz=0)]
    _r, _s, frames = sil.run("hbmin", cmds, duration=1.0)
    errs = [v for _t, n, v in frames if n == "CMD_ERROR"]
    check([(v["rejected_cmd"], v["error"]) for v in errs] == [(0x16, 10)],
          f"SET_TM_RATE HEARTBEAT 0 Hz: replies {errs}")
    late = [t for t, _v in hb_frames(frames) if t > 0.1]
    # 10 Hz over 0.9 s: 9 frames, one more or less by the phase of the scheduler
    check(8 <= len(late) <= 10, f"{len(late)} HEARTBEAT frames after the refusal")
    print(f"HEARTBEAT 0 Hz refused HEARTBEAT_MIN; {len(late)} heartbeats in the 0.9 s after")


def position_mode(sil):
    target = 62.8319  # 10 turns, in the frame of POSITION.theta_m_rad (from boot)
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=3),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.2, "SET_POSITION_REF", theta_ref_rad=target)]
    cmds += [sil.frame(0.1 * k, "HOST_HEARTBEAT", counter=k) for k in range(1, 30)]
    _r, s, frames = sil.run("position", sorted(cmds), duration=2.5,
                            extra=["--set", "J_kgm2=0.005", "--set", "stop_decel_rad_s2=200"])
    rows = rows_of(os.path.join(sil.work, "position"))
    th0 = next(r["POSITION.theta_m_rad"] for r in rows if r["t"] >= 0.06)
    pos = [(t, v) for t, n, v in frames if n == "POSITION"]
    refs = [v["theta_ref_rad"] for _t, n, v in frames if n == "POSITION_REF" and _t > 0.25]
    check(refs and all(abs(x - target) <= 0.5e-4 for x in refs),
          f"POSITION_REF does not echo the target: {refs[:3]}")
    # the trapezoid (150 rad/s, 200 rad/s^2) takes 1.17 s: at rest from 1.6 s
    end = [v["theta_m_rad"] for t, v in pos if t >= 2.0]
    err = max(abs(x - target) for x in end)
    # one encoder count (2 pi / 8192 = 7.7e-4 rad) plus the signal's half step
    check(err <= 7.7e-4 + 0.5e-4, f"final position error {err:.5f} rad")
    over = max(v["theta_m_rad"] for _t, v in pos) - target
    check(over <= 0.05, f"overshoot {over:.4f} rad")
    check(s["final_faults"] == 0 and s["cmd_rejected"] == 0,
          f"faults {s['final_faults']}, rejected {s['cmd_rejected']}")
    print(f"position: from {th0:.4f} rad to {target} rad (10 turns); final error {err * 1e3:.3f} mrad, "
          f"overshoot {over * 1e3:.2f} mrad")


def flood_run(sil, name, flood_per_s, t_end):
    """SPEED mode at 100 rad/s with the host's heartbeats every 0.1 s up to
    1.2 s, and, if flood_per_s, another node's frames at that rate from
    0.07 s: id 0x041 (node 2, cmd 1), no data: the shortest frame, and a
    lower priority than every node-1 identifier, so on a real bus the host's
    heartbeats and the drive's telemetry win arbitration and the flood takes
    all the rest. Returns (summary, rows, foreign frames sent)."""
    cmds = [sil.frame(0.05, "SET_CONTROL_MODE", control_mode=2),
            sil.frame(0.06, "SET_ENABLE", enable=1),
            sil.frame(0.065, "SET_SPEED_REF", omega_ref_rad_s=100.0)]
    hb = [(0.1 * k, sil.frame(0.1 * k, "HOST_HEARTBEAT", counter=k)) for k in range(1, 13)]
    flood = []
    if flood_per_s:
        flood = [(k / flood_per_s, "(%017.6f) can0 041#" % (k / flood_per_s))
                 for k in range(int(0.07 * flood_per_s), int(t_end * flood_per_s))]
    merged = sorted(hb + flood, key=lambda x: x[0])
    cmds += [line for t, line in merged if t >= 0.066]  # after the set-up, in time order
    _r, s, _frames = sil.run(name, sorted(cmds), duration=t_end,
                             extra=["--set", "bitrate_kbps=1000", "--set", "J_kgm2=0.005"])
    return s, rows_of(os.path.join(sil.work, name)), len(flood)


def foreign_flood(sil):
    t_end = 1.5
    # 100 % bus load at the configured 1 Mbit/s: the shortest standard frame
    # (no data) is 47 bits without stuff bits (SOF 1, id 11, RTR 1, IDE 1,
    # r0 1, DLC 4, CRC 15, delimiters and ACK 3, EOF 7, intermission 3):
    # 1e6 / 47 = 21277 frames per second, one every 47 us. Delivered at their
    # simulated time on top of the node's own traffic (slightly more than
    # the bus could carry).
    bitrate = 1e6
    n_per_s = round(bitrate / 47)
    s, rows, n_flood = flood_run(sil, "flood", n_per_s, t_end)
    _s0, rows0, _ = flood_run(sil, "noflood", 0, t_end)
    check(s["param.bitrate_kbps"] * 1e3 == bitrate, "the flood's rate assumes the configured bit rate")
    # heartbeats up to 1.2 s: enabled, not stopping, until then
    running = [r for r in rows if 0.1 <= r["t"] <= 1.2]
    check(all(r["HEARTBEAT.enabled"] == 1.0 and r["HEARTBEAT.stopping"] == 0.0 for r in running),
          "the flood delayed the keep-alive into a stop")
    check(s["cmd_accepted"] == 3 + 12, f"{s['cmd_accepted']} commands accepted, 3 + 12 heartbeats sent")
    # foreign frames dropped first: every one in the receive interrupt (it
    # runs each PWM period, before the fast step, as the image's CAN
    # interrupt takes what the bus delivered), by one identifier comparison,
    # before the ring and the command handler; the frames of the run's last
    # period arrive after its last receive
    per_period = n_per_s / (s["tick_hz"] * s["param.slow_loop_div"])
    check(n_flood - per_period - 1 <= s["app_rx_foreign"] <= n_flood
          and s["cmd_rx_foreign"] == s["app_rx_foreign"],
          f"{s['app_rx_foreign']} foreign frames dropped in the receive interrupt, "
          f"{s['cmd_rx_foreign'] - s['app_rx_foreign']} later, {n_flood} sent")
    check(s["app_rx_overflows"] == 0, f"{s['app_rx_overflows']} own frames lost to a full ring")
    # the per-period work: at 10 kHz a period takes the 2.1 flood frames of
    # its 100 us (3 when the 47 us grid puts one more in it) plus at most
    # one own command; the bound of one call is 2 x the ring (64)
    per_tick = s["app_rx_read_max"]
    check(per_period <= per_tick <= per_period + 2,
          f"a period took at most {per_tick:g} frames from the HAL "
          f"({per_period:.1f} flood frames per period)")
    check(s["cmd_poll_frames_max"] <= 16 + 64, f"a poll read {s['cmd_poll_frames_max']} frames")
    check(s["cmd_rejected"] == 0 and s["final_faults"] == 0,
          f"rejected {s['cmd_rejected']}, faults {s['final_faults']}")
    # the control and the telemetry did not notice: the run with the flood is
    # the run without it, every CSV column (plant, telemetry values, frame
    # masks) in every row, exactly (as text: the CSV's NaN for a message not
    # produced compares equal to itself only so)
    def text(name):
        with open(os.path.join(sil.work, name, "can-telemetry.csv")) as f:
            return f.read().splitlines()
    lines, lines0 = text("flood"), text("noflood")
    same = len(rows) == len(rows0) and lines == lines0
    diff = next((k for k, (a, b) in enumerate(zip(lines, lines0, strict=False)) if a != b), None)
    check(same, f"the flood changed the drive's run (first differing row {diff})")
    w = [r["omega_m_true_rad_s"] for r in rows if 1.0 <= r["t"] <= 1.2]
    check(w and all(abs(x - 100.0) < 2.0 for x in w), "the speed loop did not hold 100 rad/s")
    print(f"flood: {n_flood} foreign frames ({n_per_s}/s, 100 % of 1 Mbit/s) dropped in the "
          f"receive interrupt, at most {per_tick:g} frames per period, keep-alive accepted "
          f"throughout, the run identical to the one without the flood")


def enable_after_commissioning(sil):
    """The VM test's drive (tests/can/vm/mdtool_vcan.sh: 5 kHz PWM (at 2 kHz
    the current ripple exceeds the 10 A limit: no safe gains), a 20 Hz
    current loop, no flywheel) commissioned over CAN, then SPEED 20 rad/s
    enabled while the rotor still coasts at about 60 rad/s from the flux
    test, at several delays after DONE. Before the drive wrote the zero
    vector into the duty registers when it opened the bridge, the first
    enabled period ran on the commissioning's last voltage vector at a rotor
    angle long gone and tripped OVERCURRENT at 8, 13 and 89 ms after DONE
    (not at 0 or 21 ms): the ASan run of can.mdtool_vcan that failed after
    calibrate (run refused SET_SPEED_REF with MODE, stop_reason FAULT)."""
    vm = ["--set", "timeout_s=2.0", "--set", "pwm_hz=5000", "--set", "slow_loop_div=5",
          "--set", "substeps=1", "--set", "bw_hz=20", "--set", "speed_pll_bw_rad_s=500",
          "--set", "J_kgm2=0.002", "--set", "speed_ramp_rad_s2=200"]
    start = [sil.frame(0.05, "COMMISSION_CMD", action=1, i_test_a=0, v_test_max_v=0,
                       speed_max_m_rad_s=0)]
    # the host's keep-alive while it runs (commissioning needs it)
    alive = [sil.frame(0.06 + 0.1 * k, "HOST_HEARTBEAT", counter=k % 256) for k in range(80)]
    _r, _s, frames = sil.run("commission", sorted(start + alive), duration=8.0, extra=vm)
    done = next((t for t, n, v in frames if n == "COMMISSION_STATUS" and v["step"] == 7), None)
    check(done is not None, "commissioning reached DONE")
    if done is None:
        return
    for ms in (0, 8, 13, 21, 89):
        t = done + ms / 1000.0
        cmds = start + [a for a in alive if a < sil.frame(t, "HOST_HEARTBEAT", counter=0)]
        cmds += [sil.frame(t, "SET_CONTROL_MODE", control_mode=2),
                        sil.frame(t + 0.0005, "SET_ENABLE", enable=1),
                        sil.frame(t + 0.001, "SET_SPEED_REF", omega_ref_rad_s=20.0)]
        cmds += [sil.frame(t + 0.1 * k, "HOST_HEARTBEAT", counter=k) for k in range(1, 11)]
        name = f"enable_after_done_{ms}ms"
        _r, s, _f = sil.run(name, sorted(cmds), duration=t + 1.1, extra=vm)
        rows = rows_of(os.path.join(sil.work, name))
        w0 = next(r["omega_m_true_rad_s"] for r in rows if r["t"] >= t)
        w_end = rows[-1]["omega_m_true_rad_s"]
        check(s["final_faults"] == 0 and s["final_stop_reason"] == 0 and s["cmd_rejected"] == 0,
              f"enable {ms} ms after DONE at {w0:.1f} rad/s: faults {s['final_faults']}, "
              f"stop reason {s['final_stop_reason']}, rejected {s['cmd_rejected']}")
        # the speed PI (3 A) has settled on 20 rad/s a second later: within
        # 1 rad/s (the 500 rad/s encoder loop's ripple at 5 kHz)
        check(abs(w_end - 20.0) < 1.0, f"enable {ms} ms after DONE: {w_end:.2f} rad/s after 1 s")
    print(f"enable after commissioning (DONE at {done:.3f} s, rotor coasting): no fault at "
          f"0, 8, 13, 21, 89 ms after DONE")


def main():
    _args, sil = setup()
    timeout_stop_in_speed_mode(sil)
    timeout_stop_in_position_mode(sil)
    stale_heartbeat(sil)
    heartbeat_min(sil)
    position_mode(sil)
    foreign_flood(sil)
    enable_after_commissioning(sil)
    return report(fails)


if __name__ == "__main__":
    sys.exit(main())
