#!/usr/bin/env python3
"""Where the fast interrupt's instructions go, function by function.

Runs the interrupt benchmark image (tools/bench/bench_isr.c, built with -g:
debug sections only, the code is the same) under qemu-system-arm
-M netduinoplus2 -icount shift=0 with QEMU's gdb stub on a unix socket, and
for each run (sensored, sensorless) single-steps one whole ADC interrupt:
the counted period PROFILE_PERIOD, which the image announces by calling
bench_profile_mark() just before it. Every instruction's address is
attributed to the function it belongs to in the source:

- the innermost frame from a .c file of its inline chain
  (arm-none-eabi-addr2line -f -i), so the drive's static helpers that the
  compiler inlined (check_sample, update_position, dead_comp, ...) keep
  their names, and the header one-liners (mc_sat_f32, mc_park_f32, ...)
  count in the function that uses them;
- and, inclusive, to every function on the call stack (from the entries
  and returns seen while stepping).

The image then runs to its end and prints its own counts; the stepped total
of each run must equal the image's TIM2 count of the same period (both are
QEMU's instruction count; the benchmark subtracts the call's overhead, the
stepped count starts at the handler's first instruction and ends with its
return, one instruction the benchmark's overhead takes off), or the tool
fails. The virtual clock runs with -icount shift=0,sleep=off, so the time
the emulation spends stopped at the stub does not reach TIM2.

usage: run_isr_profile.py --qemu QEMU --elf BOARD=ELF --nm NM --addr2line A2L [--out FILE]
Prints the JSON report (also to --out). Exit 2 on a usage error, 1 when the
profile disagrees with the image's count or the image fails.
"""
import argparse
import collections
import json
import os
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_isr_bench import parse  # same folder

MARK = "bench_profile_mark"
HANDLER = "ADC_IRQHandler"
RUNS = ("sensored", "sensorless")
STEP_LIMIT = 20000  # one interrupt is ~1500 instructions; more is a runaway


class Stub:
    """The few GDB remote-protocol packets the profile needs."""

    def __init__(self, path, timeout_s):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self.sock.connect(path)
                break
            except (FileNotFoundError, ConnectionRefusedError):
                if time.monotonic() > deadline:
                    raise SystemExit(f"QEMU's gdb stub did not open {path}") from None
                time.sleep(0.05)
        self.sock.settimeout(timeout_s)
        self.buf = b""
        self.ack = True
        if self.cmd("QStartNoAckMode") == "OK":
            self.ack = False

    def _read_packet(self):
        while True:
            start = self.buf.find(b"$")
            end = self.buf.find(b"#", start + 1) if start >= 0 else -1
            if start >= 0 and end >= 0 and len(self.buf) >= end + 3:
                data = self.buf[start + 1:end].decode("ascii")
                self.buf = self.buf[end + 3:]
                if self.ack:
                    self.sock.sendall(b"+")
                return data
            chunk = self.sock.recv(65536)
            if not chunk:
                raise SystemExit("QEMU closed the gdb connection")
            self.buf += chunk

    def cmd(self, data):
        csum = sum(data.encode("ascii")) % 256
        self.sock.sendall(f"${data}#{csum:02x}".encode("ascii"))
        return self._read_packet()

    def run_to_end(self):
        """Continue and let the image end: QEMU answers with its exit (W..)
        and closes the socket, possibly before our acknowledgement reaches
        it, so a closed connection here is the normal end, not an error."""
        data = "c"
        try:
            self.sock.sendall(f"${data}#{sum(data.encode('ascii')) % 256:02x}".encode("ascii"))
            while self.sock.recv(65536):
                pass
        except OSError:
            pass

    def reg(self, n):
        """Core register n (0..15) from a 'g' read (QEMU's ARM stub has no 'p')."""
        v = self.cmd("g")
        return int.from_bytes(bytes.fromhex(v[8 * n:8 * n + 8]), "little")


def symbols(nm, elf):
    """Function symbols: sorted [(start, end, name)]."""
    out = subprocess.run([nm, "-S", "--defined-only", elf], capture_output=True, text=True,
                         check=True).stdout
    funcs = []
    for line in out.splitlines():
        f = line.split()
        if len(f) == 4 and f[2] in "tTW":
            start = int(f[0], 16) & ~1
            funcs.append((start, start + int(f[1], 16), f[3]))
    return sorted(funcs)


def sym_at(funcs, pc):
    lo, hi = 0, len(funcs)
    while lo < hi:
        mid = (lo + hi) // 2
        if funcs[mid][0] <= pc:
            lo = mid + 1
        else:
            hi = mid
    if lo and funcs[lo - 1][0] <= pc < funcs[lo - 1][1]:
        return funcs[lo - 1]
    raise SystemExit(f"pc 0x{pc:08x} is in no function of the image")


def owners(a2l, elf, pcs):
    """pc -> (function, file) of the innermost frame from a .c file."""
    pcs = sorted(set(pcs))
    out = subprocess.run([a2l, "-e", elf, "-f", "-i", "-a"] + [hex(p) for p in pcs],
                         capture_output=True, text=True, check=True).stdout.splitlines()
    chains, cur, i = {}, None, 0
    while i < len(out):
        if out[i].startswith("0x"):
            cur = int(out[i], 16)
            chains[cur] = []
            i += 1
            continue
        loc = out[i + 1].rsplit(":", 1)[0]
        chains[cur].append((out[i], os.path.basename(loc)))
        i += 2
    res = {}
    for pc in pcs:
        chain = chains.get(pc, [])
        own = next(((fn, f) for fn, f in chain if f.endswith(".c")), None)
        res[pc] = own if own else (chain[0] if chain else ("?", "?"))
    return res


def step_interrupt(stub, funcs, handler):
    """Single-step from the handler's entry to its return: [pc, ...]."""
    ret = stub.reg(14) & ~1
    pcs = []
    pc = stub.reg(15)
    if pc != handler:
        raise SystemExit(f"stopped at 0x{pc:08x}, not at {HANDLER}")
    while pc != ret:
        pcs.append(pc)
        if len(pcs) > STEP_LIMIT:
            raise SystemExit(f"{HANDLER} did not return within {STEP_LIMIT} instructions")
        stub.cmd("s")
        pc = stub.reg(15)
    return pcs


def attribute(pcs, funcs, own):
    """Self counts per source function; inclusive counts per called function."""
    self_c = collections.Counter()
    incl = collections.Counter()
    stack = []
    for pc in pcs:
        start, _, name = sym_at(funcs, pc)
        if not stack or stack[-1] != name:
            if pc == start:
                stack.append(name)  # a call (or a tail call) enters it
            elif name in stack:
                while stack[-1] != name:
                    stack.pop()  # returned
            else:
                stack.append(name)
        for n in set(stack):
            incl[n] += 1
        fn, f = own[pc]
        self_c[(fn, f)] += 1
    return self_c, incl


def profile(qemu, elf, nm, a2l, timeout_s=300):
    funcs = symbols(nm, elf)
    by_name = {n: s for s, _, n in funcs}
    for need in (MARK, HANDLER):
        if need not in by_name:
            raise SystemExit(f"{elf} has no {need}: not an interrupt benchmark image")
    with tempfile.TemporaryDirectory() as tmp:
        sock = os.path.join(tmp, "gdb.sock")
        out_path = os.path.join(tmp, "bench.txt")
        cmd = [qemu, "-M", "netduinoplus2", "-nographic", "-monitor", "none", "-serial", "null",
               "-icount", "shift=0,sleep=off", "-S", "-gdb", f"unix:{sock},server=on,wait=on",
               "-chardev", "file,id=sh0,path=" + out_path,
               "-semihosting-config", "enable=on,target=native,chardev=sh0", "-kernel", elf]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            stub = Stub(sock, timeout_s)
            stepped = {}
            for run in RUNS:
                stub.cmd(f"Z0,{by_name[MARK]:x},2")
                stop = stub.cmd("c")
                if not stop.startswith("T"):
                    raise SystemExit(f"the image ended before the {run} run's mark: {stop}")
                stub.cmd(f"z0,{by_name[MARK]:x},2")
                stub.cmd(f"Z0,{by_name[HANDLER]:x},2")
                stub.cmd("c")
                stub.cmd(f"z0,{by_name[HANDLER]:x},2")
                stepped[run] = step_interrupt(stub, funcs, by_name[HANDLER])
            stub.run_to_end()  # the image's end (semihosting exit)
        finally:
            try:
                proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                raise SystemExit("the benchmark image did not end after the profile") from None
        with open(out_path, encoding="ascii") as f:
            text = f.read()
    if proc.returncode != 0:
        sys.stderr.write(text)
        raise SystemExit(f"bench image exited {proc.returncode}")
    board, rows, _meta = parse(text)
    own = owners(a2l, elf, [pc for pcs in stepped.values() for pc in pcs])
    report = {"board": board, "runs": {}}
    for run, pcs in stepped.items():
        prof = rows[(run, "isr_profiled_period")]
        if prof["n"] != 1:
            raise SystemExit(f"{board} {run}: the image counted {prof['n']} profiled periods")
        bench_n = prof["max"]
        # The image subtracts the cost of calling an empty function, whose
        # one instruction (bx lr) is the handler's return too: the stepped
        # count has that return, the image's count does not.
        if len(pcs) != bench_n + 1:
            raise SystemExit(f"{board} {run}: {len(pcs)} instructions stepped, the image counted "
                             f"{bench_n} for the same period")
        self_c, incl = attribute(pcs, funcs, own)
        report["runs"][run] = {
            "instructions": len(pcs),
            "image_count": bench_n,
            "self": [{"function": fn, "file": f, "instr": n}
                     for (fn, f), n in sorted(self_c.items(), key=lambda x: (-x[1], x[0]))],
            "inclusive": [{"function": fn, "instr": n}
                          for fn, n in sorted(incl.items(), key=lambda x: (-x[1], x[0]))],
        }
    return report


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--elf", action="append", required=True, help="BOARD=ELF (repeatable)")
    ap.add_argument("--nm", required=True)
    ap.add_argument("--addr2line", required=True)
    ap.add_argument("--out")
    a = ap.parse_args(argv)
    boards = []
    for spec in a.elf:
        board, sep, elf = spec.partition("=")
        if not sep or not os.path.isfile(elf):
            ap.error(f"--elf {spec}: expected BOARD=ELF, an existing file")
        rep = profile(a.qemu, elf, a.nm, a.addr2line)
        if rep["board"] != board:
            raise SystemExit(f"{elf} says it is {rep['board']}, not {board}")
        boards.append(rep)
    out = {"method": "QEMU netduinoplus2 -icount shift=0 with its gdb stub: one ADC interrupt "
                     "single-stepped per run (the counted period the image marks), each "
                     "instruction attributed to the innermost function of a .c file of its "
                     "inline chain (addr2line -i); the total equals the image's own count of "
                     "that period", "boards": boards}
    text = json.dumps(out, indent=1)
    if a.out:
        with open(a.out, "w", encoding="ascii") as f:
            f.write(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
