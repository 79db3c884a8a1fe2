#!/usr/bin/env python3
"""The SIL drive served over socketcand (MCSIM_CAN_IF=socketcand:HOST:PORT,
hal/host SocketcandCan) against python-can's own socketcand client, as a
user on a machine without SocketCAN would use it:

1. Bit for bit: the demo command script replayed into the drive, the frames
   a python-can client receives over socketcand (identifier, data, time
   stamp to the microsecond) equal the candump-log path's, and the two runs'
   CSVs are identical (MCSIM_CAN_WAIT_CLIENTS=1: the client sees the run from
   its first frame).
2. The served drive paced to the wall clock, with a flash file, while
   another process keeps a core busy and `mdtool record rec.mf4` records the
   whole run (a second client all along): every mdtool command against it
   (scan, status, config get / set --save / export, calibrate --save,
   monitor, run speed --settle, record, decode, stats), the host and port
   given as options, as $MDTOOL_HOST/$MDTOOL_PORT and as python-can's
   CAN_CONFIG; after the save the heartbeat says cfg_status STORED; the
   monitor's HEARTBEAT.mode panel has samples; calibrate's encoder row shows
   one convention (encoder_reversed); a python-can client that disconnects
   and reconnects, one that vanishes mid-command; malformed lines from a
   client (each answered < error ... >, nothing reaches the drive, its
   heartbeat unchanged, the client still served). The recording: zero
   sequence gaps, and every telemetry frame the drive generated (the CSV's
   tm_sent_mask) at its simulated instant, none missing, none extra.

    test_socketcand.py --mcsim MCSIM --work DIR
"""
import argparse
import contextlib
import io
import json
import logging
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SRC = os.path.join(ROOT, "tools", "mdtool", "src")
sys.path.insert(0, SRC)

from mdtool import cli  # noqa: E402
from mdtool.can import dbc, log  # noqa: E402

# python-can's client warns whenever a TCP read ends inside a frame (normal)
logging.getLogger("can.interfaces.socketcand").setLevel(logging.ERROR)
fails = []
# bit i of tm_sent_mask (sim/cli/scenarios/can_telemetry.cpp)
SLOTS = ["HEARTBEAT", "CURRENTS", "VOLTAGES", "SPEED", "POSITION", "OBSERVER", "CONTROLLER", "STEPPER",
         "CURRENT_REFS", "POSITION_REF", "BUS_CURRENT", "THERMAL"]


# A busy loop that ends when this test process does: a test killed by
# ctest's timeout (SIGKILL, no finally) must not leave cores busy.
BUSY_WHILE_PARENT_LIVES = "import os\nparent = os.getppid()\nwhile os.getppid() == parent:\n    pass\n"


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        fails.append(what)


def us(t):
    return round(float(t) * 1e6)


def text(path):
    with open(path) as f:
        return f.read()


def load(path):
    return json.loads(text(path))


def start_served(mcsim, out, env_extra, args):
    """mcsim in the background serving on a free port; returns (process, port)."""
    os.makedirs(out, exist_ok=True)
    err = os.path.join(out, "mcsim.err")
    env = dict(os.environ, MCSIM_CAN_IF="socketcand:127.0.0.1:0", **env_extra)
    with open(err, "w") as f:
        p = subprocess.Popen([mcsim, "run", "can-telemetry", "--out", out, *args], env=env,
                             stdout=subprocess.DEVNULL, stderr=f)
    t_end = time.monotonic() + 30
    while time.monotonic() < t_end:
        m = re.search(r"socketcand on 127\.0\.0\.1:(\d+)", text(err))
        if m:
            return p, int(m.group(1))
        if p.poll() is not None:
            break
        time.sleep(0.05)
    p.kill()
    raise SystemExit(f"mcsim did not start serving: {text(err)}")


def mdtool(*argv, env=None):
    """One mdtool command in this process (mdtool.cli.main, the entry point
    of the command line): (exit code, output)."""
    out = io.StringIO()
    saved = dict(os.environ)
    os.environ.update(env or {})
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            try:
                rc = cli.main(list(argv))
            except SystemExit as e:
                rc = e.code if isinstance(e.code, int) else 1
    finally:
        os.environ.clear()
        os.environ.update(saved)
    print(f"  $ mdtool {' '.join(argv)}  -> exit {rc}\n    " + out.getvalue().strip().replace("\n", "\n    "),
          flush=True)
    return rc, out.getvalue()


# ------------------------------------------------------------ 1. bit for bit
def bit_for_bit(mcsim, W):
    import can
    script = os.path.join(ROOT, "tools", "can", "demo_commands.log")
    ref_dir, sc_dir = os.path.join(W, "ref"), os.path.join(W, "sc")
    os.makedirs(ref_dir)
    env = dict(os.environ, MCSIM_CAN_LOG=os.path.join(ref_dir, "can.log"), MCSIM_CAN_CMDS=script)
    env.pop("MCSIM_CAN_IF", None)
    subprocess.run([mcsim, "run", "can-telemetry", "--out", ref_dir], env=env, check=True,
                   stdout=subprocess.DEVNULL)
    ref = log.read_candump(os.path.join(ref_dir, "can.log"))
    p, port = start_served(mcsim, sc_dir, {"MCSIM_CAN_CMDS": script, "MCSIM_CAN_WAIT_CLIENTS": "1"}, [])
    got = []
    with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0") as bus:
        while True:
            m = bus.recv(2.0)
            if m is None:
                if p.poll() is not None:
                    break
                continue
            got.append((us(m.timestamp), m.arbitration_id, m.is_extended_id, bytes(m.data)))
    check(p.wait(30) == 0, "the served run ends by itself (non-real-time, after its 2 s)")
    want = [(us(t), cid, "ext" in fl, data) for t, _i, cid, data, fl in ref]
    first = next((i for i, (a, b) in enumerate(zip(want, got, strict=False)) if a != b), None)
    check(len(want) > 1000 and got == want,
          f"socketcand: the client received the candump path's {len(want)} frames bit for bit, time "
          f"stamps to the microsecond ({len(got)} received"
          + (f"; first difference at {first}: {want[first]} vs {got[first]}" if first is not None else "") + ")")
    check(text(os.path.join(ref_dir, "can-telemetry.csv")) == text(os.path.join(sc_dir, "can-telemetry.csv")),
          "the two runs' CSVs are identical (the drive did the same)")
    s = load(os.path.join(sc_dir, "can-telemetry.json"))
    r = load(os.path.join(ref_dir, "can-telemetry.json"))
    check(s["socketcand_tx_frames"] == r["can_log_frames"] and s["can_script_frames"] == r["can_script_frames"]
          == 10 and s["socketcand_tx_client_drops"] == 0,
          f"summaries: {s['socketcand_tx_frames']} frames sent, {s['can_script_frames']} script frames, "
          f"{s['socketcand_tx_client_drops']} dropped for the client")


# ------------------------------------------------------- refused settings
def refusals(mcsim, W):
    """A transport mcsim cannot use: exit 2 with the reason, nothing run."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        cases = [({"MCSIM_CAN_IF": "socketcand:127.0.0.1"}, "expected socketcand:HOST:PORT"),
                 ({"MCSIM_CAN_IF": "socketcand:127.0.0.1:70000"}, "expected socketcand:HOST:PORT"),
                 ({"MCSIM_CAN_IF": "socketcand:no.such.host:0"}, "is not an IPv4 address"),
                 ({"MCSIM_CAN_IF": f"socketcand:127.0.0.1:{port}"}, "Address already in use"),
                 ({"MCSIM_CAN_IF": "socketcand:127.0.0.1:0", "MCSIM_CAN_WAIT_CLIENTS": "x"},
                  "a number of clients"),
                 ({"MCSIM_CAN_WAIT_CLIENTS": "1"}, "on a socketcand bus only")]
        for k, (env_extra, want) in enumerate(cases):
            env = {key: v for key, v in os.environ.items() if not key.startswith("MCSIM_CAN")}
            env.update(env_extra, MCSIM_CAN_LOG=os.path.join(W, "refused.log"))
            r = subprocess.run([mcsim, "run", "can-telemetry", "--out", os.path.join(W, f"refused{k}")],
                               env=env, capture_output=True, text=True, timeout=60)
            check(r.returncode == 2 and want in r.stderr and not os.path.exists(
                os.path.join(W, f"refused{k}", "can-telemetry.json")) and not os.path.exists(
                os.path.join(W, "refused.log")),
                f"{env_extra}: exit {r.returncode}, '{r.stderr.strip()}'")


# ----------------------------------------------------- 2. the served drive
def raw_client(port):
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    return s


def read_until(s, pred, timeout=5.0):
    buf = b""
    t_end = time.monotonic() + timeout
    s.settimeout(0.2)
    while time.monotonic() < t_end and not pred(buf):
        try:
            b = s.recv(4096)
        except TimeoutError:
            continue
        if not b:
            return buf + b"<EOF>"
        buf += b
    return buf


def heartbeat(port, db):
    import can
    from mdtool.can.client import Drive
    with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0") as bus:
        return Drive(bus, db, 1, 3.0).heartbeat()


def malformed(port, db):
    """Malformed lines: refused one by one, nothing reaches the drive."""
    before = heartbeat(port, db)
    s = raw_client(port)
    check(read_until(s, lambda b: b"< hi >" in b) == b"< hi >", "raw client: greeted < hi >")
    s.sendall(b"< open can0 >")
    check(read_until(s, lambda b: b"< ok >" in b) == b"< ok >", "raw client: < open can0 > ok")
    bad = [b"< send 021 9 1 2 3 4 5 6 7 8 9 >", b"hello there\n", b"< send 12345 1 00 >",
           b"< " + b"x" * 300 + b" >", b"< fdsend 021 0 0 >"]
    s.sendall(b"".join(bad) + b"< echo >")
    r = read_until(s, lambda b: b"< echo >" in b).decode()
    errs = re.findall(r"< error ([^>]*) >", r)
    check(len(errs) == len(bad) and r.endswith("< echo >"),
          f"{len(bad)} malformed lines, each refused with a reason, the client still served: {errs}")
    s.sendall(b"< rawmode >")
    r = read_until(s, lambda b: b"< frame 021 " in b).decode()
    check(r.startswith("< ok >") and "< frame 021 " in r, "then in raw mode it receives the drive's frames")
    s.close()
    t = raw_client(port)
    read_until(t, lambda b: b"< hi >" in b)
    t.sendall(b"< open can1 >")
    r = read_until(t, lambda b: b"<EOF>" in b)
    check(r == b"< error could not open bus ><EOF>", f"another bus: refused and disconnected ({r!r})")
    t.close()
    after = heartbeat(port, db)
    keys = ("mode", "enabled", "faults", "last_error", "last_error_cmd", "stop_reason")
    check(all(before[k] == after[k] for k in keys),
          f"the drive unaffected: heartbeat {[after[k] for k in keys]} as before")
    return len(bad) + 1


def reconnect(port, db):
    """A python-can client that disconnects and reconnects; one that goes
    away in the middle of a command."""
    import can

    def some(n):
        with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0") as bus:
            ts = []
            while len(ts) < n:
                m = bus.recv(3.0)
                if m is None:
                    break
                ts.append(m.timestamp)
            return ts
    a = some(50)
    s = raw_client(port)
    read_until(s, lambda b: b"< hi >" in b)
    s.sendall(b"< open can0 >< rawmode >< send 037 1 ")  # half a command, then gone
    s.close()
    b = some(50)
    check(len(a) == 50 and len(b) == 50 and b[0] > a[-1],
          f"disconnect and reconnect: 50 frames, then 50 more from t = {b[0] if b else 0:.3f} s "
          f"(after {a[-1] if a else 0:.3f} s)")


def served_drive(mcsim, W, py):
    db = dbc.load_db()
    run = os.path.join(W, "live")
    os.makedirs(run)
    os.chdir(run)
    busy = subprocess.Popen([py, "-c", BUSY_WHILE_PARENT_LIVES])  # a core kept busy throughout
    # light enough for the wall clock on a loaded machine; a valid parameter
    # set (with --flash); the default telemetry rates; the motor without the
    # scenario's flywheel (commissioning: commission/README.md, Limits)
    p, port = start_served(mcsim, run, {"MCSIM_CAN_WAIT_CLIENTS": "1"},
                           ["--duration", "300", "--flash", "drive.flash", "--set", "realtime=1",
                            "--set", "end_after_stop_s=0.3", "--set", "pwm_hz=5000", "--set", "slow_loop_div=5",
                            "--set", "substeps=1", "--set", "bw_hz=50", "--set", "speed_pll_bw_rad_s=500",
                            "--set", "J_kgm2=0.002", "--set", "timeout_s=2.0"])
    bus = ["-i", "socketcand", "--host", "127.0.0.1", "--port", str(port)]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [SRC, os.environ.get("PYTHONPATH")])))
    with open("record.out", "w") as f:
        rec = subprocess.Popen([py, "-m", "mdtool.cli", "record", "rec.mf4", *bus, "--report", "rec.json",
                                "--ready", "rec.ready"], env=env, stdout=f, stderr=subprocess.STDOUT)
    try:
        t_end = time.monotonic() + 60
        while not os.path.exists("rec.ready") and rec.poll() is None and time.monotonic() < t_end:
            time.sleep(0.05)  # the recorder is the client the run waits for
        check(os.path.exists("rec.ready"), "the recorder connected: " + text("record.out"))
        rc, out = mdtool("scan", "-i", "socketcand", "--timeout", "2",
                         env={"CAN_CONFIG": json.dumps({"host": "127.0.0.1", "port": port})})
        check(rc == 0 and "node 1: mode IDLE" in out and "config EMPTY" in out,
              "scan (host and port from python-can's CAN_CONFIG): node 1, IDLE, config EMPTY")
        rc, out = mdtool("status", "-i", "socketcand", env={"MDTOOL_HOST": "127.0.0.1", "MDTOOL_PORT": str(port)})
        check(rc == 0 and "mode IDLE" in out and "CURRENTS" in out,
              "status ($MDTOOL_HOST, $MDTOOL_PORT): heartbeat and telemetry")
        rc, out = mdtool("config", "get", "speed_max_rad_s", *bus)
        check(rc == 0 and abs(float(out.split()[1]) - 150.0) < 1e-3, "config get: the scenario's 150 rad/s")
        rc, out = mdtool("config", "set", "speed_max_rad_s=123.5", "--save", *bus)
        check(rc == 0 and "applied" in out and "saved (record 1)" in out, "config set --save: applied, saved")
        rc, out = mdtool("status", *bus)
        check(rc == 0 and "cfg_status STORED" in out, "after the save the heartbeat says cfg_status STORED")
        rc, out = mdtool("config", "export", "drive.toml", *bus)
        check(rc == 0 and "speed_max_rad_s = 123.5" in text("drive.toml"),
              "config export: the saved value in drive.toml")
        rc, out = mdtool("calibrate", *bus, "--save", "--progress-timeout", "60", "--json", "cal.json",
                         "--timeout", "3")
        row = re.search(r"^encoder_reversed\s+(\S+)\s+(\S+)\s+(\S+)\s*$", out, re.M)
        check(rc == 0 and "DONE" in out and "applied and saved (record 2)" in out,
              "calibrate --save: progress to DONE, applied and saved")
        check(row is not None and row.groups() == ("0", "0", "same") and "encoder_direction" not in out,
              f"calibrate: the encoder row in one convention: {row.group(0).split() if row else out[-400:]}")
        rc, out = mdtool("monitor", "HEARTBEAT.mode", "CURRENTS.i_q_a", *bus, "--no-gui", "--frames", "20",
                         "--png", "monitor.png")
        m = re.search(r"HEARTBEAT\.mode (\d+) samples, CURRENTS\.i_q_a (\d+) samples", out)
        # 20 frames of 50 ms: about 1 s of a 10 Hz heartbeat and 200 Hz currents
        check(rc == 0 and m is not None and int(m.group(1)) >= 3 and int(m.group(2)) >= 50,
              f"monitor: the HEARTBEAT.mode panel has samples ({m.groups() if m else out.strip()})")
        n_bad = malformed(port, db)
        reconnect(port, db)
        rc, out = mdtool("run", "speed", "20", "--duration", "1", "--settle", "1.0", "--settle-timeout", "60",
                         *bus, "--timeout", "3")
        check(rc == 0 and "settled: speed" in out, "run speed 20 --settle 1.0")
        check(p.wait(60) == 0, "the SIL ended after the drive was disabled")
    finally:
        if p.poll() is None:
            p.kill()
        time.sleep(0.5)  # the recorder drains its socket (the server closed it)
        rec.send_signal(signal.SIGTERM)
        rec_rc = rec.wait(60)
        busy.kill()
    s = load("can-telemetry.json")
    r = load("rec.json")
    check(rec_rc == 0 and r["seq_gaps"] == 0 and r["seq_lost"] == 0 and r["frames"] > 5000,
          f"mdtool record rec.mf4 with a core busy: {r['frames']} frames, sequence gaps {r['seq_gaps']}")
    check(s["socketcand_tx_client_drops"] == 0 and s["socketcand_unflushed_clients"] == 0
          and s["socketcand_rx_overruns"] == 0 and s["socketcand_clients_max"] >= 2,
          f"server: no frame dropped for a client, none left unsent, no overrun, "
          f"{int(s['socketcand_clients_max'])} clients at once")
    check(s["socketcand_commands_refused"] == n_bad,
          f"server: exactly the {n_bad} malformed commands refused ({s['socketcand_commands_refused']})")
    check(s["cfg_saves"] == 2 and s["final_stop_reason"] == 2, "two saves; the run stopped on DISABLE")
    # every telemetry frame the drive generated is in the recording, at its instant
    frames = log.read_frames("rec.mf4")
    table = dbc.by_cmd(db)
    import csv
    with open("can-telemetry.csv") as f:
        rows = list(csv.DictReader(f))
    sent = {n: [us(row["t"]) for row in rows if int(row["tm_sent_mask"]) >> i & 1] for i, n in enumerate(SLOTS)}
    got = {n: [] for n in SLOTS}
    host = 0
    for t, _c, cid, _d, _f in frames:
        name = table[cid & dbc.CMD_MASK].name
        if name in got:
            got[name].append(t)
        elif "Host" in table[cid & dbc.CMD_MASK].senders:
            host += 1
    t0 = min(min(v) for v in got.values() if v)  # MF4 keeps time since its first frame
    t0_csv = min(min(v) for v in sent.values() if v)
    same = all([us(t - t0) for t in got[n]] == [x - t0_csv for x in sent[n]] for n in SLOTS)
    check(same and sum(map(len, sent.values())) > 5000,
          f"the recording holds every telemetry frame the drive generated at its instant "
          f"({sum(map(len, got.values()))} of {sum(map(len, sent.values()))})")
    check(host == s["socketcand_rx_frames"],
          f"the recorder saw every frame the other clients sent, as on a bus ({host} of "
          f"{int(s['socketcand_rx_frames'])})")
    rc, out = mdtool("decode", "rec.mf4", "--out", "decoded")
    check(rc == 0 and os.path.getsize(os.path.join("decoded", "HEARTBEAT.csv")) > 0, "decode rec.mf4")
    rc, out = mdtool("stats", "rec.mf4")
    check(rc == 0 and "frames lost (sequence gaps): 0" in out, "stats rec.mf4: no sequence gap")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    W = os.path.abspath(a.work)
    shutil.rmtree(W, ignore_errors=True)
    os.makedirs(W)
    t0 = time.monotonic()
    refusals(os.path.abspath(a.mcsim), W)
    bit_for_bit(os.path.abspath(a.mcsim), W)
    served_drive(os.path.abspath(a.mcsim), W, sys.executable)
    print(f"socketcand checks ({time.monotonic() - t0:.0f} s): "
          + (f"FAILED: {len(fails)}" if fails else "passed"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
