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
"""
import argparse
import csv
import json
import os
import re
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
DBC_DEFAULT = os.path.join(HERE, "motordrive.dbc")
DBC_NODE = 1  # node id the DBC file's frame ids are written for
CMD_BITS = 5
CMD_MASK = (1 << CMD_BITS) - 1
NODE_MAX = 62  # 63 (all ones) is kept free for a broadcast address


class UsageError(Exception):
    pass


# --------------------------------------------------------------------- DBC
def load_db(path=DBC_DEFAULT):
    import cantools  # imported here so --help works without the venv
    try:
        return cantools.database.load_file(path, strict=True)
    except (OSError, cantools.database.UnsupportedDatabaseFormatError) as e:
        raise UsageError(f"cannot load DBC {path}: {e}")


def cmd_of(msg):
    return msg.frame_id & CMD_MASK


def frame_id(node, cmd):
    if not 0 <= node <= NODE_MAX:
        raise UsageError(f"node id {node} out of range 0..{NODE_MAX}")
    return (node << CMD_BITS) | cmd


def by_cmd(db):
    return {cmd_of(m): m for m in db.messages}


# -------------------------------------------------------------- candump log
_LINE = re.compile(r"^\((\d+\.\d+)\)\s+(\S+)\s+([0-9A-Fa-f]+)(#.*)$")


def parse_candump_line(line):
    """(t_s, iface, can_id, data bytes, flags) or None for a blank or # line.
    flags: set of 'ext', 'rtr', 'fd', 'err'. Raises ValueError when malformed."""
    line = line.strip()
    if not line or line.startswith("#"):  # blank or comment (command scripts)
        return None
    m = _LINE.match(line)
    if not m:
        raise ValueError(f"not a candump -L line: {line!r}")
    t_s, iface, id_txt, rest = float(m.group(1)), m.group(2), m.group(3), m.group(4)
    flags = set()
    can_id = int(id_txt, 16)
    if len(id_txt) == 8:
        flags.add("ext")
        if can_id & 0x20000000:
            flags.add("err")
        can_id &= 0x1FFFFFFF
    elif len(id_txt) != 3:
        raise ValueError(f"identifier must have 3 or 8 hex digits: {line!r}")
    if rest.startswith("##"):
        flags.add("fd")
        payload = rest[3:]  # one flags nibble after ##
    elif rest.upper().startswith("#R"):
        flags.add("rtr")
        payload = ""
    else:
        payload = rest[1:]
    payload = payload.replace(".", "")
    if len(payload) % 2:
        raise ValueError(f"odd number of hex digits: {line!r}")
    return t_s, iface, can_id, bytes.fromhex(payload), flags


def read_candump(path):
    frames = []
    try:
        with open(path) as f:
            for n, line in enumerate(f, start=1):
                try:
                    fr = parse_candump_line(line)
                except ValueError as e:
                    raise UsageError(f"{path}:{n}: {e}")
                if fr is not None:
                    frames.append(fr)
    except OSError as e:
        raise UsageError(f"cannot read {path}: {e.strerror}")
    return frames


def format_candump_line(t_s, iface, can_id, data):
    return f"({t_s:017.6f}) {iface} {can_id:03X}#{bytes(data).hex().upper()}"


# ----------------------------------------------------- signal (de)coding
def _raw_bits(data, start, length):
    word = int.from_bytes(bytes(data) + bytes(8), "little")
    return (word >> start) & ((1 << length) - 1)


def decode_signals(msg, data):
    """Own little-endian decoder (independent of cantools' decode, which the
    tests use as the cross-check). Returns {signal: physical value}."""
    out = {}
    for s in msg.signals:
        if s.byte_order != "little_endian":
            raise UsageError(f"{msg.name}.{s.name}: only little-endian signals are supported")
        raw = _raw_bits(data, s.start, s.length)
        if s.is_signed and raw & (1 << (s.length - 1)):
            raw -= 1 << s.length
        out[s.name] = raw * s.scale + s.offset
    return out


def encode_signals(msg, values):
    word = 0
    for s in msg.signals:
        v = values.get(s.name, 0.0)
        if s.minimum is not None and not (s.minimum - s.scale / 2 <= v <= s.maximum + s.scale / 2):
            raise UsageError(f"{msg.name}.{s.name}={v} outside [{s.minimum}, {s.maximum}]")
        raw = int(round((v - s.offset) / s.scale))
        word |= (raw & ((1 << s.length) - 1)) << s.start
    return word.to_bytes(8, "little")[: msg.length]


# ------------------------------------------------------------- bus load
def _crc15(bits):
    crc = 0
    for b in bits:
        nxt = b ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if nxt:
            crc ^= 0x4599
    return crc


def frame_bits(can_id, data, ext=False, rtr=False):
    """Bits a classic frame occupies on the bus, stuff bits counted exactly,
    including the 3-bit intermission (ISO 11898-1)."""
    def bits_of(v, n):
        return [(v >> (n - 1 - i)) & 1 for i in range(n)]
    dlc = len(data)
    if ext:
        head = [0] + bits_of(can_id >> 18, 11) + [1, 1] + bits_of(can_id & 0x3FFFF, 18) + [int(rtr), 0, 0]
    else:
        head = [0] + bits_of(can_id, 11) + [int(rtr), 0, 0]
    body = head + bits_of(dlc, 4)
    if not rtr:
        for byte in data:
            body += bits_of(byte, 8)
    body += bits_of(_crc15(body), 15)
    stuffed, run, last = 0, 0, None
    for b in body:
        if b == last:
            run += 1
        else:
            run, last = 1, b
        if run == 5:
            stuffed += 1
            run, last = 1, 1 - b  # the stuff bit starts a new run
    return len(body) + stuffed + 1 + 2 + 7 + 3  # CRC delim, ACK, EOF, IFS


def worst_case_bits(dlc):
    """Worst-case stuffed length of a classic 11-bit frame (55 + 10 n), as
    the firmware's budget check (mc_telemetry.c) assumes."""
    return 55 + 10 * dlc


# --------------------------------------------------------------- decode
def decode_log(db, frames, node):
    """[(msg, t_s, {sig: value})] for frames of `node` the DBC knows,
    plus a count of the frames it skipped."""
    table = by_cmd(db)
    out, skipped = [], 0
    for t_s, _iface, can_id, data, flags in frames:
        if flags & {"ext", "rtr", "fd", "err"} or (can_id >> CMD_BITS) != node:
            skipped += 1
            continue
        msg = table.get(can_id & CMD_MASK)
        if msg is None or len(data) != msg.length:
            skipped += 1
            continue
        out.append((msg, t_s, decode_signals(msg, data)))
    return out, skipped


def write_csvs(db, decoded, out_dir, merged):
    os.makedirs(out_dir, exist_ok=True)
    written = []
    t0 = decoded[0][1] if decoded else 0.0
    if merged:
        cols = [f"{m.name}.{s.name}" for m in db.messages for s in m.signals]
        path = os.path.join(out_dir, "merged.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t", "message"] + cols)
            last = {c: "" for c in cols}
            for msg, t_s, vals in decoded:
                for k, v in vals.items():
                    last[f"{msg.name}.{k}"] = repr(v)
                w.writerow([f"{t_s - t0:.6f}", msg.name] + [last[c] for c in cols])
        written.append(path)
        return written
    per = {}
    for msg, t_s, vals in decoded:
        per.setdefault(msg.name, []).append((t_s, vals))
    for m in db.messages:
        rows = per.get(m.name)
        if not rows:
            continue
        path = os.path.join(out_dir, f"{m.name}.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t", "t_log"] + [s.name for s in m.signals])
            for t_s, vals in rows:
                w.writerow([f"{t_s - t0:.6f}", f"{t_s:.6f}"] + [repr(vals[s.name]) for s in m.signals])
        written.append(path)
    return written


def stats_of(db, frames, node, bitrate):
    decoded, skipped = decode_log(db, frames, node)
    per = {}
    for msg, t_s, vals in decoded:
        e = per.setdefault(msg.name, {"frames": 0, "gaps": 0, "lost": 0, "first_t": t_s,
                                      "last_t": t_s, "last_seq": None})
        e["frames"] += 1
        e["last_t"] = t_s
        if "seq" in vals:
            seq = int(vals["seq"])
            if e["last_seq"] is not None:
                lost = (seq - e["last_seq"] - 1) % 256
                if lost:
                    e["gaps"] += 1
                    e["lost"] += lost
            e["last_seq"] = seq
    for e in per.values():
        span = e["last_t"] - e["first_t"]
        e["rate_hz"] = (e["frames"] - 1) / span if e["frames"] > 1 and span > 0 else 0.0
        del e["last_seq"]
    bits = sum(frame_bits(i, d, "ext" in fl, "rtr" in fl) for _t, _if, i, d, fl in frames
               if "fd" not in fl and "err" not in fl)
    span = (frames[-1][0] - frames[0][0]) if len(frames) > 1 else 0.0
    return {
        "frames": len(frames),
        "frames_skipped": skipped,
        "duration_s": span,
        "bitrate_bps": bitrate,
        "bus_load": (bits / span / bitrate) if span > 0 else 0.0,
        "messages": per,
        "lost_total": sum(e["lost"] for e in per.values()),
    }


# -------------------------------------------------------------- commands
def parse_assignments(msg, items):
    vals = {}
    names = {s.name for s in msg.signals}
    for it in items:
        if "=" not in it:
            raise UsageError(f"expected signal=value, got {it!r}")
        k, v = it.split("=", 1)
        if k not in names:
            raise UsageError(f"{msg.name} has no signal {k!r} (signals: {', '.join(sorted(names)) or 'none'})")
        if s_choices := next(s for s in msg.signals if s.name == k).choices:
            for raw, name in s_choices.items():
                if str(name) == v:
                    v = str(raw)
        try:
            vals[k] = float(v)
        except ValueError:
            raise UsageError(f"{k}: not a number: {v!r}")
    return vals


def find_message(db, name):
    try:
        return db.get_message_by_name(name.upper())
    except KeyError:
        raise UsageError(f"unknown message {name!r} (known: {', '.join(m.name for m in db.messages)})")


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


# ------------------------------------------------------------------ record
# Why the logger lost frames on a busy machine (measured: 658 of 2923 frames
# with one core kept busy, inside the CAN test's emulated VM): the socket's
# receive queue is the only buffer while Python is not scheduled, and
# (1) SO_RCVBUF is silently capped at net.core.rmem_max (208 KiB: about 230
#     queued CAN frames, well under a second of telemetry), and
# (2) every frame was flushed to the file on its own (one write system call,
#     over 9p in the VM, per frame), so draining a backlog was slower than
#     the bus filled it.
# The recorder now forces a large queue (SO_RCVBUFFORCE where it may, else
# SO_RCVBUF, the size it got is reported), drains the socket in batches,
# writes through a buffer flushed about every RECORD_FLUSH_S, and asks the
# kernel for its drop counter (SO_RXQ_OVFL) so a loss is never silent.
RECORD_RCVBUF_BYTES = 16 << 20  # ~20,000 queued frames: > 10 s at the default rates
RECORD_FLUSH_S = 0.5
SO_RXQ_OVFL = getattr(__import__("socket"), "SO_RXQ_OVFL", 40)
SO_RCVBUFFORCE = getattr(__import__("socket"), "SO_RCVBUFFORCE", 33)
SO_TIMESTAMPNS = getattr(__import__("socket"), "SO_TIMESTAMPNS", 35)
SO_MEMINFO, SK_MEMINFO_DROPS = 55, 8  # linux/sock_diag.h (Linux >= 4.6)
CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000


class SocketcanRecorder:
    """A raw SocketCAN socket that reports the kernel's drop counter.

    python-can's SocketCAN bus reads one ancillary item (the time stamp) and
    has no access to SO_RXQ_OVFL, so the recorder reads the socket itself
    with the standard library's AF_CAN support; frames are formatted exactly
    as `candump -L` does, and read back with python-can's candump reader.
    """

    def __init__(self, iface, rcvbuf=RECORD_RCVBUF_BYTES):
        import socket
        import struct
        self._struct = struct
        self._socket = socket
        self.sock = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, rcvbuf)
            self.forced = True
        except OSError:  # not CAP_NET_ADMIN: capped at net.core.rmem_max
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
            self.forced = False
        self.rcvbuf = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
        self.sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
        self.sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
        try:  # error frames too, as candump -L shows them when asked
            self.sock.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_ERR_FILTER, 0x1FFFFFFF)
        except (AttributeError, OSError):
            pass
        try:
            self.sock.bind((iface,))
        except OSError as e:
            self.sock.close()
            raise UsageError(f"record: cannot open SocketCAN interface {iface!r}: {e.strerror}")
        self.sock.setblocking(False)
        self.dropped = 0  # the kernel's cumulative count for this socket
        self._cmsg_space = socket.CMSG_SPACE(16) + socket.CMSG_SPACE(4)

    def poll_drops(self):
        """The socket's drop count now. SO_RXQ_OVFL stamps each frame with the
        count at the time it was queued, so drops after the last frame read
        only show here (SO_MEMINFO); the larger of the two is kept."""
        try:
            info = self.sock.getsockopt(self._socket.SOL_SOCKET, SO_MEMINFO, 9 * 4)
            self.dropped = max(self.dropped, self._struct.unpack_from("@9I", info)[SK_MEMINFO_DROPS])
        except OSError:
            pass
        return self.dropped

    def close(self):
        self.poll_drops()
        self.sock.close()

    def read_batch(self, iface, timeout_s, max_frames=4096):
        """Up to max_frames candump -L lines; waits at most timeout_s for the first."""
        import select
        out = []
        if timeout_s > 0:
            r, _, _ = select.select([self.sock], [], [], timeout_s)
            if not r:
                return out
        unpack_ts = self._struct.Struct("@qq").unpack_from
        unpack_u32 = self._struct.Struct("@I").unpack_from
        head = self._struct.Struct("<IB3x").unpack_from
        for _ in range(max_frames):
            try:
                cf, anc, _flags, _addr = self.sock.recvmsg(72, self._cmsg_space)
            except BlockingIOError:
                break
            stamp = None
            for _level, typ, data in anc:
                if typ == SO_TIMESTAMPNS and len(data) >= 16:
                    sec, ns = unpack_ts(data)
                    stamp = f"{sec:010d}.{ns // 1000:06d}"  # as candump: microseconds, truncated
                elif typ == SO_RXQ_OVFL and len(data) >= 4:
                    self.dropped = unpack_u32(data)[0]
            if stamp is None:
                stamp = f"{time.time():017.6f}"
            can_id, length = head(cf)
            payload = cf[8:8 + length]
            if can_id & CAN_ERR_FLAG:
                ident = f"{can_id & 0x1FFFFFFF | CAN_ERR_FLAG:08X}"
            elif can_id & CAN_EFF_FLAG:
                ident = f"{can_id & 0x1FFFFFFF:08X}"
            else:
                ident = f"{can_id & 0x7FF:03X}"
            if len(cf) == 72:  # CAN FD frame
                line = f"({stamp}) {iface} {ident}##{cf[5] & 1:X}{payload.hex().upper()}"
            elif can_id & CAN_RTR_FLAG:
                line = f"({stamp}) {iface} {ident}#R"
            else:
                line = f"({stamp}) {iface} {ident}#{payload.hex().upper()}"
            out.append(line)
        return out


def cmd_record(a, db):
    stop = {"now": False}

    def on_signal(_sig, _frm):
        stop["now"] = True
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    t_end = time.monotonic() + a.duration if a.duration else None
    rec = SocketcanRecorder(a.iface)
    n = 0
    try:
        with open(a.out, "w", buffering=1 << 20) as f:
            if a.ready:
                open(a.ready, "w").close()
            t_flush = time.monotonic() + RECORD_FLUSH_S
            while True:
                now = time.monotonic()
                ending = stop["now"] or (t_end is not None and now >= t_end)
                # once told to stop, drain what the socket already holds, then stop
                lines = rec.read_batch(a.iface, 0.0 if ending else 0.1)
                if lines:
                    f.write("\n".join(lines) + "\n")
                    n += len(lines)
                elif ending:
                    break
                if now >= t_flush:
                    f.flush()
                    t_flush = now + RECORD_FLUSH_S
    finally:
        rec.close()
    report = {"log": a.out, "frames": n, "kernel_dropped": rec.dropped,
              "rcvbuf_bytes": rec.rcvbuf, "rcvbuf_forced": rec.forced}
    print(f"{a.out}: {n} frames; kernel dropped {rec.dropped} (SO_RXQ_OVFL); "
          f"receive buffer {rec.rcvbuf} B{'' if rec.forced else ' (not forced: capped by rmem_max)'}")
    if a.report:
        with open(a.report, "w") as rf:
            json.dump(report, rf, indent=1)
    if rec.dropped:
        print(f"mc_can: record: the kernel dropped {rec.dropped} frames", file=sys.stderr)
    if a.decode_dir:
        frames = read_candump(a.out)
        decoded, _ = decode_log(db, frames, a.node)
        for p in write_csvs(db, decoded, a.decode_dir, a.merged):
            print(p)
    return 1 if rec.dropped else 0


def cmd_decode(a, db):
    frames = read_candump(a.log)
    decoded, skipped = decode_log(db, frames, a.node)
    for p in write_csvs(db, decoded, a.out, a.merged):
        print(p)
    if skipped:
        print(f"skipped {skipped} frames (other nodes, unknown ids or lengths)", file=sys.stderr)
    return 0


def cmd_stats(a, db):
    s = stats_of(db, read_candump(a.log), a.node, a.bitrate)
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


def cmd_plot(a, _db):
    mcplot = os.path.join(HERE, "..", "plot", "mcplot.py")
    args = [sys.executable, mcplot, a.csv] + (["-o", a.o] if a.o else [])
    return subprocess.call(args)


def cmd_table(_a, db):
    print("| id (node 1) | cmd | message | dir | len | signal | bits | scale | range | unit |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for m in sorted(db.messages, key=lambda m: m.frame_id):
        d = "drive→host" if m.senders == ["Drive"] else "host→drive"
        sigs = m.signals or [None]
        for i, s in enumerate(sigs):
            head = (f"| 0x{m.frame_id:03X} | 0x{cmd_of(m):02X} | {m.name} | {d} | {m.length} "
                    if i == 0 else "| | | | | ")
            if s is None:
                print(head + "| — | | | | |")
                continue
            sign = "s" if s.is_signed else "u"
            rng = f"{s.minimum:g} … {s.maximum:g}"
            if s.choices:
                rng += " (" + ", ".join(f"{k} {v}" for k, v in s.choices.items()) + ")"
            print(head + f"| {s.name} | {s.start}+{s.length}{sign} | {s.scale:g} | {rng} | {s.unit or ''} |")
    return 0


def cmd_dbc(a, db):
    with open(a.dbc) as f:
        text = f.read()
    shift = (a.node - DBC_NODE) << CMD_BITS
    frame_id(a.node, 0)

    def rebase(m):
        return m.group(1) + str(int(m.group(2)) + shift)
    text = re.sub(r"^(BO_ )(\d+)", rebase, text, flags=re.M)
    text = re.sub(r"^((?:CM_ BO_|CM_ SG_|VAL_) )(\d+)", rebase, text, flags=re.M)
    with open(a.o, "w") as f:
        f.write(text)
    return 0


# ------------------------------------------------------------------ gen-c
def _cfloat(v):
    r = repr(float(v))
    if "e" not in r and "." not in r:
        r += ".0"
    return r + "f"


def gen_c(db, dbc_name):
    msgs = sorted(db.messages, key=lambda m: cmd_of(m))
    for m in msgs:
        if (m.frame_id >> CMD_BITS) != DBC_NODE:
            raise UsageError(f"{m.name}: frame id 0x{m.frame_id:X} is not on node {DBC_NODE}")
        if m.length > 8 or m.is_extended_frame:
            raise UsageError(f"{m.name}: only classic 11-bit frames are generated")
        for s in m.signals:
            if s.byte_order != "little_endian" or s.is_float or s.length > 32:
                raise UsageError(f"{m.name}.{s.name}: only little-endian integers <= 32 bits")
    up = str.upper
    h = [f"/* Generated by tools/can/mc_can.py gen-c from tools/can/{dbc_name}: do not edit. */",
         "/**", " * @file mc_can_dbc.h", " * @brief Command ids, message and signal indices of the CAN protocol",
         " *        (tables in mc_can_dbc.c, types and codec in mc_can_proto.h).", " */",
         "#ifndef MC_CAN_DBC_H", "#define MC_CAN_DBC_H", "",
         f"#define MC_CAN_DBC_NODE_ID {DBC_NODE}u /**< node the DBC file's frame ids are written for */",
         "", "/* Command ids (low 5 bits of the identifier). */"]
    for m in msgs:
        h.append(f"#define MC_CAN_CMD_{up(m.name)} 0x{cmd_of(m):02X}u")
    h += ["", "/* Indices into mc_can_messages[]. */"]
    for i, m in enumerate(msgs):
        h.append(f"#define MC_CAN_MSG_{up(m.name)} {i}u")
    h.append(f"#define MC_CAN_MSG_COUNT {len(msgs)}u")
    h += ["", "/* Signal indices within each message (value arrays of mc_can_proto_pack/unpack). */"]
    nmax = 0
    for m in msgs:
        for j, s in enumerate(m.signals):
            h.append(f"#define MC_CAN_{up(m.name)}_{up(s.name)} {j}u")
        h.append(f"#define MC_CAN_{up(m.name)}_NSIG {len(m.signals)}u")
        nmax = max(nmax, len(m.signals))
    h.append(f"#define MC_CAN_NSIG_MAX {nmax}u")
    h += ["", "/* Named values (VAL_ tables). */"]
    seen = {}
    for m in msgs:
        for s in m.signals:
            for raw, name in (s.choices or {}).items():
                key = f"MC_CAN_VAL_{up(s.name)}_{up(str(name))}"
                if key in seen:
                    if seen[key] != raw:
                        raise UsageError(f"{key} has two values ({seen[key]}, {raw})")
                    continue
                seen[key] = raw
                h.append(f"#define {key} {int(raw)}u")
    h += ["", "#endif /* MC_CAN_DBC_H */", ""]

    c = [f"/* Generated by tools/can/mc_can.py gen-c from tools/can/{dbc_name}: do not edit. */",
         "/**", " * @file mc_can_dbc.c", " * @brief Message and signal tables of the CAN protocol.", " */",
         '#include "mc_can_proto.h"', "", "#include <stddef.h>", ""]
    for m in msgs:
        if not m.signals:
            continue
        c.append(f"static const mc_can_signal_t sig_{m.name.lower()}[{len(m.signals)}] = {{")
        for s in m.signals:
            c.append(f"    {{{s.start}u, {s.length}u, {'true' if s.is_signed else 'false'}, "
                     f"{_cfloat(s.scale)}, {_cfloat(s.offset)}, {_cfloat(s.minimum)}, "
                     f"{_cfloat(s.maximum)}}}, /* {s.name} [{s.unit or '-'}] */")
        c.append("};")
    c += ["", "const mc_can_message_t mc_can_messages[MC_CAN_MSG_COUNT] = {"]
    for m in msgs:
        d = "MC_CAN_DIR_TX" if m.senders == ["Drive"] else "MC_CAN_DIR_RX"
        sig = f"sig_{m.name.lower()}" if m.signals else "NULL"
        c.append(f"    {{MC_CAN_CMD_{up(m.name)}, {m.length}u, {d}, {len(m.signals)}u, {sig}}}, /* {m.name} */")
    c += ["};", ""]
    return "\n".join(h), "\n".join(c)


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
    g = sub.add_parser("gen-c", help="generate firmware/app/mc_can_dbc.{h,c}")
    g.add_argument("--out-dir", required=True)
    a = p.parse_args(argv)
    try:
        frame_id(a.node, 0)
        # record needs no DBC unless it decodes: cantools imports python-can, which
        # imports asammdf, pandas and pyarrow when they are installed (seconds,
        # tens of seconds in the CAN test's emulated VM) before the socket opens
        db = None if a.cmd == "record" and not a.decode_dir else load_db(a.dbc)
        return {"record": cmd_record, "decode": cmd_decode, "stats": cmd_stats, "plot": cmd_plot,
                "encode": cmd_encode, "send": cmd_send, "table": cmd_table, "dbc": cmd_dbc,
                "gen-c": cmd_gen_c}[a.cmd](a, db)
    except UsageError as e:
        print(f"mc_can: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
