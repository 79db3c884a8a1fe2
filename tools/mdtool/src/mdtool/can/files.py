"""Input and output files of the CAN commands: read with a size limit and a
clear error, output checked before anything is sent to a drive.

A drive file (`config load`) is a few kB: more than READ_LIMIT_BYTES is
refused as not a drive file (`config load /dev/zero` must not read until
memory runs out). The DBC and the parameter table have their own limits
(DBC_LIMIT_BYTES, META_LIMIT_BYTES): ten times the repository's files.
"""
import os

from .errors import UsageError

READ_LIMIT_BYTES = 1 << 20   # drive/motor/board TOML files (the shipped ones: < 5 kB)
DBC_LIMIT_BYTES = 1 << 20    # tools/can/motordrive.dbc: about 20 kB
META_LIMIT_BYTES = 4 << 20   # tools/config/params_meta.json: about 60 kB


def read_limited(path, limit=READ_LIMIT_BYTES, what="file"):
    """The bytes of `path`, at most `limit` of them; UsageError with the
    path and the reason for an unreadable, oversized or directory path."""
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
    except OSError as e:
        raise UsageError(f"cannot read {what} {path}: {e.strerror or e}") from e
    if len(data) > limit:
        raise UsageError(f"{path}: more than {limit} bytes: not a {what} (nothing sent)")
    return data


def read_text(path, limit=READ_LIMIT_BYTES, what="file"):
    try:
        return read_limited(path, limit, what).decode("utf-8")
    except UnicodeDecodeError as e:
        raise UsageError(f"{path}: not UTF-8 text (byte {e.start}): not a {what}") from e


def check_writable(path, what="output file"):
    """Refuse, before any frame is sent, an output path that cannot be
    written: a missing or read-only folder, or a folder in its place."""
    d = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise UsageError(f"{what} {path} is a folder")
    if not os.path.isdir(d):
        raise UsageError(f"{what} {path}: no folder {d}")
    if not os.access(d, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise UsageError(f"{what} {path}: not writable")


def write_atomic(path, text):
    """Write `text` to a temporary file beside `path`, then rename it over
    `path`: an interrupted write leaves the old file, never half a file."""
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)), f".{os.path.basename(path)}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except OSError as e:
        raise UsageError(f"cannot write {path}: {e.strerror or e}") from e
