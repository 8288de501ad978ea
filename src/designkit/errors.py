"""Exception hierarchy of designkit; the CLI maps each class to an exit code.

Every mistake a user can make is a :class:`DesignkitError`: a spec that does not validate
(:class:`SpecError`, which names the YAML key path) or a model that cannot be built
(:class:`ModelError`, which names the model argument; the spec layer re-raises it as a
:class:`SpecError` with the full key path, e.g. ``plant.dh[1].mass``).  Anything else that
escapes is a bug.
"""

from __future__ import annotations


class DesignkitError(Exception):
    """Base class of every error designkit raises on purpose (exit code 2: bad input)."""

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

    def __init__(self, path: str, message: str) -> None:
        self.path = path
        self.message = message
        super().__init__(f"{path}: {message}" if path else message)


class ModelError(DesignkitError):
    """A model that cannot be built: an invalid robot description, plant parameter or argument.

    Parameters
    ----------
    field : str
        The model argument or description field at fault, relative to the model
        (``"Km"``, ``"links[1].mass"``, ``"q_low"``); a spec's key path is prefixed to it by
        the spec layer.  When ``message`` is omitted, ``field`` is the message and the error
        concerns the model as a whole.
    message : str, optional
        What is wrong, in one line.
    """

    def __init__(self, field: str, message: str | None = None) -> None:
        if message is None:
            field, message = "", field
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}" if field else message)

    @property
    def path(self) -> str:
        """Same as :attr:`field` (the key path relative to the model)."""
        return self.field
