"""The `mdtool` CAN subcommands (added to mdtool.cli's parser).

Every command that talks to a drive takes --interface/--channel/--bitrate
(any python-can interface), --node and --timeout. Every argument and input
file is checked before the first frame is sent. Exit codes: 0 ok,
2 usage (bad argument, file, or a value refused here before sending),
3 no reply within the timeout, 4 refused by the drive (its reason printed),
5 `calibrate --cogging`: the calibration ran and failed (its named failure
printed), 1 other failures (frames lost while recording, a bus or file
error, a reply no drive sends),
130 / 143 interrupted by SIGINT (Ctrl-C) / SIGTERM (`run` has sent DISABLE,
`calibrate` ABORT).
"""
import contextlib
import json
import math
import os
import signal
import sys
import threading
import time

from .errors import Interrupted, UsageError


def bounded(lo, hi, unit="s", low_open=False):
    """An argparse type: a finite number in [lo, hi] (or (lo, hi]); anything
    else is a usage error (exit 2) before anything is sent."""
    import argparse

    def parse(text):
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not (math.isfinite(v) and (lo < v if low_open else lo <= v) and v <= hi):
            raise argparse.ArgumentTypeError(
                f"{text} is outside {'(' if low_open else '['}{lo:g}, {hi:g}] {unit}".rstrip())
        return v
    return parse


def count(lo, hi):
    import argparse

    def parse(text):
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(f"{v} is outside [{lo}, {hi}]")
        return v
    return parse


@contextlib.contextmanager
def signals_raise():
    """While a command talks to a drive, SIGINT and SIGTERM raise
    Interrupted in the main thread, so every `finally` on the way out runs
    (run's DISABLE, calibrate's ABORT); the previous handlers come back
    after. Outside the main thread (a library caller) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_signal(signum, _frame):
        raise Interrupted(signum)
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _bus_args(p, with_node=True):
    g = p.add_argument_group("CAN bus (python-can)")
    g.add_argument("--interface", "-i", default=os.environ.get("MDTOOL_INTERFACE", "socketcan"),
                   help="python-can interface: socketcan, slcan, pcan, virtual, ... "
                        "(default socketcan, or $MDTOOL_INTERFACE)")
    g.add_argument("--channel", "-c", default=os.environ.get("MDTOOL_CHANNEL", "can0"),
                   help="channel: can0, vcan0, /dev/ttyACM0, PCAN_USBBUS1, ... (default can0)")
    g.add_argument("--bitrate", "-b", type=count(1000, 10_000_000),
                   help="bit rate [bit/s] where the interface sets it")
    g.add_argument("--host", help="socketcand: the server's address (or $MDTOOL_HOST, or python-can's "
                                  "configuration: CAN_CONFIG, ~/.canrc)")
    g.add_argument("--port", type=count(1, 65535),
                   help="socketcand: the server's TCP port (or $MDTOOL_PORT, or python-can's configuration)")
    if with_node:
        g.add_argument("--node", "-n", type=count(0, 62), default=1, help="drive node id 0..62 (default 1)")
        g.add_argument("--timeout", type=bounded(0.0, 60.0, low_open=True), default=1.0,
                       help="reply timeout [s], (0, 60] (default 1)")
    g.add_argument("--dbc", help="DBC file (default: the package's, see mdtool.can.paths)")


def _bus_opts(a):
    """The interface options beyond interface/channel/bitrate (socketcand's
    host and port) given as options or in $MDTOOL_HOST / $MDTOOL_PORT;
    python-can's configuration supplies what is not given."""
    host = a.host or os.environ.get("MDTOOL_HOST") or None
    port = a.port
    if port is None and os.environ.get("MDTOOL_PORT"):
        try:
            port = int(os.environ["MDTOOL_PORT"])
        except ValueError:
            raise UsageError(f"$MDTOOL_PORT={os.environ['MDTOOL_PORT']!r}: a TCP port number") from None
    return {k: v for k, v in (("host", host), ("port", port)) if v is not None}


def _db(a):
    from .dbc import load_db
    return load_db(a.dbc)


class _Session:
    def __init__(self, a):
        from .client import Drive
        from .record import open_bus
        self.db = _db(a)
        self.bus = open_bus(a.interface, a.channel, a.bitrate, **_bus_opts(a))
        self.drive = Drive(self.bus, self.db, a.node, a.timeout)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.bus.shutdown()


# ------------------------------------------------------------------ scan
def cmd_scan(a):
    from .client import scan
    from .record import open_bus
    db = _db(a)
    bus = open_bus(a.interface, a.channel, a.bitrate, **_bus_opts(a))
    try:
        found = scan(bus, db, a.timeout)
    finally:
        bus.shutdown()
    if not found:
        print(f"no drive heartbeat on {a.interface}:{a.channel} within {a.timeout:g} s", file=sys.stderr)
        return 3
    for node, hb in sorted(found.items()):
        print(f"node {node}: mode {hb['mode']}, control {hb['control_mode']}, "
              f"enabled {hb['enabled']}, faults 0x{hb['faults']:04X}, config {hb['cfg_status']}")
    return 0


# ---------------------------------------------------------------- status
def cmd_status(a):
    with _Session(a) as s:
        hb = s.drive.heartbeat()
        latest = {}
        t_end = time.monotonic() + a.listen
        while time.monotonic() < t_end:
            d = s.drive.decode(s.bus.recv(0.05))
            if d and d[0] != "HEARTBEAT":
                latest[d[0]] = d[1]
    if a.json:
        print(json.dumps({"node": a.node, "heartbeat": hb, "telemetry": latest}, indent=1))
        return 0
    print(f"node {a.node}: " + ", ".join(f"{k} {v}" for k, v in hb.items() if k != "seq"))
    for name, vals in sorted(latest.items()):
        print(f"  {name}: " + ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                                        for k, v in vals.items() if k != "seq"))
    return 0


# ---------------------------------------------------------------- config
def _params(a):
    from .params import ParamTable
    return ParamTable(a.params_meta)


def _read(drive, p):
    from .params import from_raw
    return from_raw(p, drive.param("READ", p["id"]))


def _write(drive, p, raw):
    """WRITE; a new node id or bit rate (access reboot) is staged only by
    the CONFIRM the drive asks for as the very next request."""
    from .errors import Refused
    try:
        return drive.param("WRITE", p["id"], raw)
    except Refused as e:
        if e.status != "NEEDS_CONFIRM":
            raise
    print(f"{p['name']}: confirmed (in effect after APPLY, SAVE and a reset of the drive)")
    return drive.param("CONFIRM", p["id"], raw)


def cmd_config(a):
    from .files import check_writable
    from .params import fmt_value, from_raw, read_toml, to_raw, write_toml
    table = _params(a)
    if a.action == "list":  # offline: the table itself
        for p in table.params:
            print(f"{p['id']:>4} {p['name']:<24} {p['type']} {table.range_text(p):<32} {p['access']:<9} {p['desc']}")
        return 0
    # checks that need no drive come first
    writes = []
    if a.action == "set":
        if not a.items:
            raise UsageError("config set NAME=VALUE ...")
        for it in a.items:
            k, eq, v = it.partition("=")
            if not eq:
                raise UsageError(f"expected NAME=VALUE, got {it!r}")
            writes.append((k, table.check(k, v)))
    elif a.action == "load":
        if not a.items or len(a.items) != 1:
            raise UsageError("config load FILE (a motor, board or drive TOML file)")
        writes = [(k, table.check(k, v)) for k, v in read_toml(a.items[0], table)]
    elif a.action == "export":
        if not a.items or len(a.items) != 1:
            raise UsageError("config export FILE")
        check_writable(a.items[0], "config export file")
    elif a.action in ("save", "defaults") and a.items:
        raise UsageError(f"config {a.action} takes no names or files (got {' '.join(a.items)})")
    names = a.items if a.action == "get" else []
    sel = [table.get(n) for n in names] if names else table.params

    with _Session(a) as s:
        d = s.drive
        if a.action == "get":
            for p in sel:
                v = _read(d, p)
                print(f"{p['name']:<24} {fmt_value(p, v):>14} {p['unit']:<8} "
                      f"{table.range_text(p):<32} {p['access']}")
            return 0
        if a.action == "export":
            vals = {p["name"]: _read(d, p) for p in table.params}
            write_toml(a.items[0], table, vals,
                       [f"Drive configuration of node {a.node} ({a.interface}:{a.channel}), "
                        "exported by `mdtool config export`.",
                        "[motor] and [board] use the keys of sim/motors/*.toml; [drive] the rest.",
                        "Staged values (what APPLY applies); load with `mdtool config load FILE`."])
            print(f"{a.items[0]}: {len(vals)} parameters")
            return 0
        if a.action == "defaults":
            d.param("LOAD_DEFAULTS")
            print("defaults staged")
        for k, v in writes:
            p = table.get(k)
            got = _write(d, p, to_raw(p, v))
            print(f"{k} = {fmt_value(p, from_raw(p, got))} {p['unit']} (staged)")
        if a.action in ("set", "load", "defaults") and not a.no_apply:
            d.param("APPLY")
            print("applied")
        if a.action == "save" or (a.action in ("set", "load", "defaults") and a.save):
            seq = d.param("SAVE")
            print(f"saved (record {seq})")
    return 0


# ------------------------------------------------------------------- run
def cmd_run(a):
    from .client import RUN_LIMITS, check_limit
    for name in ("duration", "keepalive", "settle_timeout"):
        check_limit(name, getattr(a, name), RUN_LIMITS)
    with _Session(a) as s:
        n = {"frames": 0}

        def on_frame(name, vals):
            n["frames"] += 1
            if name == "SPEED" and a.verbose:
                print(f"omega {vals['omega_m_rad_s']:.3f} rad/s (ref {vals['omega_ref_rad_s']:.3f})")
            if name == "POSITION" and a.verbose:
                print(f"theta {vals['theta_m_rad']:.4f} rad (multi-turn)")
            if vals.get("sat") == 1 and a.verbose:
                print(f"{name}: a value did not fit its signal (sat)")
        hb = s.drive.run(a.mode, a.setpoint, a.duration, i_d=a.id, period=a.keepalive, on_frame=on_frame,
                         settle=a.settle, settle_timeout=a.settle_timeout)
        hb_after = s.drive.wait_for(lambda n, v: n == "HEARTBEAT" and v["enabled"] == 0, a.timeout,
                                    "HEARTBEAT showing the drive disabled")[1]
    if a.settle is not None:
        print(f"settled: {a.mode} {s.drive.last_measured:.3f} within {a.settle:g} of {a.setpoint:g}")
    print(f"ran {a.mode} {a.setpoint:g} for {a.duration:g} s ({n['frames']} frames from node {a.node}); "
          f"last heartbeat while running: {hb}; now: mode {hb_after['mode']}, enabled {hb_after['enabled']}")
    return 0


# ------------------------------------------------------- record / decode
def cmd_record(a):
    from .record import record
    db = _db(a)
    rep = record(a.out, db, a.node, interface=a.interface, channel=a.channel, bitrate=a.bitrate,
                 duration=a.duration, ready=a.ready, report=a.report, bus_opts=_bus_opts(a))
    if rep["kernel_dropped"] or rep["seq_lost"]:
        print(f"mdtool: record: frames lost (kernel {rep['kernel_dropped']}, sequence gaps "
              f"{rep['seq_lost']})", file=sys.stderr)
        return 1
    return 0


def cmd_decode(a):
    from .log import decode_log, read_frames, write_csvs
    db = _db(a)
    decoded, skipped = decode_log(db, read_frames(a.log), a.node)
    for p in write_csvs(db, decoded, a.out, a.merged):
        print(p)
    if skipped:
        print(f"skipped {skipped} frames (other nodes, unknown ids or lengths)", file=sys.stderr)
    return 0


def cmd_stats(a):
    from .log import read_frames, stats_of
    db = _db(a)
    s = stats_of(db, read_frames(a.log), a.node, a.bitrate)
    print(f"{a.log}: {s['frames']} frames in {s['duration_s']:.3f} s, "
          f"bus load {100 * s['bus_load']:.2f} % of {a.bitrate / 1000:g} kbit/s")
    print(f"{'message':<18}{'frames':>8}{'rate_hz':>10}{'gaps':>6}{'lost':>6}")
    for name, e in s["messages"].items():
        print(f"{name:<18}{e['frames']:>8}{e['rate_hz']:>10.1f}{e['gaps']:>6}{e['lost']:>6}")
    print(f"frames lost (sequence gaps): {s['lost_total']}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(s, f, indent=1)
    return 0


def cmd_convert(a):
    from .log import convert
    print(f"{a.dst}: {convert(a.src, a.dst)} frames")
    return 0


def cmd_calibrate_cogging(a):
    """calibrate --cogging (mdtool.can.cogging): exit 0 the map in use (and
    saved with --save), 3 no reply or CAL_TIMEOUT, 4 refused before it ran
    (FAULT, BUSY, PENDING, NO_OFFSET, NOT_READY), 5 it ran and failed
    (NO_OFFSET, ROTOR_BLOCKED, MEAS, MAP_IMPLAUSIBLE_*, ABORTED, ...), 1 a
    reply no drive sends; DISABLE is sent on every way out once it enabled."""
    from .cogging import BOUND_S, CAL_PASSES, COG_N, NOMINAL_S, PHASE_TEXT, calibrate_cogging
    given = [o for o, v in (("--i-test", a.i_test), ("--v-test-max", a.v_test_max),
                            ("--speed-max", a.speed_max), ("--json", a.json)) if v]
    if given:
        raise UsageError(f"calibrate --cogging takes no {', '.join(given)} (the commissioning's "
                         "options); nothing sent")
    shown = {}

    def progress(phase, prog):  # one line per change of phase or percentage
        line = (f"  pass {prog.pass_no + 1}/{CAL_PASSES} {PHASE_TEXT[phase]:<13} {prog.percent:>3} %  "
                f"angle points {prog.done[0]:>4}/{COG_N} forward, {prog.done[1]:>4}/{COG_N} back")
        if not a.quiet and shown.get("line") != line:
            shown["line"] = line
            print(line, flush=True)
    if not a.quiet:
        print(f"anticogging calibration: {CAL_PASSES} passes of a turn forward and one back, about "
              f"{NOMINAL_S:.0f} s "
              f"(gives up after {a.cal_timeout:.0f} s; its own bound {BOUND_S:.0f} s)", flush=True)
    with _Session(a) as s:
        calibrate_cogging(s.drive, a.cal_timeout, save=a.save, on_progress=progress)
    return 0


def cmd_calibrate(a):
    if a.cogging:
        return cmd_calibrate_cogging(a)
    from .calibrate import ITEMS, calibrate, check_failed, rows
    from .errors import Refused
    from .params import fmt_value, from_raw
    table = _params(a)
    if a.json:
        from .files import check_writable
        check_writable(a.json, "--json file")
    with _Session(a) as s:
        d = s.drive
        # the start frame's options within their signals, before any frame
        try:
            d.frame("COMMISSION_CMD", action=1, i_test_a=a.i_test, v_test_max_v=a.v_test_max,
                    speed_max_m_rad_s=a.speed_max)
        except UsageError as e:
            raise UsageError(f"calibrate options refused: {e}; nothing sent") from None
        # the configuration in use, where the drive serves its parameters
        present = {}
        try:
            for _item, (_res, pname, _u) in ITEMS.items():
                p = table.get(pname)
                present[pname] = from_raw(p, d.param("READ", p["id"]))
        except Refused as e:
            if e.status != "UNSUPPORTED":
                raise
            present = {}

        shown = {}

        def progress(v):  # one line per change of step or percentage
            line = f"  {v['step']:<11} {int(v['progress_pct']):>3} %"
            if not a.quiet and shown.get("line") != line:
                shown["line"] = line
                print(line, flush=True)
        summ = calibrate(d, a.i_test, a.v_test_max, a.speed_max, a.progress_timeout, progress,
                         abort_on_exit=True)
        if a.json:
            with open(a.json, "w") as f:
                json.dump(dict(summ, present=present), f, indent=1)
        check_failed(summ)
        print(f"{'parameter':<20}{'measured':>14}  {'unit':<10}{'in use':>14}{'change':>10}")
        for pname, v, unit, old, ch in rows(summ["results"], present, table, summ["valid"]):
            print(f"{pname:<20}{v:>14.6g}  {unit:<10}"
                  f"{fmt_value(table.get(pname), old) if old is not None else '-':>14}{ch:>10}")
        if summ["sensorless"]:
            print("measured without an encoder: R, L and the flux (I-f spin); pole_pairs is the "
                  "one in use, no encoder offset or direction, no J or B (not staged)")
        if not summ["staged"]:
            print("not staged: this drive has no parameter service (results shown only)")
            if a.save:
                raise Refused("--save: the drive did not stage the results (no parameter service)",
                              status="UNSUPPORTED")
            return 0
        if not a.save:
            print("staged on the drive, not in effect: with --save mdtool applies them "
                  "(PARAM_REQ APPLY, the whole-set check) and stores them (SAVE)")
            return 0
        d.param("APPLY")
        seq = d.param("SAVE")
        print(f"applied and saved (record {seq})")
    return 0


# ----------------------------------------------------------------- flash
def cmd_flash(a):
    from . import image
    from .flash import Flasher, parse_nodes, read_image
    from .record import open_bus
    nodes = parse_nodes(a.node)
    data, hdr = read_image(a.image)  # checked before the bus is touched
    print(f"{a.image}: {image.describe(hdr)}")
    db = _db(a)
    bus = open_bus(a.interface, a.channel, a.bitrate, **_bus_opts(a))
    try:
        for n in nodes:
            Flasher(bus, db, n, a.timeout, a.retries,
                    progress=None if a.quiet else (lambda s: print(s, flush=True))).flash(data, hdr, a.wait)
            print(f"node {n}: updated to {image.version_text(hdr['app_version'])}")
    finally:
        bus.shutdown()
    return 0


# --------------------------------------------------------------- monitor
def cmd_monitor(a):
    from .monitor import monitor
    if a.png:
        from .files import check_writable
        check_writable(a.png, "--png file")
    with _Session(a) as s:
        return monitor(s.drive, a.signals, window_s=a.window, frames=a.frames, png=a.png,
                       no_gui=a.no_gui, duration=a.duration)


def add_parsers(sub):
    p = sub.add_parser("scan", help="nodes on the bus (from their heartbeats)")
    _bus_args(p, with_node=False)
    p.add_argument("--timeout", type=bounded(0.0, 60.0, low_open=True), default=1.0,
                   help="listen this long [s], (0, 60]")
    p.set_defaults(fn=cmd_scan)

    p = sub.add_parser("status", help="a drive's heartbeat and latest telemetry")
    _bus_args(p)
    p.add_argument("--listen", type=bounded(0.0, 60.0), default=0.3,
                   help="collect telemetry this long [s], [0, 60]")
    p.add_argument("--json", action="store_true")
    p.set_defaults(fn=cmd_status)

    p = sub.add_parser("config", help="parameters: list | get [NAME...] | set NAME=V... | save | "
                       "load FILE | export FILE | defaults")
    p.add_argument("action", choices=["list", "get", "set", "save", "load", "export", "defaults"])
    p.add_argument("items", nargs="*")
    p.add_argument("--no-apply", action="store_true", help="set/load/defaults: stage only, no APPLY")
    p.add_argument("--save", action="store_true", help="set/load/defaults: SAVE after APPLY")
    p.add_argument("--params-meta", help="parameter table (default: the package's params_meta.json)")
    _bus_args(p)
    p.set_defaults(fn=cmd_config)

    p = sub.add_parser("run", help="run a mode with a setpoint; the keep-alive is sent for you")
    p.add_argument("mode", choices=["current", "speed", "position"])
    p.add_argument("setpoint", type=float,
                   help="current: i_q [A]; speed: [rad/s]; position: multi-turn target [rad] from the "
                        "position at enable")
    p.add_argument("--id", type=float, default=0.0, help="current mode: i_d [A]")
    p.add_argument("--duration", type=bounded(0.0, 86400.0), default=1.0,
                   help="[s], [0, 86400] (then disable)")
    p.add_argument("--keepalive", type=bounded(0.01, 1.0), default=0.05,
                   help="keep-alive period [s], [0.01, 1] (keep it under half the drive's "
                        "can_timeout_s)")
    p.add_argument("--settle", type=float, metavar="TOL",
                   help="after --duration, hold until 3 frames in a row of the measured speed "
                   "[rad/s] or i_q [A] lie within TOL of the setpoint (exit 3 if not)")
    p.add_argument("--settle-timeout", type=bounded(0.0, 3600.0), default=30.0,
                   help="longest hold for --settle [s], [0, 3600]")
    p.add_argument("--verbose", "-v", action="store_true")
    _bus_args(p)
    p.set_defaults(fn=cmd_run)

    p = sub.add_parser("flash", help="an application image into drives over CAN, through their "
                       "bootloader: checked, written, verified, started (firmware/boot/README.md)")
    p.add_argument("image", help="a sealed application image (.bin of the build, e.g. "
                   "build/stm32f405-vesc6/firmware/targets/stm32f405/mc_stm32f405.bin)")
    p.add_argument("--node", "-n", action="append", metavar="N[,N...]",
                   help="node id(s), flashed in turn (repeat or separate by commas; default 1)")
    p.add_argument("--timeout", type=bounded(0.0, 60.0, low_open=True), default=1.0,
                   help="reply timeout [s], (0, 60] (default 1)")
    p.add_argument("--retries", type=count(0, 20), default=3,
                   help="resends of a refused or unanswered block, 0..20 (default 3)")
    p.add_argument("--wait", type=bounded(0.0, 600.0, low_open=True), default=10.0,
                   help="longest wait for the bootloader, and for the new image to answer [s], (0, 600]")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines")
    _bus_args(p, with_node=False)
    p.set_defaults(fn=cmd_flash)

    p = sub.add_parser("monitor", help="live plot of chosen signals (matplotlib)")
    p.add_argument("signals", nargs="+", help="MESSAGE.signal, e.g. SPEED.omega_m_rad_s CURRENTS.i_q_a")
    p.add_argument("--window", type=bounded(0.0, 3600.0, low_open=True), default=5.0,
                   help="seconds shown, (0, 3600]")
    p.add_argument("--frames", type=count(1, 1_000_000), help="stop after this many animation frames")
    p.add_argument("--duration", type=bounded(0.0, 1e6, low_open=True),
                   help="stop after this long [s], (0, 1e6]")
    p.add_argument("--png", help="write the final figure here")
    p.add_argument("--no-gui", action="store_true", help="headless (Agg): collect, then write --png")
    _bus_args(p)
    p.set_defaults(fn=cmd_monitor)

    p = sub.add_parser("record", help="record the bus (.log candump, .blf, .asc, .mf4, .csv, .trc)")
    p.add_argument("out")
    p.add_argument("--duration", type=bounded(0.0, 1e6), default=0.0,
                   help="seconds, [0, 1e6] (0: until Ctrl-C / SIGTERM)")
    p.add_argument("--ready", help="touch this file once the bus is open")
    p.add_argument("--report", help="frames, kernel drops, sequence gaps as JSON")
    _bus_args(p)
    p.set_defaults(fn=cmd_record)

    for name, fn, hlp in (("decode", cmd_decode, "decode a log (any format) to CSV"),
                          ("stats", cmd_stats, "frames per message, sequence gaps, bus load")):
        p = sub.add_parser(name, help=hlp)
        p.add_argument("log")
        p.add_argument("--node", "-n", type=count(0, 62), default=1)
        p.add_argument("--dbc")
        if name == "decode":
            p.add_argument("--out", required=True, help="output directory")
            p.add_argument("--merged", action="store_true", help="one merged.csv")
        else:
            p.add_argument("--bitrate", type=bounded(1e3, 1e7, "bit/s"), default=1e6,
                           help="[bit/s] (default 1e6)")
            p.add_argument("--json")
        p.set_defaults(fn=fn)

    p = sub.add_parser("convert", help="copy a log into another format (by extension)")
    p.add_argument("src")
    p.add_argument("dst")
    p.set_defaults(fn=cmd_convert)

    from .cogging import DEFAULT_TIMEOUT_S
    p = sub.add_parser("calibrate", help="commission a motor: measure R, Ld, Lq, flux, pole pairs, "
                       "encoder offset and direction, current-sensor offsets; --save stores them. "
                       "--cogging: the anticogging map instead")
    p.add_argument("--cogging", action="store_true",
                   help="calibrate the anticogging map (anticogging 2; the drive turns once each way "
                        "in SPEED), then use it (anticogging 1); --save stores it")
    p.add_argument("--cal-timeout", type=bounded(0.0, DEFAULT_TIMEOUT_S, low_open=True),
                   default=DEFAULT_TIMEOUT_S,
                   help=f"--cogging: give up after this long [s], (0, {DEFAULT_TIMEOUT_S:.1f}] (default: "
                        "the calibration's own time bound plus 10 %%)")
    p.add_argument("--i-test", type=float, default=0.0, help="test current [A] (0: the drive's default)")
    p.add_argument("--v-test-max", type=float, default=0.0,
                   help="largest test voltage [V] (0: the drive's default)")
    p.add_argument("--speed-max", type=float, default=0.0,
                   help="cap of the flux spin-up, mechanical [rad/s] (0: the drive's default)")
    p.add_argument("--save", action="store_true", help="APPLY the staged results and SAVE them")
    p.add_argument("--progress-timeout", type=bounded(0.0, 3600.0, low_open=True), default=5.0,
                   help="give up when no progress arrives this long [s], (0, 3600]")
    p.add_argument("--json", help="write status, results and the configuration in use here")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines")
    p.add_argument("--params-meta", help="parameter table (default: the package's params_meta.json)")
    _bus_args(p)
    p.set_defaults(fn=cmd_calibrate)
