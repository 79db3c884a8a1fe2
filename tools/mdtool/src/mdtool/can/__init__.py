"""CAN tools of mdtool: the DBC (tools/can/motordrive.dbc) is the single
source of every message and signal.

    dbc      load the DBC, frame ids (node << 5 | cmd), own signal codec, bus load
    log      candump -L text logs, any python-can log format, decode to CSV, stats
    record   recorders: raw SocketCAN (kernel drop counter) and python-can buses
    client   the drive over any python-can bus: scan, status, parameters, run
    params   the parameter table (params_meta.json) and the motor/board TOML files
    cli      the `mdtool` CAN subcommands

Nothing here imports the SIL extension (mdtool._sil); tools/can/mc_can.py
uses these modules straight from the source tree.
"""
from .errors import CanToolError, NoReply, Refused, UsageError  # noqa: F401
