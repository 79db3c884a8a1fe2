"""Application images for the bootloader (firmware/boot/mc_boot_image.h):
the header, its CRC-32, sealing a freshly linked image and checking a file
before it is sent. The constants are the C header's; tests/update checks
they agree.

An image is the application's flash contents from the start of the
application slot (0x08004000 on the STM32F405, layout 1): the vector table,
the 32-byte header at HDR_OFFSET, then the rest. CRC-32 (zlib's) over every
byte but the header's crc32 and commit words.
"""
import struct
import zlib

from .errors import UsageError

MAGIC = 0x474D494D          # "MIMG"
COMMIT_MAGIC = 0x54494D43   # "CMIT"
HDR_VERSION = 1
HDR_OFFSET = 0x188
HDR_BYTES = 32
CRC_OFFSET = HDR_OFFSET + 24
COMMIT_OFFSET = HDR_OFFSET + 28
MIN_BYTES = HDR_OFFSET + HDR_BYTES
LAYOUT_ID = 1
APP_ADDR = 0x08004000
APP_MAX_BYTES = 752 * 1024
BOOT_ADDR = 0x08000000
BOOT_MAX_BYTES = 16 * 1024
RAM_START, RAM_END = 0x20000000, 0x20020000
BOARDS = {1: "example", 2: "odrive36", 3: "vesc6", 4: "odrive36_24v", 100: "pil"}
_FIELDS = ("magic", "hdr_version", "board_id", "layout_id", "app_version", "image_bytes",
           "crc32", "commit")


def image_crc(data):
    """The image CRC of data (the crc32 and commit words left out)."""
    c = zlib.crc32(data[:CRC_OFFSET])
    return zlib.crc32(data[MIN_BYTES:], c) & 0xFFFFFFFF


def version_text(v):
    return f"{v >> 16}.{(v >> 8) & 0xFF}.{v & 0xFF}"


def board_name(b):
    return BOARDS.get(b, f"board {b}")


def describe(h):
    """One line about an image's header: board, layout, version, length, CRC-32."""
    return (f"{board_name(h['board_id'])}, layout {h['layout_id']}, version "
            f"{version_text(h['app_version'])}, {h['image_bytes']} bytes, CRC-32 0x{h['crc32']:08X}")


def header(data):
    """The header fields of an image (a dict), or UsageError if it has none."""
    if len(data) < MIN_BYTES:
        raise UsageError(f"{len(data)} bytes: too short for an image (at least {MIN_BYTES})")
    vals = struct.unpack_from("<8I", data, HDR_OFFSET)
    return dict(zip(_FIELDS, vals, strict=True))


def check(data):
    """The header of a sealed image, or UsageError naming what is wrong: the
    same checks the bootloader makes (but the board and the layout, which
    the caller compares with the node's)."""
    h = header(data)
    if h["magic"] != MAGIC:
        raise UsageError(f"no image header at 0x{HDR_OFFSET:X} (magic 0x{h['magic']:08X}): "
                         "not an application image built for the bootloader")
    if h["hdr_version"] != HDR_VERSION:
        raise UsageError(f"header version {h['hdr_version']}, this tool knows {HDR_VERSION}")
    if h["image_bytes"] != len(data) or len(data) % 4 or len(data) > APP_MAX_BYTES:
        raise UsageError(f"header says {h['image_bytes']} bytes, the file has {len(data)} "
                         f"(a multiple of 4, at most {APP_MAX_BYTES})")
    crc = image_crc(data)
    if crc != h["crc32"]:
        raise UsageError(f"CRC-32 0x{crc:08X} does not match the header's 0x{h['crc32']:08X}: "
                         "the file is corrupt or was changed after it was sealed")
    sp, pc = struct.unpack_from("<2I", data, 0)
    if not (RAM_START <= sp <= RAM_END) or not pc & 1 or not APP_ADDR <= (pc & ~1) < APP_ADDR + len(data):
        raise UsageError(f"vectors SP 0x{sp:08X}, reset 0x{pc:08X}: not linked for the slot at "
                         f"0x{APP_ADDR:08X}")
    return h


def seal(data):
    """The image with image_bytes, crc32 and commit filled (commit set: the
    form flashed over SWD; the bootloader writes commit itself after an
    update). data: the linked image from the slot's start."""
    data = bytearray(data)
    data += b"\xff" * (-len(data) % 4)
    h = header(bytes(data))
    if h["magic"] != MAGIC or h["hdr_version"] != HDR_VERSION or h["layout_id"] != LAYOUT_ID:
        raise UsageError(f"no image header of layout {LAYOUT_ID} at 0x{HDR_OFFSET:X}: "
                         "is the image header linked (firmware/targets/stm32f405/mc_image_header.c)?")
    if len(data) > APP_MAX_BYTES:
        raise UsageError(f"{len(data)} bytes: larger than the slot ({APP_MAX_BYTES})")
    struct.pack_into("<I", data, HDR_OFFSET + 20, len(data))
    struct.pack_into("<I", data, CRC_OFFSET, image_crc(bytes(data)))
    struct.pack_into("<I", data, COMMIT_OFFSET, COMMIT_MAGIC)
    return bytes(data)


def combine(boot, app, size=None):
    """One file from 0x08000000: the bootloader, erased flash up to the
    slot, the (sealed) application; `size` pads it (QEMU's 1 MiB flash)."""
    if len(boot) > BOOT_MAX_BYTES:
        raise UsageError(f"bootloader {len(boot)} bytes: larger than its sector ({BOOT_MAX_BYTES})")
    out = bytearray(boot) + b"\xff" * (APP_ADDR - BOOT_ADDR - len(boot)) + bytes(app)
    if size is not None:
        if len(out) > size:
            raise UsageError(f"{len(out)} bytes do not fit in {size}")
        out += b"\xff" * (size - len(out))
    return bytes(out)
