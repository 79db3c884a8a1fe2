#!/usr/bin/env python3
"""Motor-drive CAN tools: the DBC (tools/can/motordrive.dbc) is the single
source of truth for every message and signal.

    mc_can.py record  --iface IF --out LOG [--duration S] [--report F]
                                                         record SocketCAN; kernel drops reported
    mc_can.py decode  LOG --out DIR [--merged]              candump log -> CSV per message (or one CSV)
    mc_can.py stats   LOG [--bitrate B] [--json F]          frames per message, sequence gaps, bus load
    mc_can.py plot    CSV [-o PNG]                          figure of a decoded CSV (tools/plot/mcplot.py)
    mc_can.py encode  MSG [sig=value ...]                   print the cansend argument (ID#DATA)
    mc_can.py send    --iface IF MSG [sig=value ...]        send one command (python-can)
    mc_can.py table                                          protocol table (Markdown) for the README
    mc_can.py dbc     --node N -o FILE                      the DBC re-based for node N
    mc_can.py gen-c   --out-dir DIR                         firmware tables (mc_can_dbc.h/.c)

Identifiers are node_id << 5 | cmd; the DBC is written for node 1 and every
command takes --node N (default 1). A candump log is the text format of
`candump -L` ("(seconds) iface ID#DATA"). Exit code 2 on a usage error.

A thin compatibility wrapper: the functions live in the mdtool package
(tools/mdtool/src/mdtool/can), imported from this tree's source so the
tests and the firmware generator use this tree's code whatever version of
mdtool the venv has installed. `mdtool` offers the same and more (decode
and stats of any log format, record to .blf/.asc/.mf4, the drive commands).
"""

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "mdtool", "src"))

from mdtool.can.dbc import (  # noqa: E402,F401  (re-exported for the tests)
    CMD_BITS, CMD_MASK, DBC_NODE, NODE_MAX, by_cmd, cmd_of, decode_signals, encode_signals,
    find_message, frame_bits, frame_id, gen_c, load_db, parse_assignments, rebase_dbc_text,
    table_markdown, worst_case_bits)
from mdtool.can.errors import UsageError  # noqa: E402
from mdtool.can.log import (  # noqa: E402,F401
    decode_log, format_candump_line, parse_candump_line, read_candump, stats_of, write_csvs)
from mdtool.can.record import (  # noqa: E402,F401
    RECORD_FLUSH_S, RECORD_RCVBUF_BYTES, SocketcanRecorder, record)

DBC_DEFAULT = os.path.join(HERE, "motordrive.dbc")


def cmd_encode(a, db):
    msg = find_message(db, a.message)
    data = encode_signals(msg, parse_assignments(msg, a.values))
    print(f"{frame_id(a.node, cmd_of(msg)):03X}#{data.hex().upper()}")
    return 0


def cmd_send(a, db):
    import can
    msg = find_message(db, a.message)
    data = encode_signals(msg, parse_assignments(msg, a.values))
    with can.Bus(interface="socketcan", channel=a.iface) as bus:
        bus.send(can.Message(arbitration_id=frame_id(a.node, cmd_of(msg)), data=data,
                             is_extended_id=False))
    return 0


def cmd_record(a, db):
    rep = record(a.out, db, a.node, interface="socketcan", channel=a.iface, duration=a.duration,
                 ready=a.ready, report=a.report)
    if rep["kernel_dropped"]:
        print(f"mc_can: record: the kernel dropped {rep['kernel_dropped']} frames", file=sys.stderr)
    if a.decode_dir:
        decoded, _ = decode_log(db, read_candump(a.out), a.node)
        for p in write_csvs(db, decoded, a.decode_dir, a.merged):
            print(p)
    return 1 if rep["kernel_dropped"] else 0


def cmd_decode(a, db):
    frames = read_candump(a.log)
    decoded, skipped = decode_log(db, frames, a.node)
    for p in write_csvs(db, decoded, a.out, a.merged):
        print(p)
    if skipped:
        print(f"skipped {skipped} frames (other nodes, unknown ids or lengths)", file=sys.stderr)
    return 0


def print_stats(s, log, bitrate):
    print(f"{log}: {s['frames']} frames in {s['duration_s']:.3f} s, "
          f"bus load {100 * s['bus_load']:.2f} % of {bitrate / 1000:g} kbit/s")
    print(f"{'message':<18}{'frames':>8}{'rate_hz':>10}{'gaps':>6}{'lost':>6}")
    for name, e in s["messages"].items():
        print(f"{name:<18}{e['frames']:>8}{e['rate_hz']:>10.1f}{e['gaps']:>6}{e['lost']:>6}")
    print(f"frames lost (sequence gaps): {s['lost_total']}")


def cmd_stats(a, db):
    s = stats_of(db, read_candump(a.log), a.node, a.bitrate)
    print_stats(s, a.log, a.bitrate)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(s, f, indent=1)
    return 0


def cmd_plot(a, _db):
    mcplot = os.path.join(HERE, "..", "plot", "mcplot.py")
    args = [sys.executable, mcplot, a.csv] + (["-o", a.o] if a.o else [])
    return subprocess.call(args)


def cmd_table(_a, db):
    print(table_markdown(db))
    return 0


def cmd_dbc(a, db):
    with open(a.dbc) as f:
        text = f.read()
    with open(a.o, "w") as f:
        f.write(rebase_dbc_text(text, a.node))
    return 0


def cmd_gen_c(a, db):
    h, c = gen_c(db, os.path.basename(a.dbc))
    os.makedirs(a.out_dir, exist_ok=True)
    for name, text in (("mc_can_dbc.h", h), ("mc_can_dbc.c", c)):
        with open(os.path.join(a.out_dir, name), "w") as f:
            f.write(text)
        print(os.path.join(a.out_dir, name))
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(prog="mc_can.py", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dbc", default=DBC_DEFAULT, help="DBC file (default: tools/can/motordrive.dbc)")
    p.add_argument("--node", type=int, default=DBC_NODE, help="drive node id, 0..62 (default 1)")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record", help="record a SocketCAN interface to a candump log")
    r.add_argument("--iface", required=True)
    r.add_argument("--out", required=True, help="candump log to write")
    r.add_argument("--duration", type=float, default=0.0, help="seconds (0: until SIGINT/SIGTERM)")
    r.add_argument("--decode-dir", help="also decode to CSV in this directory when done")
    r.add_argument("--merged", action="store_true")
    r.add_argument("--ready", help="touch this file once the socket is open")
    r.add_argument("--report", help="write frames, kernel drops and buffer size as JSON")
    d = sub.add_parser("decode", help="decode a candump log to CSV")
    d.add_argument("log")
    d.add_argument("--out", required=True, help="output directory")
    d.add_argument("--merged", action="store_true", help="one merged.csv instead of one per message")
    s = sub.add_parser("stats", help="frames per message, sequence gaps, bus load")
    s.add_argument("log")
    s.add_argument("--bitrate", type=float, default=1e6, help="bus bit rate [bit/s] (default 1e6)")
    s.add_argument("--json", help="also write the statistics as JSON")
    pl = sub.add_parser("plot", help="plot a decoded CSV")
    pl.add_argument("csv")
    pl.add_argument("-o")
    e = sub.add_parser("encode", help="print the cansend argument for a command")
    e.add_argument("message")
    e.add_argument("values", nargs="*")
    se = sub.add_parser("send", help="send one command on a SocketCAN interface")
    se.add_argument("--iface", required=True)
    se.add_argument("message")
    se.add_argument("values", nargs="*")
    sub.add_parser("table", help="protocol table (Markdown)")
    db_ = sub.add_parser("dbc", help="write the DBC for another node id")
    db_.add_argument("-o", required=True)
    g = sub.add_parser("gen-c", help="generate firmware/app/can/mc_can_dbc.{h,c}")
    g.add_argument("--out-dir", required=True)
    a = p.parse_args(argv)
    try:
        frame_id(a.node, 0)
        db = load_db(a.dbc)  # record too: it counts sequence gaps as it goes
        return {"record": cmd_record, "decode": cmd_decode, "stats": cmd_stats, "plot": cmd_plot,
                "encode": cmd_encode, "send": cmd_send, "table": cmd_table, "dbc": cmd_dbc,
                "gen-c": cmd_gen_c}[a.cmd](a, db)
    except UsageError as e:
        print(f"mc_can: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
