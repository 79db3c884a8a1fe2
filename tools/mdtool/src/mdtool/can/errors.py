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
