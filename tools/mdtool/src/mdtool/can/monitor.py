"""`mdtool monitor`: a live plot of chosen telemetry signals (matplotlib).

Live: a FuncAnimation that drains the bus at every frame. Headless
(--no-gui, or no display): the Agg backend, the same update function called
--frames times (or for --duration), then the figure written to --png.
"""
import collections
import os
import sys
import time

from .errors import UsageError


def monitor(drive, signals, window_s=5.0, frames=None, png=None, no_gui=False, duration=None,
            interval_ms=50):
    import matplotlib
    headless = no_gui or not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if headless:
        matplotlib.use("Agg")
        if not png:
            raise UsageError("monitor without a display: give --png FILE (and --frames or --duration)")
        if frames is None and duration is None:
            raise UsageError("monitor --no-gui: give --frames N or --duration S")
    import matplotlib.pyplot as plt

    want = []
    for s in signals:
        msg_name, dot, sig = s.partition(".")
        try:
            msg = drive.db.get_message_by_name(msg_name.upper())
        except KeyError:
            raise UsageError(f"{s}: unknown message {msg_name!r}") from None
        if not dot or sig not in [x.name for x in msg.signals]:
            raise UsageError(f"{s}: {msg.name} has the signals {', '.join(x.name for x in msg.signals)}")
        want.append((msg.name, sig, next(x for x in msg.signals if x.name == sig)))
    data = {w[:2]: collections.deque() for w in want}
    counts = dict.fromkeys(data, 0)
    fig, axes = plt.subplots(len(want), 1, sharex=True, squeeze=False, figsize=(8, 2.2 * len(want) + 0.8))
    lines = []
    for ax, (m, sig, s) in zip(axes[:, 0], want):
        (ln,) = ax.plot([], [], lw=1, drawstyle="steps-post" if s.choices else "default")
        ax.set_ylabel(f"{sig}\n[{s.unit}]" if s.unit else sig)
        if s.choices:  # an enumerated signal: its value, with the DBC's names on the axis
            ax.set_yticks(sorted(int(k) for k in s.choices))
            ax.set_yticklabels([str(s.choices[k]) for k in sorted(s.choices)], fontsize=7)
        ax.set_title(m, fontsize=8, loc="left")
        ax.grid(True, alpha=0.3)
        lines.append(ln)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"node {drive.node}")
    enums = {(m, sig): (min(map(int, s.choices)), max(map(int, s.choices))) for m, sig, s in want if s.choices}
    t0 = time.monotonic()
    stats = {"frames": 0}

    def update(_i=None):
        while True:
            m = drive.bus.recv(0.0)
            if m is None:
                break
            d = drive.decode(m, names=False)  # numbers, enumerated signals too
            if d is None:
                continue
            name, vals = d
            now = time.monotonic() - t0
            for (mn, sig), q in data.items():
                if mn == name:
                    q.append((now, float(vals[sig])))
                    counts[(mn, sig)] += 1
                    stats["frames"] += 1
        now = time.monotonic() - t0
        for (key, q), ln, ax in zip(data.items(), lines, axes[:, 0]):
            while q and q[0][0] < now - window_s:
                q.popleft()
            if q:
                ln.set_data([p[0] for p in q], [p[1] for p in q])
                ax.relim()
                ax.autoscale_view()
            ax.set_xlim(max(0.0, now - window_s), max(window_s, now))
            if key in enums:  # the whole range of names stays on the axis
                ax.set_ylim(enums[key][0] - 0.5, enums[key][1] + 0.5)
        return lines

    if headless:
        n = 0
        while (frames is None or n < frames) and (duration is None or time.monotonic() - t0 < duration):
            time.sleep(interval_ms / 1000.0)
            update()
            n += 1
    else:
        from matplotlib.animation import FuncAnimation
        anim = FuncAnimation(fig, update, interval=interval_ms, frames=frames, repeat=False,
                             cache_frame_data=False)
        plt.show()
        del anim
    if png:
        fig.savefig(png, dpi=100)
        print(f"{png}: " + ", ".join(f"{m}.{s} {counts[(m, s)]} samples" for m, s, _ in want))
    for (m, s), n in counts.items():
        if n == 0:
            print(f"mdtool: monitor: no sample of {m}.{s} from node {drive.node}", file=sys.stderr)
    if stats["frames"] == 0:
        print(f"mdtool: monitor: no sample of the chosen signals from node {drive.node}")
        return 3
    return 0
