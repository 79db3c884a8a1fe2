"""Logs: the candump -L text format (own reader and writer, exactly as
candump writes it), every other python-can format (.blf, .asc, .mf4 through
asammdf, .csv, .trc) through python-can's readers and writers; decoding to
CSV and the statistics (frames per message, sequence gaps, bus load).

A frame is the tuple (t_s, channel, can_id, data bytes, flags) with flags a
set of 'ext', 'rtr', 'fd', 'err'.
"""
import csv
import os
import re

from .dbc import CMD_BITS, CMD_MASK, by_cmd, decode_signals, frame_bits
from .errors import UsageError

#: Extensions python-can reads and writes (candump .log is read and written here).
CANDUMP_EXT = ".log"
PYTHON_CAN_EXT = (".blf", ".asc", ".mf4", ".csv", ".trc")


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
                    raise UsageError(f"{path}:{n}: {e}") from e
                if fr is not None:
                    frames.append(fr)
    except OSError as e:
        raise UsageError(f"cannot read {path}: {e.strerror}") from e
    return frames


def format_candump_line(t_s, iface, can_id, data):
    return f"({t_s:017.6f}) {iface} {can_id:03X}#{bytes(data).hex().upper()}"


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
            last = dict.fromkeys(cols, "")
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


class SeqCounter:
    """Sequence gaps of the telemetry as frames arrive (the rolling 8-bit
    `seq` every telemetry message ends with); cheap enough for the recorder."""

    def __init__(self, db, node):
        self.node = node
        self.seq_at = {}  # cmd -> (name, length, start bit)
        for cmd, m in by_cmd(db).items():
            if m.senders == ["Drive"] and m.signals and m.signals[-1].name == "seq":
                s = m.signals[-1]
                self.seq_at[cmd] = (m.name, m.length, s.start, s.length)
        self.last = {}
        self.gaps = 0
        self.lost = 0

    def add(self, can_id, data, flags=()):
        if flags or (can_id >> CMD_BITS) != self.node:
            return
        at = self.seq_at.get(can_id & CMD_MASK)
        if at is None or len(data) != at[1]:
            return
        seq = (int.from_bytes(data, "little") >> at[2]) & ((1 << at[3]) - 1)
        last = self.last.get(at[0])
        if last is not None:
            lost = (seq - last - 1) % (1 << at[3])
            if lost:
                self.gaps += 1
                self.lost += lost
        self.last[at[0]] = seq


# --------------------------------------------------- any python-can format
def frame_of_message(m):
    """A python-can Message as a frame tuple."""
    flags = set()
    if m.is_extended_id:
        flags.add("ext")
    if m.is_remote_frame:
        flags.add("rtr")
    if m.is_fd:
        flags.add("fd")
    if m.is_error_frame:
        flags.add("err")
    return (float(m.timestamp), str(m.channel) if m.channel is not None else "can0",
            int(m.arbitration_id), bytes(m.data), flags)


def message_of_frame(fr):
    import can
    t_s, chan, can_id, data, flags = fr
    return can.Message(timestamp=t_s, channel=chan, arbitration_id=can_id, data=data,
                       is_extended_id="ext" in flags, is_remote_frame="rtr" in flags,
                       is_fd="fd" in flags, is_error_frame="err" in flags,
                       dlc=len(data) if "rtr" not in flags else 0)


def _ext(path):
    return os.path.splitext(path)[1].lower()


def check_format(path):
    ext = _ext(path)
    if ext != CANDUMP_EXT and ext not in PYTHON_CAN_EXT:
        raise UsageError(f"{path}: unknown log format {ext or '(no extension)'!r} "
                         f"(known: {', '.join((CANDUMP_EXT,) + PYTHON_CAN_EXT)})")
    return ext


def read_frames(path):
    """Frames of a log in any known format (by extension)."""
    if check_format(path) == CANDUMP_EXT:
        return read_candump(path)
    if not os.path.isfile(path):
        raise UsageError(f"cannot read {path}: no such file")
    if path.lower().endswith(".mf4"):
        frames = _read_mf4_data_frames(path)
        if frames is not None:
            return frames
    import can
    try:
        with can.LogReader(path) as reader:
            return [frame_of_message(m) for m in reader]
    except ImportError as e:
        raise UsageError(f"{path}: reading this format needs {e.name} (tools/requirements.txt)") from e


def _read_mf4_data_frames(path):
    """The data frames of an MF4 bus log written by python-can, read as whole
    arrays with asammdf. python-can 4.4's MF4Reader fetches one record per
    call from the start of the compressed data, which costs O(n^2) or worse:
    measured 1.4 s for 1000 frames, 109 s for 6000, and a 18,600-frame record
    of 3 s of telemetry did not finish in 5 minutes. Returns None (the caller
    then uses python-can's reader) when the file also holds error or remote
    frames, or is not laid out as python-can writes it."""
    try:
        from asammdf import MDF
    except ImportError as e:
        raise UsageError(f"{path}: reading this format needs {e.name} (tools/requirements.txt)") from e
    mdf = MDF(path)
    try:
        if len(mdf.groups) != 3 or any(len(mdf.get_master(i)) for i in (1, 2)):
            return None
        sig = mdf.get("CAN_DataFrame", group=0, raw=True)
        rec = sig.samples
        names = rec.dtype.names or ()
        if "CAN_DataFrame.ID" not in names or "CAN_DataFrame.EDL" not in names:
            return None
        if (rec["CAN_DataFrame.EDL"] != 0).any():
            return None  # CAN FD frames: python-can's reader knows their DLC coding
        start = mdf.header.start_time.timestamp()
        out = []
        for t, ch, ide, fid, size, data in zip(
                sig.timestamps.tolist(), rec["CAN_DataFrame.BusChannel"].tolist(),
                rec["CAN_DataFrame.IDE"].tolist(), rec["CAN_DataFrame.ID"].tolist(),
                rec["CAN_DataFrame.DataLength"].tolist(), rec["CAN_DataFrame.DataBytes"]):
            out.append((float(t + start), str(int(ch)), int(fid), data[:size].tobytes(),
                        {"ext"} if ide else set()))
        return out
    finally:
        mdf.close()


class FrameWriter:
    """Writes frames to a log in the format of its extension: candump -L
    text (.log, exactly as candump) or a python-can writer (.blf, .asc,
    .mf4 through asammdf, .csv, .trc)."""

    def __init__(self, path, channel="can0"):
        self.path = path
        self.ext = check_format(path)
        self.channel = channel
        self.count = 0
        if self.ext == CANDUMP_EXT:
            self._f = open(path, "w", buffering=1 << 20)  # noqa: SIM115 (the writer's close() closes it)
            self._w = None
        else:
            import can
            self._f = None
            try:
                self._w = can.Logger(path)
            except ImportError as e:
                raise UsageError(f"{path}: writing this format needs {e.name} (tools/requirements.txt)") from e

    def write_lines(self, lines, frames):
        """candump lines already formatted (the raw SocketCAN recorder) and their frames."""
        if self._f is not None:
            self._f.write("\n".join(lines) + "\n")
        else:
            for fr in frames:
                self._w.on_message_received(message_of_frame(fr))
        self.count += len(lines)

    def write(self, frame):
        if self._f is not None:
            self._f.write(format_frame(frame) + "\n")
        else:
            self._w.on_message_received(message_of_frame(frame))
        self.count += 1

    def flush(self):
        if self._f is not None:
            self._f.flush()

    def close(self):
        if self._f is not None:
            self._f.close()
        else:
            self._w.stop()


def format_frame(fr):
    """A frame as a candump -L line (error, extended, remote and FD frames too)."""
    t_s, chan, can_id, data, flags = fr
    if "err" in flags:
        ident = f"{can_id & 0x1FFFFFFF | 0x20000000:08X}"
    elif "ext" in flags:
        ident = f"{can_id:08X}"
    else:
        ident = f"{can_id:03X}"
    if "fd" in flags:
        return f"({t_s:017.6f}) {chan} {ident}##0{bytes(data).hex().upper()}"
    if "rtr" in flags:
        return f"({t_s:017.6f}) {chan} {ident}#R"
    return f"({t_s:017.6f}) {chan} {ident}#{bytes(data).hex().upper()}"


def convert(src, dst):
    """Copy every frame of one log into another format; returns the count."""
    frames = read_frames(src)
    w = FrameWriter(dst)
    try:
        for fr in frames:
            w.write(fr)
    finally:
        w.close()
    return len(frames)
