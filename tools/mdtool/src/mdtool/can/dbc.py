"""The DBC and the frame-level codec (moved from tools/can/mc_can.py).

Identifiers are node_id << 5 | cmd; the DBC is written for node 1. The own
little-endian decoder is independent of cantools' (the tests cross-check).
"""
import math
import re

from .errors import UsageError
from .files import DBC_LIMIT_BYTES, read_text
from .paths import dbc_path

DBC_NODE = 1  # node id the DBC file's frame ids are written for
CMD_BITS = 5
CMD_MASK = (1 << CMD_BITS) - 1
NODE_MAX = 62  # 63 (all ones) is kept free for a broadcast address


def load_db(path=None):
    import cantools  # imported here so --help works without the venv
    path = path or dbc_path()
    text = read_text(path, DBC_LIMIT_BYTES, "DBC file")
    try:
        return cantools.database.load_string(text, database_format="dbc", strict=True)
    except (cantools.database.UnsupportedDatabaseFormatError, cantools.database.Error) as e:
        raise UsageError(f"cannot load DBC {path}: {e}") from e


def cmd_of(msg):
    return msg.frame_id & CMD_MASK


def frame_id(node, cmd):
    if not 0 <= node <= NODE_MAX:
        raise UsageError(f"node id {node} out of range 0..{NODE_MAX}")
    return (node << CMD_BITS) | cmd


def node_of(can_id):
    return can_id >> CMD_BITS


def by_cmd(db):
    return {cmd_of(m): m for m in db.messages}


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
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise UsageError(f"{msg.name}.{s.name}={v}: not a finite number")
        if s.minimum is not None and not (s.minimum - s.scale / 2 <= v <= s.maximum + s.scale / 2):
            raise UsageError(f"{msg.name}.{s.name}={v} outside [{s.minimum}, {s.maximum}]")
        raw = round((v - s.offset) / s.scale)
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
            raise UsageError(f"{k}: not a number: {v!r}") from None
    return vals


def find_message(db, name):
    try:
        return db.get_message_by_name(name.upper())
    except KeyError:
        raise UsageError(f"unknown message {name!r} (known: {', '.join(m.name for m in db.messages)})") from None


def table_markdown(db):
    """The protocol table (Markdown) for the README."""
    out = ["| id (node 1) | cmd | message | dir | len | signal | bits | scale | range | unit |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for m in sorted(db.messages, key=lambda m: m.frame_id):
        d = "drive→host" if m.senders == ["Drive"] else "host→drive"
        sigs = m.signals or [None]
        for i, s in enumerate(sigs):
            head = (f"| 0x{m.frame_id:03X} | 0x{cmd_of(m):02X} | {m.name} | {d} | {m.length} "
                    if i == 0 else "| | | | | ")
            if s is None:
                out.append(head + "| — | | | | |")
                continue
            sign = "s" if s.is_signed else "u"
            rng = f"{s.minimum:g} … {s.maximum:g}"
            if s.choices:
                rng += " (" + ", ".join(f"{k} {v}" for k, v in s.choices.items()) + ")"
            out.append(head + f"| {s.name} | {s.start}+{s.length}{sign} | {s.scale:g} | {rng} | {s.unit or ''} |")
    return "\n".join(out)


def rebase_dbc_text(text, node):
    """The DBC text with every frame id moved from node DBC_NODE to `node`."""
    shift = (node - DBC_NODE) << CMD_BITS
    frame_id(node, 0)

    def rebase(m):
        return m.group(1) + str(int(m.group(2)) + shift)
    text = re.sub(r"^(BO_ )(\d+)", rebase, text, flags=re.M)
    return re.sub(r"^((?:CM_ BO_|CM_ SG_|VAL_) )(\d+)", rebase, text, flags=re.M)


# ------------------------------------------------------------------ gen-c
def _cfloat(v):
    r = repr(float(v))
    if "e" not in r and "." not in r:
        r += ".0"
    return r + "f"


def gen_c(db, dbc_name):
    msgs = sorted(db.messages, key=cmd_of)
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
