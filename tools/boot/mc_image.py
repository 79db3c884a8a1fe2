#!/usr/bin/env python3
"""Application images for the bootloader (firmware/boot/README.md).

    mc_image.py seal ELF --objcopy OBJCOPY      fill the image header of a linked
                                                application (image_bytes, CRC-32,
                                                commit) in the ELF, write ELF's .bin
    mc_image.py info IMAGE.bin                  the header; exit 1 if the image is bad
    mc_image.py combine --boot BOOT.bin --app APP.bin -o OUT.bin [--size BYTES]
                                                the bootloader and the application in
                                                one file from 0x08000000 (SWD, QEMU)

The build seals every application image after the link (the cross build's
mc_f405_image, tests/target); the header format lives in the mdtool
package (mdtool.can.image, from this tree's source), which `mdtool flash`
uses to check a file before it sends it. Exit codes: 0, 1 (a bad image),
2 (usage, or a tool that failed).
"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "mdtool", "src"))

from mdtool.can import image  # noqa: E402
from mdtool.can.errors import UsageError  # noqa: E402


def _objcopy(objcopy, *args):
    r = subprocess.run([objcopy, *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise UsageError(f"{objcopy} {' '.join(args)}: {r.stderr.strip()}")


def cmd_seal(a):
    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "raw.bin")
        _objcopy(a.objcopy, "-O", "binary", a.elf, raw)
        with open(raw, "rb") as f:
            sealed = image.seal(f.read())
        hdr = os.path.join(tmp, "hdr.bin")
        with open(hdr, "wb") as f:
            f.write(sealed[image.HDR_OFFSET:image.MIN_BYTES])
        _objcopy(a.objcopy, f"--update-section=.mc_image_header={hdr}", a.elf)
    out = a.bin or os.path.splitext(a.elf)[0] + ".bin"
    _objcopy(a.objcopy, "-O", "binary", a.elf, out)
    with open(out, "rb") as f:
        data = f.read()
    if data != sealed:
        raise UsageError(f"{out}: the sealed ELF does not give the sealed image (is the header "
                         "the last word of its section?)")
    print(f"{os.path.basename(a.elf)}: {image.describe(image.check(data))} -> {out}")
    return 0


def cmd_info(a):
    with open(a.image, "rb") as f:
        data = f.read()
    try:
        h = image.check(data)
    except UsageError as e:
        print(f"{a.image}: {e}", file=sys.stderr)
        return 1
    print(f"{a.image}: {image.describe(h)}, "
          f"{'committed' if h['commit'] == image.COMMIT_MAGIC else 'not committed'}")
    return 0


def cmd_combine(a):
    with open(a.boot, "rb") as f:
        boot = f.read()
    with open(a.app, "rb") as f:
        app = f.read()
    image.check(app)
    with open(a.out, "wb") as f:
        f.write(image.combine(boot, app, a.size))
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(prog="mc_image.py", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("seal")
    p.add_argument("elf")
    p.add_argument("--objcopy", default="arm-none-eabi-objcopy")
    p.add_argument("--bin", help="the sealed binary (default: ELF with .bin)")
    p.set_defaults(fn=cmd_seal)
    p = sub.add_parser("info")
    p.add_argument("image")
    p.set_defaults(fn=cmd_info)
    p = sub.add_parser("combine")
    p.add_argument("--boot", required=True)
    p.add_argument("--app", required=True)
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--size", type=lambda s: int(s, 0))
    p.set_defaults(fn=cmd_combine)
    a = ap.parse_args(argv)
    try:
        return a.fn(a)
    except (UsageError, OSError) as e:
        print(f"mc_image.py: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
