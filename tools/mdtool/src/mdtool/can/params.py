"""The drive's parameter table (tools/config/params_meta.json, generated
from tools/config/params.toml) and the simulator's motor/board TOML format.

File format of `config export` / `config load`: the keys of
sim/motors/*.toml in a [motor] table (parameters of group "motor") and a
[board] table (group "board"); every other writable parameter in a [drive]
table. `name` and `source` keys are descriptions, not parameters: they are
ignored on load. A motor file or a board file alone loads as it is.
"""
import json
import math
import struct

from .errors import UsageError
from .files import META_LIMIT_BYTES, READ_LIMIT_BYTES, read_text, write_atomic
from .paths import params_meta_path

SECTIONS = ("motor", "board", "drive")
DESCRIPTIVE_KEYS = ("name", "source")


class ParamTable:
    def __init__(self, path=None):
        path = path or params_meta_path()
        text = read_text(path, META_LIMIT_BYTES, "parameter table")
        try:
            meta = json.loads(text)
            if not isinstance(meta.get("params"), list):
                raise ValueError("no list 'params'")
        except (ValueError, AttributeError) as e:
            raise UsageError(f"cannot read the parameter table {path}: {e}") from e
        self.path = path
        self.params = meta["params"]
        self.by_name = {p["name"]: p for p in self.params}
        self.by_id = {p["id"]: p for p in self.params}

    def get(self, name):
        p = self.by_name.get(name)
        if p is None:
            raise UsageError(f"unknown parameter {name!r} (see `mdtool config list`; "
                             f"{len(self.params)} parameters in {self.path})")
        return p

    @staticmethod
    def section(p):
        return p["group"] if p["group"] in ("motor", "board") else "drive"

    @staticmethod
    def range_text(p):
        return f"[{fmt_value(p, p['min'])}, {fmt_value(p, p['max'])}] {p['unit']}".rstrip()

    def check(self, name, value):
        """The value as the drive will store it, or UsageError (checked here
        before anything is sent): type, finiteness, range, access."""
        p = self.get(name)
        if p["access"] == "readonly":
            raise UsageError(f"{name} is readonly (computed by the drive)")
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                raise UsageError(f"{name}: not a number: {value!r}") from None
        try:
            value = float(value)
        except OverflowError:
            raise UsageError(f"{name}: {value} is too large for a number") from None
        if not math.isfinite(value):
            raise UsageError(f"{name}: {value} is not finite")
        if p["type"] == "u32":
            if value != int(value):
                raise UsageError(f"{name}: {value:g} is not a whole number ({name} is u32)")
            value = int(value)
        else:
            value = float(struct.unpack("<f", struct.pack("<f", value))[0])
        if not p["min"] <= value <= p["max"]:
            raise UsageError(f"{name} = {value:g} refused here: outside its range "
                             f"{self.range_text(p)} (params_meta.json); nothing sent")
        return value


def to_raw(p, value):
    if p["type"] == "u32":
        return int(value) & 0xFFFFFFFF
    return struct.unpack("<I", struct.pack("<f", float(value)))[0]


def from_raw(p, raw):
    if p["type"] == "u32":
        return int(raw)
    return float(struct.unpack("<f", struct.pack("<I", int(raw) & 0xFFFFFFFF))[0])


def fmt_value(p, v):
    """Shortest text that reads back as the same float32 (u32: the integer)."""
    if p["type"] == "u32":
        return str(int(v))
    f = float(v)
    for digits in range(6, 18):
        t = f"{f:.{digits}g}"
        if struct.pack("<f", float(t)) == struct.pack("<f", f):
            break
    if "e" not in t and "." not in t and "inf" not in t and "nan" not in t:
        t += ".0"
    return t


def read_toml(path, table):
    """[(name, value)] in file order from a motor/board/drive TOML file (at
    most files.READ_LIMIT_BYTES); a file without a parameter is refused."""
    import tomllib
    text = read_text(path, READ_LIMIT_BYTES, "drive file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UsageError(f"{path}: not valid TOML: {e}") from e
    out = []
    for sec, body in doc.items():
        if sec not in SECTIONS or not isinstance(body, dict):
            raise UsageError(f"{path}: unknown table [{sec}] (expected {', '.join(SECTIONS)})")
        for k, v in body.items():
            if k in DESCRIPTIVE_KEYS:
                continue
            if k not in table.by_name:
                raise UsageError(f"{path}: [{sec}] {k}: not a drive parameter")
            p = table.by_name[k]
            if table.section(p) != sec:
                raise UsageError(f"{path}: {k} belongs in [{table.section(p)}], not [{sec}]")
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise UsageError(f"{path}: [{sec}] {k}: a number is expected, got {v!r}")
            out.append((k, v))
    if not out:
        raise UsageError(f"{path}: no parameter in it (a [motor], [board] or [drive] table with "
                         f"at least one parameter is expected); nothing sent")
    return out


def write_toml(path, table, values, header):
    """values: {name: value} of the drive; readonly ones become comments."""
    lines = [f"# {h}" for h in header]
    for sec in SECTIONS:
        ps = [p for p in table.params if table.section(p) == sec and p["name"] in values]
        if not ps:
            continue
        lines += ["", f"[{sec}]"]
        for p in ps:
            v = fmt_value(p, values[p["name"]])
            note = f"{p['unit']}, {p['access']}" if p["unit"] else p["access"]
            if p["access"] == "readonly":
                lines.append(f"# {p['name']} = {v}  # readonly")
            else:
                lines.append(f"{p['name']} = {v}  # {note}")
    write_atomic(path, "\n".join(lines) + "\n")
