#!/usr/bin/env python3
"""The logger (tools/can/mc_can.py) on synthetic candump logs whose content
is known exactly: frames per message, sequence gaps and frames lost, rates,
bus load, CSV output (per message and merged), node re-basing, the encode
command and the protocol table."""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOL = os.path.join(ROOT, "tools", "can", "mc_can.py")
sys.path.insert(0, os.path.dirname(TOOL))
import mc_can  # noqa: E402

fails = []


def check(cond, what):
    if not cond:
        fails.append(what)


def cli(*args):
    return subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    db = mc_can.load_db()
    cur = db.get_message_by_name("CURRENTS")
    hb = db.get_message_by_name("HEARTBEAT")

    # CURRENTS at 100 Hz with sequence 0..19 except 4, 5 (lost) and 250..255,0..3
    # (wrap, no loss); HEARTBEAT at 10 Hz; a frame of node 2 and a broken
    # length that the decoder must skip.
    lines, t = [], 0.0
    seqs = [s for s in range(20) if s not in (4, 5)] + list(range(250, 256)) + list(range(4))
    for k, s in enumerate(seqs):
        t = 0.01 * k
        data = mc_can.encode_signals(cur, {"i_d_a": 0.1 * k, "i_q_a": -0.5,
                                           "seq": s})
        lines.append(mc_can.format_candump_line(100.0 + t, "can0", 0x22, data))
        if k % 10 == 0:
            d = mc_can.encode_signals(hb, {"mode": 1, "seq": k // 10})
            lines.append(mc_can.format_candump_line(100.0 + t + 0.001, "can0", 0x21, d))
    lines.append(mc_can.format_candump_line(100.5, "can0", 0x42, bytes(8)))  # node 2
    lines.append(mc_can.format_candump_line(100.5, "can0", 0x22, bytes(7)))  # bad length
    log = os.path.join(a.work, "synthetic.log")
    with open(log, "w") as f:
        f.write("\n".join(lines) + "\n")

    frames = mc_can.read_candump(log)
    st = mc_can.stats_of(db, frames, 1, 500e3)
    c = st["messages"]["CURRENTS"]
    # the 250 after 19 is a jump of 230 frames: counted as a gap too
    check(c["frames"] == len(seqs), f"CURRENTS frames {c['frames']}")
    check(c["gaps"] == 2 and c["lost"] == 2 + 230, f"CURRENTS gaps {c['gaps']} lost {c['lost']}")
    check(abs(c["rate_hz"] - 100.0) < 1e-6, f"rate {c['rate_hz']}")  # exact spacing in the log
    check(st["messages"]["HEARTBEAT"]["lost"] == 0, "HEARTBEAT gap")
    check(st["frames_skipped"] == 2, f"skipped {st['frames_skipped']}")
    # bus load: exact stuffed bits of every frame over the log's span
    bits = sum(mc_can.frame_bits(i, d) for _t, _if, i, d, _f in frames)
    check(abs(st["bus_load"] - bits / st["duration_s"] / 500e3) < 1e-12, "bus load")
    for n in range(9):
        for data in (bytes(n), bytes([0xFF] * n), bytes([0x55] * n)):
            b = mc_can.frame_bits(0x7FF, data)
            # between the unstuffed length and the worst case (55 + 10 n)
            check(47 + 8 * n <= b <= mc_can.worst_case_bits(n), f"frame_bits({n}) = {b}")
    # a zero id and zero data stuffs a bit after every 4 more zeros: more
    # stuff bits than the alternating pattern, which needs none in its data
    check(mc_can.frame_bits(0, bytes(8)) > mc_can.frame_bits(0x555, bytes([0x55] * 8)), "stuffing")

    # CSV per message and merged
    out = os.path.join(a.work, "csv")
    r = cli("decode", log, "--out", out)
    check(r.returncode == 0, f"decode failed: {r.stderr}")
    with open(os.path.join(out, "CURRENTS.csv")) as f:
        rows = list(csv.DictReader(f))
    check(len(rows) == len(seqs), f"CURRENTS.csv rows {len(rows)}")
    check(abs(float(rows[3]["i_d_a"]) - 0.3) <= 0.001 + 1e-12, "i_d_a decoded")  # half of 0.002 A
    check(float(rows[0]["t"]) == 0.0, "time origin")
    r = cli("decode", log, "--out", out, "--merged")
    with open(os.path.join(out, "merged.csv")) as f:
        rows = list(csv.DictReader(f))
    check(len(rows) == len(seqs) + 3 and "CURRENTS.i_q_a" in rows[0], "merged.csv")

    # the DBC re-based for node 2 decodes node 2's frames with cantools
    d2 = os.path.join(a.work, "node2.dbc")
    check(cli("--node", "2", "dbc", "-o", d2).returncode == 0, "dbc --node 2")
    import cantools
    db2 = cantools.database.load_file(d2)
    check(db2.get_message_by_name("CURRENTS").frame_id == 0x42, "node 2 CURRENTS id")
    check(cli("--node", "63", "table").returncode == 2, "node 63 must be refused")

    # encode: the cansend argument; bad input is a usage error
    r = cli("encode", "SET_CURRENT_REF", "i_q_ref_a=1.0")
    # 6 bytes: i_d and i_q as 24-bit mA (version 3: any motor's current)
    check(r.stdout.strip() == "032#000000E80300", f"encode: {r.stdout!r}")
    r = cli("--node", "5", "encode", "SET_CONTROL_MODE", "control_mode=SPEED")
    check(r.stdout.strip() == "0B1#02", f"encode node 5: {r.stdout!r}")
    check(cli("encode", "SET_CURRENT_REF", "i_q_ref_a=9999").returncode == 2, "out of range accepted")
    check(cli("encode", "NO_SUCH").returncode == 2, "unknown message accepted")
    tab = cli("table").stdout
    check(all(m.name in tab for m in db.messages), "table misses a message")

    for f in fails:
        print("FAIL:", f)
    print("logger checks:", "FAILED" if fails else "passed")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
