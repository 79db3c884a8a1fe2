#!/usr/bin/env python3
"""The host side of the image format and the update messages agrees with
the firmware's:

- mdtool.can.image's constants equal the #defines of
  firmware/boot/mc_boot_image.h and mc_boot_layout.h (magic, offsets,
  versions, the slot, the board ids);
- a sealed image from the build (the update tests' application) passes
  `mc_image.py info` and image.check; any changed byte in the CRC's range
  is refused by name (exit 1), an image linked elsewhere too;
- `combine` puts the bootloader at 0 and the image at the slot;
- BOOT_DATA frames of mdtool.can.flash equal cantools' encoding of the DBC
  message, chunk by chunk; BOOT_REQ's fields sit where the C decoder reads
  them (byte 0 op, bytes 1..3 arg, 4..7 value).

    test_image_tool.py --image SEALED.bin --boot BOOT.bin --work DIR
"""
import argparse
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools", "mdtool", "src"))

from mdtool.can import dbc, flash, image  # noqa: E402
from mdtool.can.errors import UsageError  # noqa: E402

fails = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)


def defines(path):
    out = {}
    for m in re.finditer(r"^#define\s+(MC_BOOT_\w+)\s+\(?(0x[0-9A-Fa-f]+|\d+)u?", Path(path).read_text(), re.M):
        out[m.group(1)] = int(m.group(2), 0)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--image", required=True)
    ap.add_argument("--boot", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    d = defines(os.path.join(ROOT, "firmware", "boot", "mc_boot_image.h"))
    d.update(defines(os.path.join(ROOT, "firmware", "boot", "mc_boot_layout.h")))
    pairs = {"MC_BOOT_IMAGE_MAGIC": image.MAGIC, "MC_BOOT_COMMIT_MAGIC": image.COMMIT_MAGIC,
             "MC_BOOT_HDR_VERSION": image.HDR_VERSION, "MC_BOOT_HDR_OFFSET": image.HDR_OFFSET,
             "MC_BOOT_LAYOUT_ID": image.LAYOUT_ID, "MC_BOOT_APP_ADDR": image.APP_ADDR,
             "MC_BOOT_FLASH_BASE": image.BOOT_ADDR, "MC_BOOT_RAM_START": image.RAM_START,
             "MC_BOOT_RAM_END": image.RAM_END, "MC_BOOT_BOARD_EXAMPLE": 1,
             "MC_BOOT_BOARD_ODRIVE36": 2, "MC_BOOT_BOARD_VESC6": 3, "MC_BOOT_BOARD_PIL": 100}
    for k, v in pairs.items():
        check(d.get(k) == v, f"{k}: C {d.get(k)}, Python {v}")
    layout_h = Path(ROOT, "firmware", "boot", "mc_boot_layout.h").read_text()
    check(image.APP_MAX_BYTES == 752 * 1024 and "(752u * 1024u)" in layout_h, "slot size 752 KiB")
    check(image.BOARDS == {1: "example", 2: "odrive36", 3: "vesc6", 4: "odrive36_24v", 100: "pil"}, "board names")

    tool = [sys.executable, os.path.join(ROOT, "tools", "boot", "mc_image.py")]
    data = Path(a.image).read_bytes()
    r = subprocess.run(tool + ["info", a.image], capture_output=True, text=True)
    check(r.returncode == 0 and "committed" in r.stdout, f"info of the sealed image: {r.stdout.strip()}")
    h = image.check(data)
    check(h["image_bytes"] == len(data) and h["crc32"] == image.image_crc(data), "header fields")
    for at in (0, 100, image.HDR_OFFSET + 16, image.MIN_BYTES, len(data) - 1):
        bad = bytearray(data)
        bad[at] ^= 0x80
        path = os.path.join(a.work, "bad.bin")
        Path(path).write_bytes(bad)
        r = subprocess.run(tool + ["info", path], capture_output=True, text=True)
        check(r.returncode == 1 and ("CRC-32" in r.stderr or "header" in r.stderr),
              f"a changed byte at {at} refused: {r.stderr.strip()}")
    # the commit and CRC words are outside the CRC: changing commit keeps it
    unc = bytearray(data)
    unc[image.COMMIT_OFFSET:image.COMMIT_OFFSET + 4] = b"\xff" * 4
    check(image.image_crc(bytes(unc)) == h["crc32"], "the commit word is outside the CRC")
    moved = bytearray(data)
    struct.pack_into("<I", moved, 4, 0x08000101)
    try:
        image.check(image.seal(bytes(moved)))
        check(False, "an image whose reset vector is outside the slot was accepted")
    except UsageError as e:
        check("not linked for the slot" in str(e), f"vectors refused: {e}")

    out = os.path.join(a.work, "combined.bin")
    r = subprocess.run(tool + ["combine", "--boot", a.boot, "--app", a.image, "-o", out,
                               "--size", "0x100000"], capture_output=True, text=True)
    comb = Path(out).read_bytes() if r.returncode == 0 else b""
    boot = Path(a.boot).read_bytes()
    check(len(comb) == 1 << 20 and comb[:len(boot)] == boot and comb[0x4000:0x4000 + len(data)] == data
          and comb[len(boot):0x4000] == b"\xff" * (0x4000 - len(boot)), "combine: bootloader and slot")

    db = dbc.load_db(None)
    m = db.get_message_by_name("BOOT_DATA")
    blk = bytes(range(256))
    for i, f in enumerate(flash.data_frames(blk)):
        vals = {"chunk": i, **{f"d{j}": (blk[7 * i + j] if 7 * i + j < 256 else 0) for j in range(7)}}
        if m.encode(vals) != f:
            check(False, f"BOOT_DATA chunk {i}: mdtool {f.hex()}, cantools {m.encode(vals).hex()}")
            break
    else:
        check(len(flash.data_frames(blk)) == 37, "BOOT_DATA: 37 chunks of a block equal cantools'")
    q = db.get_message_by_name("BOOT_REQ").encode({"boot_op": "WRITE", "arg": 0x123456,
                                                    "value": 0xA1B2C3D4})
    check(q == bytes([17, 0x56, 0x34, 0x12, 0xD4, 0xC3, 0xB2, 0xA1]), f"BOOT_REQ layout {q.hex()}")
    check(flash.erase_timeout(len(data)) >= 1.0 + 0.8 * 2, "BEGIN waits for the sectors it erases")
    print(f"image tool: {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
