#!/usr/bin/env python3
"""mdtool's CAN commands (tools/mdtool/src/mdtool/can) on the SIL firmware's
frames and on python-can's virtual bus:

- the SIL drive (mcsim can-telemetry, the demo command script) writes a
  candump log; its frames are replayed on a python-can virtual bus while
  `mdtool record` (the library function) records that bus to .log, .blf,
  .asc and .mf4; every file reads back to the frames sent (ids, data,
  order; the bus stamps frames on arrival), the .mf4 also through asammdf directly;
- the SIL log converted to each format (`mdtool convert`, its simulated
  time stamps kept): `mdtool decode` and `mdtool stats` of every format
  equal mc_can.py's on the SIL log;
- the CLI's errors: no reply within the timeout (exit 3), a u32 not whole,
  a readonly or unknown parameter, a log format / interface, a misplaced
  key of a TOML file (exit 2; that nothing is sent then: can.mdtool_bus);
- the DBC and the parameter table the package uses are the repository's
  (and the installed copies equal them).

    test_mdtool_can.py --mcsim MCSIM --work DIR
"""
import argparse
import itertools
import json
import os
import shutil
import socket
import subprocess
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SRC = os.path.join(ROOT, "tools", "mdtool", "src")
sys.path.insert(0, SRC)

from mdtool.can import dbc, log, paths, record  # noqa: E402

fails = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)


def mdtool(*args, env=None, **kw):
    env = dict(env or os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [SRC, env.get("PYTHONPATH")]))
    return subprocess.run([sys.executable, "-m", "mdtool.cli", *args], capture_output=True, text=True,
                          env=env, timeout=120, **kw)


def same_frames(a, b, tol):
    if len(a) != len(b):
        return f"{len(a)} vs {len(b)} frames"
    ta0, tb0 = a[0][0], b[0][0]
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        if (x[2], x[3], x[4]) != (y[2], y[3], y[4]):
            return f"frame {i}: {x} vs {y}"
        if abs((x[0] - ta0) - (y[0] - tb0)) > tol:
            return f"frame {i}: time {x[0] - ta0} vs {y[0] - tb0}"
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    W = a.work

    # ---- data files: one DBC, one parameter table
    check(os.path.samefile(paths.dbc_path(), os.path.join(ROOT, "tools", "can", "motordrive.dbc")),
          "from the source tree the package reads tools/can/motordrive.dbc")
    check(os.path.samefile(paths.params_meta_path(), os.path.join(ROOT, "tools", "config", "params_meta.json")),
          "from the source tree the package reads tools/config/params_meta.json")
    r = subprocess.run([sys.executable, "-c", "import mdtool.can.paths as p, os; print(p._DATA)"],
                       capture_output=True, text=True, cwd="/", env={k: v for k, v in os.environ.items()
                                                                    if k != "PYTHONPATH"})
    data = r.stdout.strip()
    if r.returncode == 0 and os.path.isdir(data):
        for name, repo in (("motordrive.dbc", "tools/can/motordrive.dbc"),
                           ("params_meta.json", "tools/config/params_meta.json")):
            with open(os.path.join(data, name), "rb") as f1, open(os.path.join(ROOT, repo), "rb") as f2:
                check(f1.read() == f2.read(), f"installed copy {data}/{name} equals {repo}")
    else:
        print(f"note: the venv's mdtool has no CAN data folder ({(r.stderr.strip().splitlines() or [data])[-1]}); "
              "run tools/bootstrap.sh setup to install this tree's package")

    # ---- a commissioning refusal the error field has no bit for: RANGE plus
    # COMMISSION_STATUS.detail, through the DBC's codec and named by mdtool
    from mdtool.can import calibrate as cal
    from mdtool.can import client
    from mdtool.can.errors import Refused
    dbm = dbc.find_message(dbc.load_db(), "COMMISSION_STATUS")
    raw = dbc.encode_signals(dbm, {"step": 8, "error": 1 << 9, "detail": 3, "seq": 7})
    col = cal.Collector()
    col.feed("COMMISSION_STATUS", client.named(dbm, dbc.decode_signals(dbm, raw)))
    summ = col.summary()
    check(summ["detail"] == "MECH_SPIN_COAST" and summ["error"] == ["RANGE"],
          f"COMMISSION_STATUS error RANGE, detail 3 decodes as {summ['error']} {summ['detail']}")
    try:
        cal.check_failed(summ)
        check(False, "a FAILED status raises Refused")
    except Refused as e:
        check("MECH_SPIN_COAST" in str(e) and "not viscous" in str(e) and e.status == "MECH_SPIN_COAST",
              f"the refusal names its reason: {e}")
    summ0 = dict(summ, detail="NONE")
    try:
        cal.check_failed(summ0)
    except Refused as e:
        check(e.status == "RANGE", f"without a detail RANGE stays RANGE: {e.status}")

    # ---- the SIL's frames
    sil_log = os.path.join(W, "sil.log")
    env = dict(os.environ, MCSIM_CAN_LOG=sil_log,
               MCSIM_CAN_CMDS=os.path.join(ROOT, "tools", "can", "demo_commands.log"))
    subprocess.run([a.mcsim, "run", "can-telemetry", "--out", W], env=env, check=True,
                   stdout=subprocess.DEVNULL)
    db = dbc.load_db()
    ref = log.read_candump(sil_log)
    check(len(ref) > 500, f"the SIL wrote {len(ref)} frames")

    # ---- record from a python-can virtual bus into every format
    import can

    def record_into(rep, out, chan, ready, stop):
        rep.update(record.record(out, db, 1, interface="virtual", channel=chan, ready=ready, stop=stop,
                                 log=lambda *_: None))
    for ext in (".log", ".blf", ".asc", ".mf4"):
        out = os.path.join(W, "rec" + ext)
        ready = os.path.join(W, "ready" + ext)
        stop = {"now": False}
        rep = {}
        chan = "mdtool_test" + ext
        th = threading.Thread(target=record_into, args=(rep, out, chan, ready, stop))
        th.start()
        while not os.path.exists(ready):
            time.sleep(0.01)
        with can.Bus(interface="virtual", channel=chan) as tx:
            for fr in ref:
                tx.send(log.message_of_frame(fr))
        t_end = time.monotonic() + 20
        while time.monotonic() < t_end:  # the recorder has them all once it idles
            time.sleep(0.2)
            if (os.path.getsize(out) > 0 and ext != ".log") or ext == ".log":
                break
        time.sleep(0.5)
        stop["now"] = True
        th.join(30)
        back = log.read_frames(out)
        err = same_frames(ref, back, 1e9)  # times: stamped on arrival (checked by convert below)
        if err is None and any(y[0] < x[0] for x, y in itertools.pairwise(back)):
            err = "time stamps go backwards"
        check(err is None and rep.get("frames") == len(ref),
              f"record {ext}: {rep.get('frames')} frames written, read back identical" + (f" ({err})" if err else ""))
        check(rep.get("seq_gaps") == 0 and rep.get("kernel_dropped") is None,
              f"record {ext}: sequence gaps {rep.get('seq_gaps')}, kernel drops n/a on virtual")
        conv = os.path.join(W, "conv" + ext)
        r = mdtool("convert", sil_log, conv)
        check(r.returncode == 0 and same_frames(ref, log.read_frames(conv), 2e-6) is None,
              f"convert the SIL log to {ext}: same frames and times")
        out = conv
        # decode/stats of this file equal mc_can.py's on the SIL log
        st_ref = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "can", "mc_can.py"), "stats",
                                 sil_log, "--json", os.path.join(W, "ref.json")], capture_output=True)
        r = mdtool("stats", out, "--json", os.path.join(W, f"st{ext}.json"))
        with open(os.path.join(W, "ref.json")) as f1, open(os.path.join(W, f"st{ext}.json")) as f2:
            A, B = json.load(f1), json.load(f2)
        same = st_ref.returncode == 0 and r.returncode == 0 and A["frames"] == B["frames"] and \
            A["lost_total"] == B["lost_total"] and abs(A["bus_load"] - B["bus_load"]) < 1e-6 and \
            {k: (v["frames"], v["gaps"], v["lost"]) for k, v in A["messages"].items()} == \
            {k: (v["frames"], v["gaps"], v["lost"]) for k, v in B["messages"].items()}
        check(same, f"mdtool stats {ext} equals mc_can.py stats of the SIL log")
        r = mdtool("decode", out, "--out", os.path.join(W, "dec" + ext))
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "can", "mc_can.py"), "decode",
                        sil_log, "--out", os.path.join(W, "dec_ref")], capture_output=True, check=True)
        ok = r.returncode == 0
        for name in sorted(os.listdir(os.path.join(W, "dec_ref"))):
            with open(os.path.join(W, "dec_ref", name)) as f1, open(os.path.join(W, "dec" + ext, name)) as f2:
                r1 = [ln.split(",") for ln in f1.read().splitlines()]
                r2 = [ln.split(",") for ln in f2.read().splitlines()]
            # signal values identical; the time columns to 1 us (BLF/ASC/MF4 store their own clock)
            ok = ok and len(r1) == len(r2) and all(x[2:] == y[2:] and
                                                   (i == 0 or abs(float(x[0]) - float(y[0])) < 2e-6)
                                                   for i, (x, y) in enumerate(zip(r1, r2, strict=True)))
        check(ok, f"mdtool decode {ext} equals mc_can.py decode of the SIL log")
    # the MF4 through asammdf itself
    from asammdf import MDF
    mdf = MDF(os.path.join(W, "rec.mf4"))
    ids = None
    for g, grp in enumerate(mdf.groups):
        for ch in grp.channels:
            if ch.name.endswith("CAN_DataFrame.ID"):
                ids = mdf.get(ch.name, group=g).samples
                break
        if ids is not None:
            break
    check(ids is not None and [int(i) for i in ids] == [fr[2] for fr in ref if not fr[4]],
          f"asammdf reads the MF4's identifiers ({0 if ids is None else len(ids)} CAN_DataFrame.ID samples)")

    # mdtool reads MF4 data frames as whole arrays (python-can's MF4Reader is
    # O(n^2)): the same frames as python-can's own reader, on a file with
    # standard and extended ids and every data length
    small = os.path.join(W, "mix.mf4")
    mix = [(fr[0], fr[1], (fr[2] | 0x1000) if k % 3 == 0 else fr[2], fr[3][:k % 9],
            {"ext"} if k % 3 == 0 else set()) for k, fr in enumerate(ref[:600])]
    w = can.Logger(small)
    for fr in mix:
        w.on_message_received(log.message_of_frame(fr))
    w.stop()
    fast = log._read_mf4_data_frames(small)
    with can.LogReader(small) as rd:
        slow = [log.frame_of_message(m) for m in rd]
    check(fast is not None and fast == slow and len(fast) == len(mix),
          f"MF4 array reader equals python-can's MF4Reader ({0 if fast is None else len(fast)} frames)")

    # ---- the CLI's errors (python-can virtual bus: nobody answers). What a
    # refused command sends (nothing) is checked on the bus the subprocess
    # uses in can.mdtool_bus (test_mdtool_bus.py): a listener here would not
    # see a subprocess's virtual bus.
    bus = ["--interface", "virtual", "--channel", "mdtool_errors", "--timeout", "0.3"]
    r = mdtool("config", "get", "r_ohm", *bus)
    check(r.returncode == 3 and "no PARAM_REPLY" in r.stderr and "within 0.3 s" in r.stderr,
          f"no reply: exit 3, '{r.stderr.strip()}'")
    r = mdtool("config", "set", "pole_pairs=7.5", *bus)
    check(r.returncode == 2 and "whole number" in r.stderr, f"u32 not whole: '{r.stderr.strip()}'")
    r = mdtool("config", "set", "cfg_store_seq=3", *bus)
    check(r.returncode == 2 and "readonly" in r.stderr, f"readonly: '{r.stderr.strip()}'")
    r = mdtool("config", "get", "no_such_param", *bus)
    check(r.returncode == 2 and "unknown parameter 'no_such_param'" in r.stderr, f"unknown: '{r.stderr.strip()}'")
    bad = os.path.join(W, "bad.toml")
    with open(bad, "w") as f:
        f.write("[motor]\nr_ohm = 0.1\nvbus_v = 24.0\n")
    r = mdtool("config", "load", bad, *bus)
    check(r.returncode == 2 and "vbus_v belongs in [board]" in r.stderr, f"misplaced key: '{r.stderr.strip()}'")
    r = mdtool("config", "load", os.path.join(ROOT, "sim", "motors", "odrive-d5065.toml"), *bus)
    check(r.returncode == 3 and "PARAM_REPLY" in r.stderr,
          "a motor file of the simulator passes the local checks (then: no reply, exit 3)")
    r = mdtool("record", os.path.join(W, "x.xyz"), *bus, "--duration", "0.1")
    check(r.returncode == 2 and "unknown log format" in r.stderr, f"log format: '{r.stderr.strip()}'")
    r = mdtool("status", "--interface", "no_such_interface", "--channel", "x")
    check(r.returncode == 2 and "cannot open CAN interface" in r.stderr, f"interface: '{r.stderr.strip()}'")
    r = mdtool("scan", *bus[:4], "--timeout", "0.2")
    check(r.returncode == 3 and "no drive heartbeat" in r.stderr, f"scan, nobody there: '{r.stderr.strip()}'")
    r = mdtool("decode", os.path.join(W, "missing.log"), "--out", W)
    check(r.returncode == 2 and "cannot read" in r.stderr, f"missing log: '{r.stderr.strip()}'")
    # socketcand: no host/port anywhere; nobody listening (refused at once:
    # python-can's own client would retry for 10 s)
    env = {k: v for k, v in os.environ.items() if k not in ("CAN_CONFIG", "MDTOOL_HOST", "MDTOOL_PORT")}
    r = mdtool("scan", "-i", "socketcand", env=dict(env, HOME=W))
    check(r.returncode == 2 and "give the server's --host and --port" in r.stderr,
          f"socketcand without host and port: '{r.stderr.strip()}'")
    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]  # closed again: nobody listens there
    t0 = time.monotonic()
    r = mdtool("status", "-i", "socketcand", "--host", "127.0.0.1", "--port", str(port), env=dict(env, HOME=W))
    check(r.returncode == 2 and f"no server at 127.0.0.1:{port}" in r.stderr and time.monotonic() - t0 < 8,
          f"socketcand, nobody listening: '{r.stderr.strip()}' in {time.monotonic() - t0:.1f} s")

    # calibrate's table: the measured value and the one in use in the
    # parameter's convention (the drive reports the encoder's direction +-1)
    from mdtool.can import calibrate, params
    table = params.ParamTable()
    res = {v[0]: 1.0 for v in calibrate.ITEMS.values()}
    for direction, in_use, want in ((-1.0, 1, (1, "same")), (1.0, 0, (0, "same")), (1.0, 1, (0, "new"))):
        res["encoder_direction"] = direction
        row = next(r for r in calibrate.rows(res, {"encoder_reversed": in_use}, table) if r[0] == "encoder_reversed")
        check((row[1], row[4]) == want, f"calibrate row: direction {direction:+g}, in use {in_use}: {row}")
    # without an encoder (valid: offsets, R, L, flux and SENSORLESS): no rows
    # for the encoder's offset and direction, J and B (not measured)
    names = [r[0] for r in calibrate.rows(res, {}, table, valid=0x17 | calibrate.VALID_SENSORLESS)]
    check("encoder_offset_rad" not in names and "encoder_reversed" not in names and
          "j_kgm2" not in names and "b_nm_s_rad" not in names and "flux_wb" in names and
          "pole_pairs" in names, f"calibrate rows without an encoder: {names}")
    check(len(calibrate.rows(res, {}, table, valid=0x3F)) == len(calibrate.ITEMS),
          "calibrate rows with every result valid: all")
    # IF_SYNC (detail 4): named in RANGE's place with its help
    summ = cal.Collector()
    summ.feed("COMMISSION_STATUS", {"step": "FAILED", "error": 1 << 9, "detail": 4, "valid": 0,
                                    "staged": 0, "progress_pct": 0, "seq": 0})
    try:
        cal.check_failed(summ.summary())
        check(False, "IF_SYNC: a FAILED status raises Refused")
    except Refused as e:
        check(e.status == "IF_SYNC" and "I-f spin" in str(e), f"IF_SYNC named: {e}")

    print(f"mdtool CAN checks: {'FAILED: ' + str(len(fails)) if fails else 'passed'}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
