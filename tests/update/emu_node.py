"""An emulated drive node for the update tests: the STM32F405 under QEMU
(netduinoplus2) running the emulated bootloader and whatever image its
flash holds, with the flash kept in a file between boots and the CAN bus
carried over the boot link (firmware/targets/pil/mc_boot_link.h).

    node = EmuNode(qemu, flash_file, workdir)
    node.power_on()            # QEMU loads the flash file at 0x08000000
    node.send(can_id, data)    # a frame on the bus (the node's clock advances
                               # by its bus time at the bit rate)
    node.recv(timeout)         # a frame the node sent, or None
    node.cut_at(k, mode)       # lose power at flash step k (erase or program)
    node.power_off()

Every erase and program the target asks for is one step: the node applies
it to the file (PROGRAM at word granularity, as NOR flash: bits only clear)
and answers. A cut at step k: "before" (the step never happens) or "half"
(an erase erases the sector's first half; a program writes the first half
of its words and half of the next one, as mc_fake_flash's TEAR_HALF), then
QEMU is killed and the file keeps what was written. A reset the target asks
for (after COMMIT) restarts QEMU with the file: QEMU's flash is read-only
to the CPU, so only a fresh start loads what was written.

EmuBus wraps a node as a python-can bus (mdtool's code runs against it in
process), serve_socketcand() as a socketcand server (python-can's
`socketcand` interface; mdtool as a separate process). Waiting on either
advances the node's clock with the host's (TICK frames), and a reset the
target asks for reboots it, as a board would.
"""
import contextlib
import os
import queue
import shutil
import signal
import socket
import struct
import subprocess
import threading
import time

SYNC = 0xB5
HELLO, CAN_TX, ERASE, PROGRAM, READ, RESET = 1, 2, 3, 4, 5, 6
CAN_RX, TICK, FLASH_DONE, FLASH_DATA = 16, 17, 18, 19
ROLE_BOOT, ROLE_APP = 1, 2
FLASH_BASE = 0x08000000
FLASH_BYTES = 1 << 20
SLOT_SECTORS = range(1, 10)
EINVAL = 22


def crc16(data):
    c = 0xFFFF
    for b in data:
        c ^= b << 8
        for _ in range(8):
            c = ((c << 1) ^ 0x1021) if c & 0x8000 else (c << 1)
            c &= 0xFFFF
    return c


def frame(t, payload=b""):
    head = bytes([t]) + struct.pack("<H", len(payload)) + payload
    return bytes([SYNC]) + head + struct.pack("<H", crc16(head))


def sector_geometry(s):
    """(offset, bytes) of STM32F405 sector s (RM0090 table 5)."""
    if s < 4:
        return s * 0x4000, 0x4000
    if s == 4:
        return 0x10000, 0x10000
    return 0x20000 + (s - 5) * 0x20000, 0x20000


def frame_bits(n_data):
    """Worst-case bits of a classic 11-bit frame (mc_can_frame_bits_worst)."""
    return 55 + 10 * n_data


class PowerCut(Exception):
    """The node lost power at the step it was told to (EmuBus raises it to
    whoever waits on the bus, so a cut update ends at once)."""


class EmuNode:
    def __init__(self, qemu, flash_file, workdir, bitrate=500000, log=None):
        self.qemu, self.flash_file, self.workdir = qemu, flash_file, workdir
        self.bitrate = bitrate
        self.log = log or os.path.join(workdir, "qemu.log")
        os.makedirs(workdir, exist_ok=True)
        with open(flash_file, "rb") as f:
            self.flash = bytearray(f.read())
        if len(self.flash) != FLASH_BYTES:
            raise ValueError(f"{flash_file}: {len(self.flash)} bytes, not 1 MiB")
        self.proc = None
        self.time_us = 0
        self.steps = 0           # erases and programs served (all boots)
        self.ops = []            # (kind, sector, offset, bytes) of every step
        self._cut = None
        self.cut_done = None     # (step, mode) of the cut that happened
        self.reset_requested = False
        self._wlock = threading.Lock()
        # across power cycles: a frame sent just before a reset is still read
        self.rx = queue.Queue()      # CAN frames the node sent: (id, data)
        self.hellos = queue.Queue()  # (role, version, reason/sum, node)

    # ------------------------------------------------------------ power
    def power_on(self):
        """Start QEMU on the flash file (written first), wait for nothing."""
        self._write_file()
        for n in ("mc_boot_h2t", "mc_boot_t2h"):
            p = os.path.join(self.workdir, n)
            if os.path.exists(p):
                os.unlink(p)
            os.mkfifo(p)
        self._h2t = os.open(os.path.join(self.workdir, "mc_boot_h2t"), os.O_RDWR)
        self._t2h = os.open(os.path.join(self.workdir, "mc_boot_t2h"), os.O_RDWR)
        self.reset_requested = False
        self.cut_done = None
        self.hellos = queue.Queue()  # HELLO is per power-on
        with open(self.log, "ab") as lf:
            self.proc = subprocess.Popen(
                [self.qemu, "-M", "netduinoplus2", "-display", "none", "-monitor", "none",
                 "-serial", "null", "-semihosting-config", "enable=on,target=native",
                 "-device", f"loader,file={self.flash_file},addr=0x{FLASH_BASE:08X},force-raw=on"],
                cwd=self.workdir, stdout=lf, stderr=lf, start_new_session=True)
        self._stop = False
        self._reader = threading.Thread(target=self._read_loop, daemon=True)
        self._reader.start()

    def power_off(self):
        """Stop the emulated MCU at once (a power cut); the file keeps the flash."""
        if self.proc is not None:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
            self.proc = None
        self._stop = True
        if getattr(self, "_t2h", None) is not None:
            os.write(self._t2h, b"\0")  # wakes the reader (the FIFO never ends: we hold it too)
        if getattr(self, "_reader", None) is not None:
            self._reader.join(timeout=5)
            self._reader = None
        for fd in (getattr(self, "_h2t", None), getattr(self, "_t2h", None)):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._h2t = self._t2h = None
        self._write_file()

    def reboot(self):
        self.power_off()
        self.power_on()

    def bus(self):
        """This node's EmuBus (one per node, kept across power cycles)."""
        if getattr(self, "_bus", None) is None:
            self._bus = EmuBus(self)
        return self._bus

    def close(self):
        """Power off for good: the bus shut down too."""
        self.power_off()
        if getattr(self, "_bus", None) is not None:
            self._bus.shutdown()
            self._bus = None

    def running(self):
        return self.proc is not None and self.proc.poll() is None

    def wait_reset(self, timeout):
        """True once the target asked for a reset (RESET on the link) and its
        QEMU stopped. The target writes RESET, then exits: the process can be
        gone before the reader thread has taken RESET from the FIFO (a loaded
        machine delays the thread, not the exit), so an exit alone proves
        nothing yet; False when neither comes within `timeout` seconds."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            if self.reset_requested and not self.running():
                return True
            time.sleep(0.005)
        return self.reset_requested and not self.running()

    def exit_status(self):
        return None if self.proc is None else self.proc.poll()

    def _write_file(self):
        tmp = self.flash_file + ".tmp"
        with open(tmp, "wb") as f:
            f.write(self.flash)
        os.replace(tmp, self.flash_file)

    # ------------------------------------------------------------ cuts
    def cut_at(self, k, mode="half"):
        """Lose power at the k-th flash step from now (1: the next one);
        mode "before" or "half". self.cut_states then holds the flash as the
        cut leaves it both ways: "before" (the step did not happen: a block
        boundary) and "half" (it was cut half way)."""
        assert mode in ("before", "half")
        self._cut = (self.steps + k, mode)
        self.cut_states = {}

    # ------------------------------------------------------------ link
    def _send(self, data):
        with self._wlock:
            if self._h2t is not None:
                os.write(self._h2t, data)

    def send(self, can_id, data, flags=0):
        """A frame on the bus: the node's clock advances by its bus time."""
        self.time_us += frame_bits(len(data)) * 1000000 // self.bitrate + 1
        raw = bytes(data) + b"\0" * (8 - len(data))
        self._send(frame(CAN_RX, struct.pack("<III", self.time_us & 0xFFFFFFFF, can_id,
                                             len(data) | (flags << 8)) + raw))

    def tick(self, ms):
        self.time_us += int(ms * 1000)
        self._send(frame(TICK, struct.pack("<I", self.time_us & 0xFFFFFFFF)))

    def recv(self, timeout):
        try:
            return self.rx.get(timeout=timeout)
        except queue.Empty:
            return None

    def hello(self, timeout=30.0):
        """The first HELLO of this power-on (role, version, reason, node)."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            try:
                return self.hellos.get(timeout=0.05)
            except queue.Empty:
                if not self.running():
                    return None
        return None

    def _read_loop(self):
        buf = bytearray()
        while not self._stop:
            try:
                chunk = os.read(self._t2h, 4096)
            except (OSError, TypeError):
                return
            if not chunk or self._stop:
                return
            buf += chunk
            while True:
                i = buf.find(bytes([SYNC]))
                if i < 0:
                    buf.clear()
                    break
                del buf[:i]
                if len(buf) < 4:
                    break
                n = struct.unpack_from("<H", buf, 2)[0]
                if len(buf) < 6 + n:
                    break
                body = bytes(buf[1:4 + n])
                ok = struct.unpack_from("<H", buf, 4 + n)[0] == crc16(body)
                t, payload = buf[1], bytes(buf[4:4 + n])
                if not ok:
                    del buf[:1]
                    continue
                del buf[:6 + n]
                if not self._handle(t, payload):
                    return

    def _handle(self, t, p):
        """One frame of the target; False when the power is cut."""
        if t == HELLO:
            self.hellos.put(struct.unpack("<4I", p[:16]))
        elif t == CAN_TX:
            cid, lf = struct.unpack_from("<II", p)
            self.rx.put((cid, p[8:8 + (lf & 0xFF)]))
        elif t in (ERASE, PROGRAM):
            return self._step(t, p)
        elif t == READ:
            s, off, n = struct.unpack("<3I", p)
            base, size = sector_geometry(s)
            rc = 0 if off + n <= size else -EINVAL
            data = self.flash[base + off:base + off + n] if rc == 0 else b""
            self._send(frame(FLASH_DATA, struct.pack("<i", rc) + bytes(data)))
        elif t == RESET:
            self.reset_requested = True
        return True

    def _step(self, t, p):
        self.steps += 1
        s = struct.unpack_from("<I", p)[0]
        off = 0 if t == ERASE else struct.unpack_from("<I", p, 4)[0]
        base, size = sector_geometry(s)
        words = b"" if t == ERASE else p[8:]
        n = size if t == ERASE else len(words)
        if s not in SLOT_SECTORS or off + n > size:
            self._send(frame(FLASH_DONE, struct.pack("<i", -EINVAL)))
            return True
        self.ops.append(("erase" if t == ERASE else "program", s, off, n))
        cut = self._cut is not None and self.steps == self._cut[0]
        mode = self._cut[1] if cut else None
        if cut:
            self.cut_states["before"] = bytes(self.flash)
        if t == ERASE:
            upto = size // 2 if mode == "half" else (0 if mode == "before" else size)
            self.flash[base:base + upto] = b"\xff" * upto
        else:
            nw = len(words) // 4
            upto = nw // 2 if mode == "half" else (0 if mode == "before" else nw)
            at = base + off
            for i in range(upto):
                for k in range(4):
                    self.flash[at + 4 * i + k] &= words[4 * i + k]
            if mode == "half" and upto < nw:  # the next word caught half way: its low half
                for k in range(2):
                    self.flash[at + 4 * upto + k] &= words[4 * upto + k]
        if cut:
            self._cut = None
            self.cut_done = (self.steps, mode)
            self.cut_states["half"] = bytes(self.flash)  # (= before when mode is "before")
            if self.proc is not None:
                os.killpg(self.proc.pid, signal.SIGKILL)
            return False
        self._send(frame(FLASH_DONE, struct.pack("<i", 0)))
        return True


def zlib_crc(data):
    import zlib
    return zlib.crc32(data) & 0xFFFFFFFF


def make_flash(boot_bin, app_bin=None, cfg_records=None, out=None):
    """A 1 MiB flash file: the bootloader, the application (sealed) at the
    slot, configuration records (bytes) at sector 10."""
    flash = bytearray(b"\xff" * FLASH_BYTES)
    with open(boot_bin, "rb") as f:
        boot = f.read()
    flash[:len(boot)] = boot
    if app_bin:
        with open(app_bin, "rb") as f:
            app = f.read()
        flash[0x4000:0x4000 + len(app)] = app
    if cfg_records:
        base, _ = sector_geometry(10)
        flash[base:base + len(cfg_records)] = cfg_records
    with open(out, "wb") as f:
        f.write(flash)
    return out


def cfg_record(params, seq=1, layout=1):
    """A configuration record (firmware/app/config/mc_cfg_store.h) holding
    {param id: raw u32}: what the drive writes at SAVE."""
    import zlib
    words = [0x4746434D, 1 | (layout << 16), seq, len(params) | 0xFFFF0000]
    for pid, raw in params.items():
        words += [pid, raw]
    body = struct.pack(f"<{len(words)}I", *words)
    return body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF)


# ---------------------------------------------------------------- buses
class EmuBus:
    """A python-can bus on an EmuNode: what mdtool's code sends goes to the
    node, what the node sends comes back. While the caller waits, the
    node's clock advances with the host's; a reset the node asks for
    reboots it (a fresh QEMU on the flash file)."""

    def __new__(cls, node, **kw):
        import can

        class _Bus(can.BusABC):
            def __init__(self, node, **kw):
                self.node = node
                self.channel_info = "emulated node"
                super().__init__(channel="emu", **kw)

            def send(self, msg, timeout=None):
                self.node.send(msg.arbitration_id, bytes(msg.data))

            def _recv_internal(self, timeout):
                t_end = None if timeout is None else time.monotonic() + timeout
                while True:
                    if self.node.cut_done is not None:
                        raise PowerCut(f"power cut at flash step {self.node.cut_done[0]}")
                    f = self.node.recv(0.005)
                    if f is not None:
                        return can.Message(arbitration_id=f[0], data=f[1], is_extended_id=False,
                                           timestamp=time.time()), False
                    if self.node.reset_requested and not self.node.running():
                        self.node.reboot()
                    self.node.tick(5)
                    if t_end is not None and time.monotonic() >= t_end:
                        return None, False

            def shutdown(self):
                super().shutdown()
        return _Bus(node, **kw)


def serve_socketcand(nodes, port_file, stop):
    """A socketcand server (rawmode, one client at a time) on the loopback
    address: one bus with every node of `nodes` on it (a frame of the client
    goes to each, each node's frames to the client). The port goes into
    port_file. Runs until stop (a threading.Event) is set."""
    srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    srv.settimeout(0.1)
    with open(port_file + ".tmp", "w") as f:
        f.write(str(srv.getsockname()[1]))
    os.replace(port_file + ".tmp", port_file)
    while not stop.is_set():
        try:
            c, _ = srv.accept()
        except TimeoutError:
            continue
        _serve_client(nodes, c, stop)
    srv.close()


def _client_lines(c, buf):
    """Whole '< ... >' commands received so far, and the rest."""
    try:
        d = c.recv(4096)
        if not d:
            return None, buf
        buf += d
    except TimeoutError:
        pass
    out = []
    while b">" in buf:
        line, _, buf = buf.partition(b">")
        out.append(line.decode("ascii", "replace").strip().lstrip("<").split())
    return out, buf


def _serve_client(nodes, c, stop):
    c.settimeout(0.005)
    c.sendall(b"< hi >")
    buf = b""
    t0 = time.time()
    while not stop.is_set():
        try:
            lines, buf = _client_lines(c, buf)
        except OSError:
            break
        if lines is None:
            break
        for words in lines:
            if words[:1] in (["open"], ["rawmode"]):
                c.sendall(b"< ok >")
            elif words[:1] == ["send"] and len(words) >= 3:
                data = bytes(int(x, 16) for x in words[3:3 + int(words[2], 16)])
                for n in nodes:
                    n.send(int(words[1], 16), data)
            else:
                c.sendall(b"< error unknown command >")
        for n in nodes:
            f = n.recv(0.0)
            while f is not None:
                c.sendall(f"< frame {f[0]:03X} {time.time() - t0:.6f} {f[1].hex().upper()} >".encode())
                f = n.recv(0.0)
            if n.reset_requested and not n.running():
                n.reboot()
            n.tick(5)
    c.close()


def clean(workdir):
    shutil.rmtree(workdir, ignore_errors=True)
    os.makedirs(workdir)
