#!/usr/bin/env python3
"""The firmware update on the emulated STM32F405 (QEMU netduinoplus2): the
emulated bootloader (tests/target: mc_stm32f405_boot_pil) and the update
tests' application (app/boot_test_app.c, versions 1 and 2, 17 852 bytes:
two slot sectors), the flash in a file between boots, CAN over the boot
link (emu_node.py), mdtool's own flasher (mdtool.can.flash) as the host.

  power-cut   An update from version 1 to 2 is cut at every erase and every
              program step the bootloader asks for (one block each, and the
              commit word): QEMU is killed in the middle of the step. Both
              states a cut can leave are rebooted: the step not done (a
              block boundary) and the step half done (an erase that erased
              half its sector, a block of which half the words and half of
              the next one were written). Each boot must start version 1
              exactly as it was, version 2 exactly, or stay in the
              bootloader with a named reason and answer INFO on the stored
              node id; never anything else (a hang, a fault, a mixture). The
              update is then completed from there, and the flash file must
              end identical to an uninterrupted update's, whose boot starts
              version 2. The configuration sectors never change.
  refusals    An image for another board and a corrupt image are refused
              before anything is erased (the file checked by mdtool, then
              the bootloader itself); the node keeps running version 1.
  enter       The application enters its bootloader only with ENTER, the
              confirmation and the token it gave; a node that has no valid
              image (erased slot) announces itself and can be flashed.

    test_update_pil.py --qemu Q --boot BOOT.bin --v1 APP1.bin --v2 APP2.bin --work DIR TEST
"""
import argparse
import json
import os
import sys
from pathlib import Path
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "tools", "mdtool", "src"))

import emu_node as E  # noqa: E402
from mdtool.can import dbc, flash, image  # noqa: E402
from mdtool.can.errors import NoReply, Refused, UsageError  # noqa: E402

NODE = 5
REASONS = {2: "EMPTY", 3: "MAGIC", 4: "HDR_VERSION", 5: "BOARD", 6: "LAYOUT", 7: "SIZE", 8: "CRC",
           9: "UNCOMMITTED", 10: "VECTORS", 11: "FLASH"}
fails = []


def check(ok, what):
    if not ok:
        print("FAIL " + what)
        fails.append(what)
    return ok


class Rig:
    def __init__(self, a):
        self.a = a
        self.db = dbc.load_db(None)
        self.v1, self.h1 = flash.read_image(a.v1)
        self.v2, self.h2 = flash.read_image(a.v2)
        self.cfg = E.cfg_record({110: NODE, 111: 500000})
        self.work = a.work
        E.clean(self.work)
        self.file = os.path.join(self.work, "flash.bin")

    def initial(self):
        return Path(E.make_flash(self.a.boot, self.a.v1, self.cfg, out=self.file)).read_bytes()

    def node(self, contents):
        with open(self.file, "wb") as f:
            f.write(contents)
        return E.EmuNode(self.a.qemu, self.file, os.path.join(self.work, "q"))

    def flasher(self, node, quiet=True):
        # An answer comes within milliseconds on an idle machine; the run is
        # lock-step (the node's clock is the host's), so a long timeout only
        # costs time when something hangs, and a machine shared by many jobs
        # may stall QEMU for seconds
        return flash.Flasher(node.bus(), self.db, NODE, timeout=20.0,
                             progress=None if quiet else print)


def slot(contents, n):
    return contents[0x4000:0x4000 + n]


def cfg_sectors(contents):
    return contents[0xC0000:]


def classify(rig, contents):
    """Boot the flash `contents`: ('old'|'new'|'boot', detail). A node that
    starts an image must hold exactly that image."""
    node = rig.node(contents)
    node.power_on()
    h = node.hello(timeout=30.0)
    try:
        if h is None:
            return ("none", f"no HELLO (QEMU exit status {node.exit_status()})"), node
        role, version, extra, node_id = h
        if role == E.ROLE_APP:
            which = {rig.h1["app_version"]: "old", rig.h2["app_version"]: "new"}.get(version)
            img = rig.v1 if which == "old" else rig.v2
            if which is None or slot(contents, len(img)) != img:
                return ("mixed", f"application version {version:#x} over a slot that is not it"), node
            return (which, node_id), node
        if extra not in REASONS:
            return ("unnamed", f"bootloader reason {extra}"), node
        # reachable: INFO on the stored node id
        r = rig.flasher(node).ask("INFO")
        if str(r["boot_state"]) != "IDLE" or str(r["boot_reason"]) != REASONS[extra] or node_id != NODE:
            return ("unreachable", f"INFO {r}"), node
        return ("boot", REASONS[extra]), node
    except (NoReply, Refused) as e:
        return ("unreachable", str(e)), node


def complete(rig, node):
    """Finish the update from whatever the node runs; True when committed."""
    fl = rig.flasher(node)
    fl.check_target(rig.h2)
    r = fl.ask("INFO")
    if str(r["boot_state"]) == "APP":
        fl.enter(wait=30.0)
    fl.update(rig.v2, rig.h2)
    return node.wait_reset(30.0)  # the bootloader's reset after COMMIT


def test_power_cut(rig):
    t0 = time.monotonic()
    # the reference: an uninterrupted update, then its boot
    node = rig.node(rig.initial())
    node.power_on()
    node.hello()
    rig.flasher(node).flash(rig.v2, rig.h2, wait=30.0)
    steps = node.steps
    node.close()
    final = Path(rig.file).read_bytes()
    kinds = [op[0] for op in node.ops]
    print(f"[power-cut] an update takes {steps} flash steps: {kinds.count('erase')} erases, "
          f"{kinds.count('program')} programs (the blocks and the commit word)")
    check(cfg_sectors(final) == cfg_sectors(rig.initial()), "the update changed the configuration")
    check(slot(final, len(rig.v2)) == rig.v2, "the updated slot is not version 2")

    seen = {}
    outcome = {"old": 0, "new": 0, "boot": 0}
    reasons = {}
    for k in range(1, steps + 1):
        node = rig.node(rig.initial())
        node.power_on()
        node.hello()
        node.cut_at(k, "half")
        try:
            rig.flasher(node).flash(rig.v2, rig.h2, wait=30.0)
            check(False, f"step {k}: the update went through a cut")
        except E.PowerCut:
            pass  # the node died mid-update
        check(node.cut_done == (k, "half"), f"step {k}: the cut did not happen there ({node.cut_done})")
        states = dict(node.cut_states)
        node.close()
        for mode, contents in states.items():
            key = hash(contents)
            (res, detail), node = classify(rig, contents)
            what = f"step {k}, cut {mode}"
            if os.environ.get("MC_UPDATE_VERBOSE"):
                print(f"{time.monotonic() - t0:7.2f} {what}: {res} {detail}", flush=True)
            ok = check(res in outcome, f"{what}: {res}: {detail}")
            if ok:
                outcome[res] += 1
                if res == "boot":
                    reasons[detail] = reasons.get(detail, 0) + 1
                check(cfg_sectors(contents) == cfg_sectors(rig.initial()),
                      f"{what}: the configuration changed")
                try:
                    done = complete(rig, node)
                except (NoReply, Refused) as e:
                    done = check(False, f"{what}: completing the update: {e}")
                node.close()
                after = Path(rig.file).read_bytes()
                if not done:
                    check(False, f"{what}: the bootloader did not reset within 30 s of the completed update")
                else:
                    differs = [i for i in range(min(len(after), len(final))) if after[i] != final[i]]
                    check(after == final, f"{what}: the flash after the completed update differs from the "
                          f"reference at {len(differs)} bytes (first at 0x{differs[0] if differs else 0:x}; "
                          f"sizes {len(after)}, {len(final)})")
            else:
                node.close()
            seen[key] = res
            if len(fails) > 5:
                return
    dt = time.monotonic() - t0
    summary = {"steps": steps, "cuts": 2 * steps, "distinct_states": len(seen), **outcome,
               "reasons": reasons, "seconds": round(dt, 1)}
    print("[power-cut] " + json.dumps(summary))
    check(outcome["old"] >= 1, "no cut left the old image (the cut before the first erase)")
    check(outcome["old"] + outcome["new"] + outcome["boot"] == 2 * steps, "a state was not classified")


def test_refusals(rig):
    node = rig.node(rig.initial())
    node.power_on()
    node.hello()
    fl = rig.flasher(node)
    # another board's image (a valid one: the board id re-sealed): mdtool refuses
    other = bytearray(rig.v2)
    other[image.HDR_OFFSET + 8] = 3  # VESC 6
    other = image.seal(bytes(other))
    try:
        fl.flash(other, image.check(other))
        check(False, "an image for another board was flashed")
    except UsageError as e:
        check("is for vesc6" in str(e), f"refusal names the boards: {e}")
    check(node.steps == 0, "a refused image erased or wrote something")
    # the bootloader refuses it too, before erasing: BEGIN with the other board
    fl.enter(wait=30.0)
    try:
        fl.ask("BEGIN", 3 | (1 << 8) | (1 << 16), len(other))
        check(False, "BEGIN for another board accepted")
    except Refused as e:
        check(e.status == "BOARD", f"BEGIN refused {e.status}, not BOARD")
    check(node.steps == 0, "the bootloader erased for another board's image")
    # a corrupt file: mdtool refuses to read it
    bad = bytearray(rig.v2)
    bad[5000] ^= 0xFF
    bad_path = os.path.join(rig.work, "bad.bin")
    with open(bad_path, "wb") as f:
        f.write(bad)
    try:
        flash.read_image(bad_path)
        check(False, "a corrupt file was accepted")
    except UsageError as e:
        check("CRC-32" in str(e), f"corrupt file refusal names the CRC: {e}")
    # the same bytes sent anyway (a host that does not check): VERIFY refuses
    # them, COMMIT is refused, the node stays in its bootloader and says why
    hdr = image.header(bytes(bad))
    try:
        fl.update(bytes(bad), hdr)
        check(False, "a corrupt image was committed")
    except Refused as e:
        check(e.status == "IMAGE_CRC", f"corrupt image refused {e.status}, not IMAGE_CRC")
    node.close()
    (res, detail), node = classify(rig, Path(rig.file).read_bytes())
    check(res == "boot" and detail == "CRC", f"after a corrupt update the node boots {res} {detail}")
    node.close()
    print("[refusals] another board's image and a corrupt image refused, nothing started")


def test_enter(rig):
    node = rig.node(rig.initial())
    node.power_on()
    node.hello()
    fl = rig.flasher(node)
    r = fl.ask("INFO")
    check(str(r["boot_state"]) == "APP", "version 1 does not answer as the application")
    check(fl.ask("VERSION")["value"] == rig.h1["app_version"], "VERSION is not the image's")
    # ENTER with a wrong key, a wrong token: still the application
    for args, st in (((0,), "KEY"),):
        try:
            fl.ask("ENTER", value=args[0], ok=("CONFIRM",))
        except Refused as e:
            check(e.status == st, f"ENTER with a wrong key: {e.status}")
    tok = fl.ask("ENTER", value=flash.ENTER_KEY, ok=("CONFIRM",))["value"]
    try:
        fl.ask("ENTER_CONFIRM", value=tok ^ 1)
    except Refused as e:
        check(e.status == "KEY", f"a wrong token: {e.status}")
    node.tick(50)
    check(str(fl.ask("INFO")["boot_state"]) == "APP", "a wrong token entered the bootloader")
    r = fl.enter(wait=30.0)
    check(str(r["boot_reason"]) == "REQUESTED", f"the bootloader says {r['boot_reason']}")
    # a block sent twice (a host that gave up waiting): both copies are
    # answered, the second not written; the stale answer does not fail the
    # next block
    fl.ask("BEGIN", rig.h2["board_id"] | (1 << 8) | (1 << 16), len(rig.v2),
           timeout=flash.erase_timeout(len(rig.v2)))
    for _ in range(2):
        fl.request("WRITE", 0, E.zlib_crc(rig.v2[:256]))
        for f in flash.data_frames(rig.v2[:256]):
            fl._send(flash.CMD_DATA, f)
    check(fl.block_reply(0)["value"] == 1, "block 0 taken")
    steps = node.steps
    try:
        fl.write_block(rig.v2, 1)
    except (NoReply, Refused) as e:
        check(False, f"block 1 after a block sent twice: {e}")
    check(node.steps == steps + 1, f"{node.steps - steps} programs for block 1 (block 0 twice: once)")
    fl.ask("ABORT")
    node.close()
    # an erased slot: the bootloader announces EMPTY; flash version 2 into it
    blank = bytearray(rig.initial())
    blank[0x4000:0xC0000] = b"\xff" * (0xC0000 - 0x4000)
    node = rig.node(bytes(blank))
    node.power_on()
    h = node.hello()
    check(h is not None and h[0] == E.ROLE_BOOT and REASONS.get(h[2]) == "EMPTY",
          f"an erased slot boots {h}")
    bus = node.bus()
    ann = None
    t_end = time.monotonic() + 5
    while ann is None and time.monotonic() < t_end:
        m = bus.recv(0.1)
        if m is not None and m.arbitration_id == (NODE << 5 | 0x0F) and m.data[0] == 0:
            ann = m
    check(ann is not None and ann.data[3] == 2, f"no ANNOUNCE with reason EMPTY ({ann})")
    rig.flasher(node).flash(rig.v2, rig.h2, wait=30.0)
    node.close()
    print("[enter] ENTER needs its key and token; an erased node announces itself and is flashed")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--boot", required=True)
    ap.add_argument("--v1", required=True)
    ap.add_argument("--v2", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("test", choices=["power-cut", "refusals", "enter"])
    a = ap.parse_args()
    rig = Rig(a)
    t0 = time.monotonic()
    {"power-cut": test_power_cut, "refusals": test_refusals, "enter": test_enter}[a.test](rig)
    print(f"{a.test}: {time.monotonic() - t0:.1f} s, {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
