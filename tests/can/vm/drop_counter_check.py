#!/usr/bin/env python3
"""The recorder's kernel drop counter counts real drops (run on a kernel with
vcan, inside the CAN test's VM): a recorder socket with the smallest receive
queue the kernel allows is not read while another socket sends N frames on
the same interface; then it is drained. Asserts, exactly (nothing here is
timing-dependent: the queue is full long before the sender ends):
  frames read + SO_RXQ_OVFL count == N, the count > 0, and the frames read
  are the first ones sent, in order (the kernel drops at the tail).
    drop_counter_check.py IFACE REPO
"""
import os
import socket
import struct
import sys

iface, root = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(root, "tools", "can"))
import mc_can  # noqa: E402

N = 2000
rec = mc_can.SocketcanRecorder(iface, rcvbuf=1)  # the kernel rounds up to its minimum
tx = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
tx.bind((iface,))
for k in range(N):
    tx.send(struct.pack("<IB3x8s", 0x123, 8, k.to_bytes(8, "little")))
tx.close()
lines = []
while True:
    batch = rec.read_batch(iface, 0.2)
    if not batch:
        break
    lines += batch
rec.close()
got = [int.from_bytes(bytes.fromhex(ln.split("#")[1]), "little") for ln in lines]
fails = []
if len(got) + rec.dropped != N:
    fails.append(f"read {len(got)} + dropped {rec.dropped} != sent {N}")
if rec.dropped == 0:
    fails.append(f"no drop counted with a {rec.rcvbuf} B queue and {N} frames unread")
if got != list(range(len(got))):
    fails.append("the frames read are not the first ones sent, in order")
print(f"[drop_counter] sent {N}, read {len(got)}, kernel dropped {rec.dropped} "
      f"(queue {rec.rcvbuf} B)")
for f in fails:
    print("FAIL:", f)
sys.exit(1 if fails else 0)
