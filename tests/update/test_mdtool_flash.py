#!/usr/bin/env python3
"""`mdtool flash` (the command, as a separate process) against emulated
bootloaders over the boot link: two emulated STM32F405 nodes (emu_node.py,
ids 5 and 6 from their configuration records) on one bus served to mdtool
by a socketcand server (python-can's own `socketcand` client):

- both nodes run version 1; `mdtool flash V2 -n 5 -n 6` updates them in
  turn: exit 0, progress, "verified", each node then boots version 2 (its
  HELLO after a fresh start) with its configuration sectors unchanged;
- the drive's own PIL image (mc_stm32f405_pil.bin, linked for the slot and
  sealed by the build) flashed the same way (without the wait for its
  answer: the PIL image talks to its host over USART1, not this link) is
  started by the bootloader: its USART1 HELLO arrives;
- errors, each with its exit code and nothing written: a node that does
  not answer (3), an image for another board (2), a corrupt file (2), a
  file that is no image (2), a bad node id (2).

    test_mdtool_flash.py --qemu Q --boot BOOT.bin --v1 APP1.bin --v2 APP2.bin
                         --pil PIL.bin --work DIR
"""
import argparse
import json
import os
import socket
import subprocess
import sys
from pathlib import Path
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SRC = os.path.join(ROOT, "tools", "mdtool", "src")
sys.path.insert(0, HERE)
sys.path.insert(0, SRC)

import emu_node as E  # noqa: E402
from mdtool.can import dbc, flash, image  # noqa: E402

fails = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)
    return ok


def mdtool(port, *args):
    env = dict(os.environ, PYTHONPATH=SRC,
               CAN_CONFIG=json.dumps({"host": "127.0.0.1", "port": port}))
    return subprocess.run([sys.executable, "-m", "mdtool.cli", *args, "--interface", "socketcand",
                           "--channel", "can0"], capture_output=True, text=True, env=env, timeout=300)


def pil_hello_on_usart(node_dir, flash_file, qemu, timeout=20.0):
    """Boot the flash file with USART1 on a socket: the drive's PIL image
    sends its HELLO frame (firmware/targets/pil/mc_pil_frame.h) first."""
    path = os.path.join(node_dir, "usart1.sock")
    if os.path.exists(path):
        os.unlink(path)
    srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    srv.bind(path)
    srv.listen(1)
    srv.settimeout(timeout)
    q = subprocess.Popen([qemu, "-M", "netduinoplus2", "-display", "none", "-monitor", "none",
                          "-serial", "unix:" + path, "-semihosting-config", "enable=on,target=native",
                          "-device", f"loader,file={flash_file},addr=0x08000000,force-raw=on"],
                         cwd=node_dir, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        c, _ = srv.accept()
        c.settimeout(timeout)
        got = b""
        while len(got) < 5:
            d = c.recv(5 - len(got))
            if not d:
                break
            got += d
        return got
    except OSError:
        return b""
    finally:
        q.kill()
        q.wait()
        srv.close()


def main():
    ap = argparse.ArgumentParser()
    for k in ("qemu", "boot", "v1", "v2", "pil", "work"):
        ap.add_argument("--" + k, required=True)
    a = ap.parse_args()
    E.clean(a.work)
    nodes = []
    for nid in (5, 6):
        d = os.path.join(a.work, f"node{nid}")
        os.makedirs(d)
        f = E.make_flash(a.boot, a.v1, E.cfg_record({110: nid}), out=os.path.join(d, "flash.bin"))
        n = E.EmuNode(a.qemu, f, d)
        n.power_on()
        check(n.hello() is not None, f"node {nid} starts version 1")
        nodes.append(n)
    cfg_before = [bytes(n.flash[0xC0000:]) for n in nodes]
    stop = threading.Event()
    port_file = os.path.join(a.work, "port")
    th = threading.Thread(target=E.serve_socketcand, args=(nodes, port_file, stop), daemon=True)
    th.start()
    while not os.path.exists(port_file):
        time.sleep(0.01)
    port = int(Path(port_file).read_text())
    try:
        # ---- the update of two nodes in turn
        t0 = time.monotonic()
        # long timeouts: the nodes are lock-step, QEMU may stall on a loaded machine
        r = mdtool(port, "flash", a.v2, "-n", "5", "-n", "6", "--timeout", "20", "--wait", "60")
        print(r.stdout + r.stderr)
        check(r.returncode == 0, f"mdtool flash -n 5 -n 6: exit {r.returncode}")
        for nid in (5, 6):
            check(f"node {nid}: verified" in r.stdout and f"node {nid}: updated to 2.0.0" in r.stdout,
                  f"node {nid}: progress, verification and the new version printed")
        check(" 50 %" in r.stdout and "100 %" in r.stdout, "progress in percent")
        print(f"[mdtool-flash] two nodes updated in {time.monotonic() - t0:.1f} s")
        stop.set()
        th.join(timeout=10)
        for n, cfg in zip(nodes, cfg_before, strict=True):
            n.close()
            check(bytes(n.flash[0xC0000:]) == cfg, "the configuration sectors did not change")
            n.power_on()
            h = n.hello()
            check(h is not None and h[0] == E.ROLE_APP and h[1] == 0x020000,
                  f"after a fresh start the node runs version 2 ({h})")
        # ---- errors: nothing written, the documented exit codes
        stop = threading.Event()
        os.unlink(port_file)
        th = threading.Thread(target=E.serve_socketcand, args=(nodes, port_file, stop), daemon=True)
        th.start()
        while not os.path.exists(port_file):
            time.sleep(0.01)
        port = int(Path(port_file).read_text())
        steps = [n.steps for n in nodes]
        r = mdtool(port, "flash", a.v1, "-n", "7", "--timeout", "0.5")
        check(r.returncode == 3 and "no BOOT_REPLY to INFO from node 7" in r.stderr,
              f"an absent node: exit {r.returncode}, {r.stderr.strip()}")
        other = bytearray(Path(a.v2).read_bytes())
        other[image.HDR_OFFSET + 8] = 2  # the ODrive v3.6
        other_path = os.path.join(a.work, "odrive.bin")
        Path(other_path).write_bytes(image.seal(bytes(other)))
        r = mdtool(port, "flash", other_path, "-n", "5")
        check(r.returncode == 2 and "is for odrive36" in r.stderr and "nothing sent" in r.stderr,
              f"another board's image: exit {r.returncode}, {r.stderr.strip()}")
        bad = bytearray(Path(a.v1).read_bytes())
        bad[9000] ^= 0x01
        bad_path = os.path.join(a.work, "bad.bin")
        Path(bad_path).write_bytes(bad)
        r = mdtool(port, "flash", bad_path, "-n", "5")
        check(r.returncode == 2 and "CRC-32" in r.stderr, f"a corrupt file: exit {r.returncode}")
        r = mdtool(port, "flash", os.path.join(ROOT, "README.md"), "-n", "5")
        check(r.returncode == 2 and "not an application image" in r.stderr,
              f"not an image: exit {r.returncode}, {r.stderr.strip()}")
        r = mdtool(port, "flash", a.v1, "-n", "63")
        check(r.returncode == 2, f"node 63: exit {r.returncode}")
        check([n.steps for n in nodes] == steps, "a refused flash erased or wrote something")
        # ---- the drive's own image into node 5 (in process, the same flasher)
        stop.set()
        th.join(timeout=10)
        data, hdr = flash.read_image(a.pil)
        fl = flash.Flasher(nodes[0].bus(), dbc.load_db(None), 5, timeout=20.0, progress=None)
        fl.check_target(hdr)
        fl.enter(wait=30.0)
        fl.update(data, hdr)
        check(nodes[0].wait_reset(10.0), "node 5 did not reset within 10 s of COMMIT")
        nodes[0].power_off()
        got = pil_hello_on_usart(nodes[0].workdir, nodes[0].flash_file, a.qemu)
        check(got[:3] == bytes([0xA5, 6, 0]), f"the drive's PIL image starts (USART1 HELLO {got.hex()})")
    finally:
        stop.set()
        for n in nodes:
            n.close()
    print(f"mdtool flash: {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
