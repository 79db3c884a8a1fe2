#!/usr/bin/env python3
"""PNG figures of the thermal and DC-bus protection scenarios (issue 33).

    power_figs.py thermal ON.csv OFF.csv LIMIT_C PNG
        `mcsim run thermal-duty` with derating on and off (--set derate=0):
        the plant's winding and the drive's estimate against the limit, and
        the derated current limit beside the current asked.
    power_figs.py bus ON.csv OFF.csv PNG
        `mcsim run bus-limits` with the drive's limits on and off
        (--set limits=off): the plant's supply current and the drive's
        estimate against the limits in force, and the speed.

Each CSV is the scenario's own (header row, seconds in `t`); the numbers
the figures show are in the checked table `gen:power-limits`
(firmware/app/README.md).
"""
import sys

# the plots' shared CSV reader, PNG writer and pyplot on the Agg backend
from csmc_figs import plt, read, save


def panel(a, ylabel, loc):
    a.set_ylabel(ylabel)
    a.legend(loc=loc, fontsize=8)
    a.grid(alpha=0.3)


def thermal(on, off, limit_c, png):
    fig, ax = plt.subplots(2, 1, figsize=(10, 7.5), sharex=True)
    t_on = [x / 60.0 for x in on["t"]]
    t_off = [x / 60.0 for x in off["t"]]
    a = ax[0]
    a.plot(t_off, off["t_winding_c"], color="tab:red", lw=1.0, label="winding, derating off (plant)")
    a.plot(t_on, on["t_winding_c"], color="tab:blue", lw=1.4, label="winding, derating on (plant)")
    a.plot(t_on, on["t_winding_est_c"], color="k", lw=0.8, ls="--",
           label="drive's estimate, derating on")
    a.plot(t_on, on["t_housing_c"], color="tab:gray", lw=0.8, label="housing (plant)")
    a.axhline(limit_c, color="tab:red", ls=":", lw=1.0, label=f"limit {limit_c:g} °C")
    panel(a, "temperature [°C]", "lower right")
    a = ax[1]
    a.plot(t_on, on["i_limit_a"], color="tab:blue", lw=1.2, label="current limit in force (derated)")
    a.plot(t_on, [abs(x) for x in on["i_d_ref_a"]], color="tab:orange", lw=0.8,
           label="|i_d| asked (after the limit)")
    panel(a, "current [A]", "lower right")
    a.set_xlabel("time [min]")
    fig.suptitle("thermal-duty: overload cycle, winding model and derating")
    save(fig, png)


def bus(on, off, png):
    fig, ax = plt.subplots(2, 1, figsize=(10, 7.5), sharex=True)
    a = ax[0]
    a.plot(off["t"], off["i_bus_a"], color="tab:red", lw=0.8, label="supply current, limits off (plant)")
    a.plot(on["t"], on["i_bus_a"], color="tab:blue", lw=1.2, label="supply current, limits on (plant)")
    a.plot(on["t"], on["i_bus_est_a"], color="k", lw=0.6, ls="--", label="drive's estimate, limits on")
    a.plot(on["t"], on["i_bus_max_a"], color="tab:green", lw=1.0, ls=":", label="motoring limit")
    a.plot(on["t"], [-x for x in on["i_bus_regen_max_a"]], color="tab:purple", lw=1.0, ls=":",
           label="regenerating limit")
    panel(a, "DC-bus current [A] (+ drawn)", "upper right")
    a = ax[1]
    a.plot(off["t"], off["omega_m_rad_s"], color="tab:red", lw=0.8, label="speed, limits off")
    a.plot(on["t"], on["omega_m_rad_s"], color="tab:blue", lw=1.2, label="speed, limits on")
    a.plot(on["t"], on["omega_ref_rad_s"], color="k", lw=0.6, ls="--", label="speed command")
    panel(a, "speed [rad/s]", "upper right")
    a.set_xlabel("time [s]")
    fig.suptitle("bus-limits: acceleration and regenerative stop on a supply with internal resistance")
    save(fig, png)


def main(argv):
    if len(argv) == 5 and argv[0] == "thermal":
        thermal(read(argv[1]), read(argv[2]), float(argv[3]), argv[4])
    elif len(argv) == 4 and argv[0] == "bus":
        bus(read(argv[1]), read(argv[2]), argv[3])
    else:
        sys.stderr.write(__doc__)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
