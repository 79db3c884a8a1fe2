"""Errors of the CAN tools, with the exit code the CLI returns for each."""


class CanToolError(Exception):
    """Base class; exit code 1."""

    exit_code = 1


class UsageError(CanToolError):
    """Bad arguments or input files (exit code 2)."""

    exit_code = 2


class NoReply(CanToolError):
    """The drive did not answer within the timeout (exit code 3)."""

    exit_code = 3


class Refused(CanToolError):
    """The drive refused a request; `status` is the reason's name (exit code 4)."""

    exit_code = 4

    def __init__(self, message, status=None, value=None):
        super().__init__(message)
        self.status = status
        self.value = value


class Interrupted(BaseException):
    """SIGINT (Ctrl-C) or SIGTERM while a command ran; exit code 128 +
    the signal's number (130, 143), as a shell reports a process the signal
    ended. A BaseException, as KeyboardInterrupt: no `except Exception`
    on the way swallows it, and every `finally` (DISABLE) still runs."""

    def __init__(self, signum):
        import signal
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum
        self.exit_code = 128 + signum
