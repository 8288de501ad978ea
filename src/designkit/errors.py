"""Exception hierarchy of designkit; the CLI maps each class to an exit code."""

from __future__ import annotations


class DesignkitError(Exception):
    """Base class of every error designkit raises on purpose."""

    exit_code: int = 2


class SpecError(DesignkitError):
    """Invalid user input: a spec file, a robot description or an argument.

    Parameters
    ----------
    path : str
        Key path of the offending field, e.g. ``"controller.poles[2]"``; empty for the whole input.
    message : str
        What is wrong, in one line.
    """

    exit_code = 2

    def __init__(self, path: str, message: str) -> None:
        self.path = path
        self.message = message
        super().__init__(f"{path}: {message}" if path else message)


class InfeasibleError(DesignkitError):
    """A design problem that has no solution (e.g. requirements no pole set can meet)."""

    exit_code = 1


class ModelError(DesignkitError):
    """A robot model that cannot be built (unsupported URDF, inconsistent parameters)."""

    exit_code = 2
