#!/usr/bin/env python3
"""Instruction counts of the drive image's interrupts, per board, and the
CPU budget built from them.

Runs the interrupt benchmark image of each board (bench_isr.c: the image's
own ADC_IRQHandler, CAN1_RX0_IRQHandler and PendSV_Handler on RAM stand-ins
of the peripherals) under qemu-system-arm -M netduinoplus2 -icount shift=0
and writes a JSON report:

- per board and run (sensored, sensorless): the whole fast interrupt (mean,
  max over RUN_PERIODS periods, and over the periods that pend the slow
  loop), its parts (ADC read, encoder read, speed law, FOC, duties write,
  application mark; the rest is the drive's supervision and glue), the CAN
  receive interrupt per frame, the slow loop (normal and with a full ring of
  16 command frames, each answered, over every telemetry phase);
- the CPU load of the fast interrupt at 20 and 40 kHz PWM;
- the budget: fast interrupt at 40 kHz + CAN receive interrupt at a 100 %
  flood of this node's shortest frames at 1 Mbit/s + the slow loop at 1 kHz,
  with the response time of each (fixed priorities: fast > CAN rx > slow).

QEMU counts instructions, not cycles. Cycles are estimated as
instructions x CPI with CPI_ASSUMED (see CYCLE_NOTE), plus the exception
entry and exit per interrupt (EXC_CYCLES).

usage: run_isr_bench.py --qemu QEMU --elf BOARD=ELF [--elf ...] [--out FILE]
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_bench import run_image  # same folder

SYSCLK_HZ = 168e6
PWM_HZ = (20e3, 40e3)
SLOW_HZ = 1e3  # the slow loop's rate (1 kHz at 20 kHz / 20; the divider follows the PWM rate)
CAN_BPS = 1e6
# Shortest classic frame: SOF 1 + id 11 + RTR 1 + IDE 1 + r0 1 + DLC 4 + CRC 15 +
# delimiter 1 + ACK 2 + EOF 7 = 44 bits, no data, no stuff bits, + 3 bits of
# intermission: the highest frame rate a bus can carry (ISO 11898-1).
CAN_MIN_FRAME_BITS = 47
CAN_FIFO_DEPTH = 3  # bxCAN receive FIFO 0 (RM0090 32.7.5)
TARGET_SENSORED = 450
TARGET_SENSORLESS = 600
CPI_ASSUMED = 1.25
# Exception entry (12 cycles, 29 with the FP context stacked lazily on first
# FP use) and return (10, 27 with FP): Cortex-M4 TRM / ARM AN298.
EXC_CYCLES = 29 + 27
CYCLE_NOTE = (
    "QEMU counts executed instructions, not cycles. On the STM32F405 most integer and "
    "FPU instructions take 1 cycle; loads and stores 2 (1 when pipelined), taken branches "
    "2-4, integer divides 2-12, VDIV/VSQRT 14. Code runs from flash with 5 wait states "
    "at 168 MHz; the ART accelerator (128-bit prefetch, 64-line instruction cache, "
    "8-line data cache) hides them on sequential code and cache hits, and a miss costs up "
    "to 5 cycles. Data in SRAM or CCM has no wait state. Cycles here = instructions x "
    f"{CPI_ASSUMED} + {EXC_CYCLES} per interrupt (entry and return with the FP context).")


def parse(text):
    board = None
    rows = {}
    meta = {}
    for raw in text.splitlines():
        line = raw.strip()
        if not line.startswith("{"):
            continue
        obj = json.loads(line)
        board = obj.get("board", board)
        if "part" in obj:
            n = obj["n"]
            rows[(obj["run"], obj["part"])] = {
                "n": n, "min": obj["min"], "max": obj["max"],
                "mean": round(obj["sum"] / n, 1) if n else None}
        else:
            for k, v in obj.items():
                if k != "board":
                    meta[k] = v
    if "error" in meta:
        raise SystemExit(f"bench_isr ({board}) failed: {meta}")
    return board, rows, meta


def load_pct(instr, rate_hz, cpi=1.0, exc=0):
    return 100.0 * (instr * cpi + exc) * rate_hz / SYSCLK_HZ


def response_time(c_own, higher):
    """Worst-case response time [cycles] of a task of c_own cycles under the
    higher-priority tasks [(cycles, period_cycles)] (fixed-priority
    preemptive, iterated to the fixed point); None when they saturate."""
    if sum(c / t for c, t in higher) >= 1.0:
        return None
    r = c_own
    for _ in range(1000):
        nxt = c_own + sum(math.ceil(r / t) * c for c, t in higher)
        if nxt == r:
            return r
        r = nxt
    return None


def board_report(board, rows, meta):
    runs = {}
    for run, target in (("sensored", TARGET_SENSORED), ("sensorless", TARGET_SENSORLESS)):
        isr = rows[(run, "isr")]
        parts = {p: rows[(run, p)] for p in
                 ("adc_read", "encoder_read", "law", "foc", "duties_write", "app_mark")}
        rest = isr["mean"] - sum(p["mean"] for p in parts.values())
        runs[run] = {
            "isr": isr, "isr_slow_due": rows[(run, "isr_slow_due")],
            "parts": parts, "drive_rest_mean": round(rest, 1),
            # boards with a brake chopper: its duty write, not in the runs'
            # interrupt (their tables leave brake_enable 0)
            "brake_write": rows.get((run, "brake_write")),
            # the sensored run: the anticogging feed-forward alone from the
            # bins and from the series (and the series' derivation, once),
            # the whole interrupt with the series on ("isr": off)
            "cog_lookup": rows.get((run, "cog_lookup")),
            "cog_series": rows.get((run, "cog_series")),
            "cog_series_init": rows.get((run, "cog_series_init")),
            "isr_anticogging": rows.get((run, "isr_anticogging")),
            "slow": rows[(run, "slow")], "slow_full_ring": rows[(run, "slow_full_ring")],
            "can_rx": rows[(run, "can_rx")], "can_rx_heartbeat": rows[(run, "can_rx_heartbeat")],
            "target_instr": target, "met": isr["max"] <= target,
            "load_pct": {f"{int(f / 1e3)}khz": {
                "cpi1_mean": round(load_pct(isr["mean"], f), 2),
                "cpi1_max": round(load_pct(isr["max"], f), 2),
                "est_max": round(load_pct(isr["max"], f, CPI_ASSUMED, EXC_CYCLES), 2)}
                for f in PWM_HZ},
        }
    return {"board": board, "filter": {k: meta.get(k) for k in
                                       ("filter_banks_active", "filter_pass_ids",
                                        "filter_pass_own_ids")},
            "overhead_instr": meta.get("overhead_instr"), "runs": runs}


def budget(rep):
    """CPU budget at 40 kHz with a CAN flood, per run: loads and response
    times in cycles (instructions x CPI_ASSUMED + EXC_CYCLES)."""
    frame_hz = CAN_BPS / CAN_MIN_FRAME_BITS
    out = {}
    for run, r in rep["runs"].items():
        pwm = PWM_HZ[1]
        c_fast = r["isr"]["max"] * CPI_ASSUMED + EXC_CYCLES
        c_rx = r["can_rx"]["max"] * CPI_ASSUMED + EXC_CYCLES
        c_slow = r["slow_full_ring"]["max"] * CPI_ASSUMED + EXC_CYCLES
        t_fast = SYSCLK_HZ / pwm
        t_rx = SYSCLK_HZ / frame_hz
        t_slow = SYSCLK_HZ / SLOW_HZ
        u = {"fast": c_fast / t_fast, "can_rx": c_rx / t_rx, "slow": c_slow / t_slow}
        r_fast = c_fast
        r_rx = response_time(c_rx, [(c_fast, t_fast)])
        r_slow = response_time(c_slow, [(c_fast, t_fast), (c_rx, t_rx)])
        out[run] = {
            "pwm_hz": pwm, "can_frame_hz": round(frame_hz, 1), "slow_hz": SLOW_HZ,
            "load_pct": {k: round(100 * v, 2) for k, v in u.items()},
            "total_pct": round(100 * sum(u.values()), 2),
            "response_us": {
                "fast": round(r_fast / SYSCLK_HZ * 1e6, 2),
                "can_rx": None if r_rx is None else round(r_rx / SYSCLK_HZ * 1e6, 2),
                "slow": None if r_slow is None else round(r_slow / SYSCLK_HZ * 1e6, 1)},
            "deadline_us": {
                "fast": round(t_fast / SYSCLK_HZ * 1e6, 2),
                # the FIFO holds 3: the interrupt must run before the third
                # frame after the one that raised it has arrived
                "can_rx": round((CAN_FIFO_DEPTH - 1) * t_rx / SYSCLK_HZ * 1e6, 2),
                "slow": round(t_slow / SYSCLK_HZ * 1e6, 1)},
        }
        resp, dl = out[run]["response_us"], out[run]["deadline_us"]
        out[run]["deadlines_met"] = all(resp[k] is not None and resp[k] <= dl[k] for k in dl)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--elf", action="append", required=True, help="BOARD=ELF")
    ap.add_argument("--out")
    a = ap.parse_args()
    boards = []
    for spec in a.elf:
        name, elf = spec.split("=", 1)
        board, rows, meta = parse(run_image(a.qemu, elf))
        if board != name:
            raise SystemExit(f"{elf}: image says board {board}, expected {name}")
        rep = board_report(board, rows, meta)
        flt = rep["filter"]
        if not (flt["filter_pass_ids"] == flt["filter_pass_own_ids"] == 32):
            raise SystemExit(f"{board}: the node filter passes {flt}, not exactly this node's "
                             "32 ids")
        rep["budget"] = budget(rep)
        boards.append(rep)
    report = {
        "method": "QEMU netduinoplus2 -icount shift=0; TIM2 PSC=0 counts one tick per "
                  "instruction; the image's handlers called between two reads, minus the "
                  "cost of calling an empty function",
        "sysclk_hz": SYSCLK_HZ, "cpi_assumed": CPI_ASSUMED, "exc_cycles": EXC_CYCLES,
        "cycle_note": CYCLE_NOTE, "can_bps": CAN_BPS, "can_min_frame_bits": CAN_MIN_FRAME_BITS,
        "boards": boards,
    }
    js = json.dumps(report, indent=2)
    if a.out:
        with open(a.out, "w", encoding="ascii") as f:
            f.write(js + "\n")
    print(js)
    bad = [(b["board"], run) for b in boards for run, x in b["budget"].items()
           if not x["deadlines_met"]]
    if bad:
        print(f"deadline missed in the budget: {bad}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
