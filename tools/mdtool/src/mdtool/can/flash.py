"""`mdtool flash`: an application image into a drive over CAN, through its
bootloader (firmware/boot/README.md; BOOT_REQ, BOOT_DATA and BOOT_REPLY of
the DBC).

For each node in turn: INFO (the node's board and memory layout must be
the image's, else nothing more is sent); from the running application
ENTER and its confirmation (the drive must be disabled), then the
bootloader's answer; BEGIN (the bootloader checks the image's board,
layout, header version and size, then erases what it needs), every block
of 256 bytes with its CRC-32, answered once each (resent on a refusal or
a lost answer, up to `retries` times), VERIFY (the bootloader's own check
of the whole slot against the image's CRC-32), COMMIT; then the node resets
and must come back running the image's version. A node that waits in its
bootloader (a cut update, an invalid image) is updated the same way.
"""
import time
import zlib

from . import image
from .dbc import CMD_MASK, frame_id, node_of
from .errors import NoReply, Refused, UsageError

CMD_REPLY, CMD_REQ, CMD_DATA = 0x0F, 0x1A, 0x1B
OPS = {"ANNOUNCE": 0, "INFO": 1, "VERSION": 2, "ENTER": 3, "ENTER_CONFIRM": 4, "BEGIN": 16,
       "WRITE": 17, "VERIFY": 18, "COMMIT": 19, "ABORT": 20, "RUN": 21}
ENTER_KEY = 0x544F4F42
BLOCK, CHUNK = 256, 7
#: Why a status (BOOT_REPLY.boot_status) refuses (firmware/boot/README.md).
STATUS_HELP = {
    "OPCODE": "the node does not know this request (an older bootloader?)",
    "FORMAT": "a malformed frame (length, reserved fields)",
    "STATE": "not in this state (the application answers only INFO, VERSION and ENTER)",
    "BOARD": "the image is for another board",
    "LAYOUT": "the image is linked for another memory layout",
    "HEADER": "the image's header is not what BEGIN announced, or not one this bootloader takes",
    "SIZE": "the image does not fit the application slot",
    "SEQUENCE": "a block out of order or with frames missing",
    "BLOCK_CRC": "a block arrived with other bytes than its CRC-32 says",
    "FLASH": "the flash could not be erased, written or read back",
    "IMAGE_CRC": "the image in the slot does not match the file's CRC-32",
    "KEY": "ENTER needs its key, and its confirmation the token it answered, within 1 s",
    "BUSY": "the drive is running: disable it first",
}
# Erase time per slot sector, RM0090/DS8626 worst case at x32 (16 KiB 0.5 s,
# 64 KiB 1.1 s, 128 KiB 2 s), with margin.
_ERASE_S = {0x4000: 0.8, 0x10000: 1.5, 0x20000: 2.5}
_SLOT_SECTORS = [0x4000, 0x4000, 0x4000, 0x10000] + [0x20000] * 5


def erase_timeout(image_bytes):
    """Seconds BEGIN may take for an image of this size (the sectors it erases)."""
    t, covered = 1.0, 0
    for size in _SLOT_SECTORS:
        if covered >= image_bytes:
            break
        t += _ERASE_S[size]
        covered += size
    return t


def data_frames(block):
    """The BOOT_DATA payloads of one block: chunk index, 7 bytes, zero padding."""
    out = []
    for c in range(0, len(block), CHUNK):
        part = block[c:c + CHUNK]
        out.append(bytes([c // CHUNK]) + part + b"\0" * (CHUNK - len(part)))
    return out


class Flasher:
    def __init__(self, bus, db, node, timeout=1.0, retries=3, progress=print):
        import can
        self._can = can
        self.bus, self.db, self.node, self.timeout = bus, db, node, timeout
        self.retries, self.progress = retries, progress or (lambda *a: None)
        self.reply_msg = db.get_message_by_name("BOOT_REPLY")
        self.req_msg = db.get_message_by_name("BOOT_REQ")
        frame_id(node, 0)

    # ------------------------------------------------------------ frames
    def _send(self, cmd, data):
        self.bus.send(self._can.Message(arbitration_id=frame_id(self.node, cmd), data=data,
                                        is_extended_id=False))

    def request(self, op, arg=0, value=0):
        self._send(CMD_REQ, self.req_msg.encode({"boot_op": OPS[op], "arg": arg, "value": value}))

    def reply(self, op, timeout, also=()):
        """The next BOOT_REPLY to `op` (or to one of `also`) from our node, decoded."""
        t_end = time.monotonic() + timeout
        while True:
            left = t_end - time.monotonic()
            if left <= 0:
                raise NoReply(f"no BOOT_REPLY to {op} from node {self.node} within {timeout:g} s "
                              "(is the node on this bus, with this node id and bit rate?)")
            m = self.bus.recv(min(left, 0.1))
            if (m is None or m.is_extended_id or m.is_error_frame or node_of(m.arbitration_id) != self.node
                    or m.arbitration_id & CMD_MASK != CMD_REPLY or len(m.data) != 8):
                continue
            r = self.reply_msg.decode(bytes(m.data), decode_choices=True)
            if str(r["boot_op"]) == op or str(r["boot_op"]) in also:
                r["value"] = int(r["value"])
                return r

    def ask(self, op, arg=0, value=0, timeout=None, ok=("OK",)):
        self.request(op, arg, value)
        r = self.reply(op, timeout or self.timeout)
        st = str(r["boot_status"])
        if st not in ok:
            raise Refused(f"node {self.node} refused {op}: {st}"
                          + (f" ({STATUS_HELP[st]})" if st in STATUS_HELP else ""), status=st,
                          value=r["value"])
        return r

    # ------------------------------------------------------------ steps
    def check_target(self, hdr):
        """INFO: the node's board and layout against the image's; the reply."""
        r = self.ask("INFO")
        board, layout = r["value"] & 0xFF, (r["value"] >> 8) & 0xFF
        if board != hdr["board_id"] or layout != hdr["layout_id"]:
            raise UsageError(f"the image is for {image.board_name(hdr['board_id'])} (layout "
                             f"{hdr['layout_id']}), node {self.node} is {image.board_name(board)} "
                             f"(layout {layout}): nothing sent")
        return r

    def enter(self, wait=10.0):
        """From the application into the bootloader (ENTER, confirmation)."""
        tok = self.ask("ENTER", value=ENTER_KEY, ok=("CONFIRM",))["value"]
        self.ask("ENTER_CONFIRM", value=tok)
        t_end = time.monotonic() + wait
        while time.monotonic() < t_end:
            try:  # the bootloader announces itself as it starts
                r = self.reply("INFO", 0.3, also=("ANNOUNCE",))
            except NoReply:
                self.request("INFO")
                continue
            if str(r["boot_state"]) != "APP":
                return r
        raise NoReply(f"node {self.node} confirmed ENTER but its bootloader did not answer "
                      f"within {wait:g} s")

    def block_reply(self, k):
        """The answer to block k. Answers to an earlier block (one resent
        after its answer came late: the node answers the copy too) are
        passed over."""
        t_end = time.monotonic() + self.timeout
        while True:
            r = self.reply("WRITE", max(t_end - time.monotonic(), 0.0))
            ok, v = str(r["boot_status"]) == "OK", r["value"]
            if (ok and v <= k) or (not ok and v < k):
                continue  # stale: about an earlier block
            return r

    def write_block(self, data, k):
        """Block k until the bootloader took it; its reply."""
        blk = data[k * BLOCK:(k + 1) * BLOCK]
        crc = zlib.crc32(blk) & 0xFFFFFFFF
        last = None
        for _ in range(self.retries + 1):
            self.request("WRITE", k, crc)
            for f in data_frames(blk):
                self._send(CMD_DATA, f)
            try:
                r = self.block_reply(k)
            except NoReply as e:
                last = e
                continue  # the answer was lost, or a frame: send the block again
            st = str(r["boot_status"])
            if st == "OK" and r["value"] == k + 1:
                return r
            last = Refused(f"node {self.node} refused block {k}: {st}"
                           + (f" ({STATUS_HELP[st]})" if st in STATUS_HELP else "")
                           + ("" if st != "OK" else f" (it expects block {r['value']})"), status=st)
            if st not in ("SEQUENCE", "BLOCK_CRC", "FORMAT"):
                break  # HEADER, FLASH, STATE: sending it again will not help
        raise last

    def update(self, data, hdr):
        n = (len(data) + BLOCK - 1) // BLOCK
        arg = hdr["board_id"] | (hdr["layout_id"] << 8) | (hdr["hdr_version"] << 16)
        r = self.ask("BEGIN", arg, len(data), timeout=erase_timeout(len(data)))
        self.progress(f"node {self.node}: erased {r['value']} sector(s), writing {n} blocks")
        shown = -1
        for k in range(n):
            self.write_block(data, k)
            pct = 100 * (k + 1) // n
            if pct // 10 != shown:
                shown = pct // 10
                self.progress(f"node {self.node}: {pct:3d} % ({k + 1}/{n} blocks)")
        r = self.ask("VERIFY", value=hdr["crc32"], timeout=max(self.timeout, 3.0))
        self.progress(f"node {self.node}: verified (CRC-32 0x{r['value']:08X})")
        self.ask("COMMIT", timeout=max(self.timeout, 3.0))
        self.progress(f"node {self.node}: committed, resetting")

    def wait_running(self, version, wait=10.0):
        """The node back from its reset, running `version`."""
        t_end = time.monotonic() + wait
        while time.monotonic() < t_end:
            self.request("VERSION")
            try:
                r = self.reply("VERSION", 0.3)
            except NoReply:
                continue
            if str(r["boot_state"]) == "APP":
                if r["value"] != version:
                    raise Refused(f"node {self.node} runs version {image.version_text(r['value'])}, "
                                  f"not the image's {image.version_text(version)}", status="VERSION")
                return r
        raise NoReply(f"node {self.node} did not come back running the new image within {wait:g} s")

    def flash(self, data, hdr, wait=10.0):
        r = self.check_target(hdr)
        if str(r["boot_state"]) == "APP":
            cur = self.ask("VERSION")["value"]
            self.progress(f"node {self.node}: running version {image.version_text(cur)}, "
                          "entering its bootloader")
            self.enter(wait)
        else:
            self.progress(f"node {self.node}: in its bootloader ({r['boot_state']}, "
                          f"{r['boot_reason']})")
            if str(r["boot_state"]) != "IDLE":
                self.ask("ABORT")
        self.update(data, hdr)
        self.wait_running(hdr["app_version"], wait)
        self.progress(f"node {self.node}: running version {image.version_text(hdr['app_version'])}")


def read_image(path):
    """The bytes and header of an image file, checked (UsageError otherwise)."""
    try:
        with open(path, "rb") as f:
            data = f.read(image.APP_MAX_BYTES + 1)
    except OSError as e:
        raise UsageError(f"{path}: {e.strerror}") from e
    try:
        return data, image.check(data)
    except UsageError as e:
        raise UsageError(f"{path}: {e}") from e


def parse_nodes(items):
    """-n 1 -n 3,4 -> [1, 3, 4]; each 0..62, no repeats."""
    out = []
    for it in items or ["1"]:
        for s in str(it).split(","):
            try:
                n = int(s)
            except ValueError:
                raise UsageError(f"node {s!r}: an integer 0..62") from None
            frame_id(n, 0)
            if n in out:
                raise UsageError(f"node {n} given twice")
            out.append(n)
    return out

