"""Run several mdtool commands in one Python process:

    python mdtool_batch.py STEPS

STEPS holds one command a line, `NAME ARGS...` (shell quoting): each runs as
`mdtool ARGS...` through mdtool.cli.main, the same entry point as the
command line, with its output in NAME.out and its exit code in NAME.rc (in
the current folder). Inside the emulated VM a Python start with python-can
and cantools imported costs tens of seconds on a busy machine; paying it
once keeps the test about the drive and the tool, not the emulator's speed.
"""
import contextlib
import shlex
import sys
import traceback

from mdtool import cli


def main(path):
    with open(path, encoding="utf-8") as f:
        steps = [shlex.split(line) for line in f if line.strip()]
    for name, *argv in steps:
        with open(name + ".out", "w", encoding="utf-8") as out, \
                contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            try:
                rc = cli.main(argv)
            except SystemExit as e:  # argparse
                rc = e.code if isinstance(e.code, int) else 1
            except Exception:  # a crash is a result too: keep going, show it
                traceback.print_exc()
                rc = 1
        with open(name + ".rc", "w", encoding="utf-8") as f:
            f.write(f"{rc}\n")
        print(f"[mdtool_batch] {name}: exit {rc}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
