"""mdtool: the motor-drive host tool.

Subcommand families, one module each: sil (the scenario runner in-process),
campaign (sweeps on Dask), report (envelope figures and tables), cli (the
`mdtool` command).
"""

__version__ = "0.1.0"
