"""Parquet files of campaigns (parts, results, report copies), read and
written by Arrow from and to the path itself.

Not pandas' read_parquet/to_parquet: for a local path they open a Python
file object and hand it to pyarrow, so every buffer Arrow reads is a Python
object (arrow::py::PyBuffer). pyarrow's dataset scanner releases some of
them on its own I/O threads after the call has returned; when that happens
while the interpreter shuts down (a command that exits right after reading,
most often when both cores are busy), PyGILState_Ensure ends that thread
with pthread_exit, whose unwinding through a noexcept destructor calls
std::terminate: "terminate called without an active exception", exit 134
(apache/arrow#34314). Read from its path, a file's buffers are Arrow's own
and no Arrow thread ever needs the interpreter
(tests/sil/campaign/test_exit_codes.py: `mdtool report` 50 times with both
cores busy, and no Python file object ever reaches pyarrow).
"""
from __future__ import annotations

import os


def read_parquet(path: str, columns: list[str] | None = None):
    """The file as a pandas DataFrame (pyarrow.ArrowInvalid or OSError for
    a damaged or missing file)."""
    import pyarrow.parquet as pq

    return pq.read_table(path, columns=columns).to_pandas()


def write_parquet(df, path: str) -> None:
    """Write df (without its index) to a temporary file beside `path`, then
    rename it over `path`: a reader never sees half a file."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    tmp = os.path.join(os.path.dirname(path) or ".", "." + os.path.basename(path) + ".tmp")
    pq.write_table(pa.Table.from_pandas(df, preserve_index=False), tmp)
    os.replace(tmp, path)
