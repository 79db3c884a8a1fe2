"""Recording: the raw SocketCAN recorder with the kernel's drop counter,
and python-can's generic Bus for every other interface; the output format
follows the file's extension (log.FrameWriter). Sequence gaps of the
telemetry are counted as frames arrive (log.SeqCounter).
"""
import contextlib
import json
import logging
import signal
import time

from .errors import UsageError
from .log import FrameWriter, SeqCounter, frame_of_message

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
        # error frames too, as candump -L shows them when asked
        with contextlib.suppress(AttributeError, OSError):
            self.sock.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_ERR_FILTER, 0x1FFFFFFF)
        try:
            self.sock.bind((iface,))
        except OSError as e:
            self.sock.close()
            raise UsageError(f"record: cannot open SocketCAN interface {iface!r}: {e.strerror}") from e
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

    def read_batch(self, iface, timeout_s, max_frames=4096, frames=None):
        """Up to max_frames candump -L lines; waits at most timeout_s for the first.
        If `frames` is a list, (t_s, iface, can_id, data, flags) of each line
        is appended to it too."""
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
            if frames is not None:
                fl = set()
                if can_id & CAN_ERR_FLAG:
                    fl.add("err")
                elif can_id & CAN_EFF_FLAG:
                    fl.add("ext")
                if len(cf) == 72:
                    fl.add("fd")
                elif can_id & CAN_RTR_FLAG:
                    fl.add("rtr")
                frames.append((float(stamp), iface, can_id & (0x1FFFFFFF if fl & {"ext", "err"} else 0x7FF),
                               bytes(payload), fl))
        return out




def _interrupt_flag():
    stop = {"now": False}

    def on_signal(_sig, _frm):
        stop["now"] = True
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    return stop


def record(out, db, node, interface="socketcan", channel="can0", bitrate=None, duration=0.0,
           ready=None, report=None, bus=None, stop=None, log=print, bus_opts=None):
    """Record until `duration` seconds passed (0: until SIGINT/SIGTERM or
    stop["now"]) into `out` (format by extension). On SocketCAN the socket
    is read directly (kernel drops from SO_RXQ_OVFL); on any other
    python-can interface (or a given `bus`) through python-can, where the
    kernel's counter does not exist (reported as None). Returns the report:
    frames, kernel_dropped, seq_gaps, seq_lost, receive buffer."""
    writer = FrameWriter(out, channel=channel)  # refuses an unknown extension before opening the bus
    seq = SeqCounter(db, node)
    if stop is None:
        stop = _interrupt_flag()
    t_end = time.monotonic() + duration if duration else None
    rec = None
    own_bus = False
    try:
        if bus is None and interface == "socketcan":
            rec = SocketcanRecorder(channel)
        elif bus is None:
            bus = open_bus(interface, channel, bitrate, **(bus_opts or {}))
            own_bus = True
        if ready:
            open(ready, "w").close()
        t_flush = time.monotonic() + RECORD_FLUSH_S
        while True:
            now = time.monotonic()
            ending = stop["now"] or (t_end is not None and now >= t_end)
            got = 0
            if rec is not None:
                # once told to stop, drain what the socket already holds, then stop
                frames = []
                lines = rec.read_batch(channel, 0.0 if ending else 0.1, frames=frames)
                if lines:
                    writer.write_lines(lines, frames)
                    for fr in frames:
                        seq.add(fr[2], fr[3], fr[4])
                    got = len(lines)
            else:
                m = bus.recv(0.0 if ending else 0.1)
                if m is not None:
                    fr = frame_of_message(m)
                    if fr[1] in ("None", ""):
                        fr = (fr[0], channel) + fr[2:]
                    writer.write(fr)
                    seq.add(fr[2], fr[3], fr[4])
                    got = 1
            if not got and ending:
                break
            if now >= t_flush:
                writer.flush()
                t_flush = now + RECORD_FLUSH_S
    finally:
        writer.close()
        if rec is not None:
            rec.close()
        if own_bus:
            bus.shutdown()
    rep = {"log": out, "frames": writer.count, "interface": interface, "channel": channel,
           "kernel_dropped": rec.dropped if rec is not None else None,
           "seq_gaps": seq.gaps, "seq_lost": seq.lost}
    if rec is not None:
        rep.update(rcvbuf_bytes=rec.rcvbuf, rcvbuf_forced=rec.forced)
        log(f"{out}: {writer.count} frames; kernel dropped {rec.dropped} (SO_RXQ_OVFL); "
            f"receive buffer {rec.rcvbuf} B{'' if rec.forced else ' (not forced: capped by rmem_max)'}; "
            f"sequence gaps {seq.gaps} ({seq.lost} frames lost)")
    else:
        log(f"{out}: {writer.count} frames; kernel drops not available on {interface}; "
            f"sequence gaps {seq.gaps} ({seq.lost} frames lost)")
    if report:
        with open(report, "w") as rf:
            json.dump(rep, rf, indent=1)
    return rep


def _socketcand_reachable(args):
    """python-can's socketcand client retries a refused connection for 10 s
    (logging each try): find out first, in one try, whether a server answers
    at host:port (from the arguments or python-can's configuration)."""
    import socket

    import can
    cfg = can.util.load_config(config=dict(args))
    host, port = cfg.get("host"), cfg.get("port")
    if host is None or port is None:
        raise UsageError("socketcand: give the server's --host and --port (or $MDTOOL_HOST, $MDTOOL_PORT, "
                         "or host and port in python-can's configuration: CAN_CONFIG, ~/.canrc)")
    try:
        port = int(port)
        with socket.create_connection((host, port), timeout=SOCKETCAND_CONNECT_S):
            pass
    except (OSError, ValueError) as e:
        raise UsageError(f"socketcand: no server at {host}:{port} ({e}); is the drive running? "
                         "(mcsim with MCSIM_CAN_IF=socketcand:HOST:PORT)") from e
    args.update(host=host, port=port)


SOCKETCAND_CONNECT_S = 3.0


def open_bus(interface, channel, bitrate=None, **kw):
    """A python-can bus, with a clear error when it cannot be opened."""
    import can
    args = dict(interface=interface, channel=channel, **kw)
    if bitrate:
        args["bitrate"] = int(bitrate)
    try:
        if interface == "socketcand":
            _socketcand_reachable(args)
            # python-can's client logs a WARNING each time a TCP read ends in
            # the middle of a frame, which is normal on a stream: keep errors only
            logging.getLogger("can.interfaces.socketcand").setLevel(logging.ERROR)
        return can.Bus(**args)
    except (can.CanError, OSError, ValueError, ImportError, TypeError) as e:
        raise UsageError(f"cannot open CAN interface {interface!r} channel {channel!r}: {e}") from e
