"""Exception hierarchy of designkit; the CLI maps each class to an exit code.

Every mistake a user can make is a :class:`DesignkitError` (the CLI answers it with exit code 2
and one line ``designkit: error: <key path>: <message>``); anything else that escapes is a bug.

* :class:`DesignkitError`: the base class; catch it to handle every user mistake at once.
* :class:`SpecError`: a spec that does not validate (YAML syntax, types, values, size limits) or a
  wrong argument of the API (``load_spec(None)``, ``run(42)``); ``path`` is the YAML key path
  (``controller.poles[2]``) or the argument's name.
* :class:`ModelError`: a model that cannot be built, naming the model argument (the spec layer
  re-raises it as a :class:`SpecError` with the full key path, e.g. ``plant.dh[1].mass``).
* :class:`OutputError`: an output location that cannot be written (``write_report`` to an
  existing file, an unwritable folder); nothing is overwritten.
* :class:`NameNotFoundError`: a lookup by a name that does not exist (``gains["K9"]``,
  ``arm.functions["nope"]``); a :class:`SpecError` that is also a :class:`KeyError`, so code written
  for a mapping keeps working.

Every class has ``path`` (where, possibly empty) and ``message`` (what, one line) attributes.
Messages that quote a user value quote at most :data:`QUOTE_LIMIT` characters of it
(:func:`short_repr`).
"""

from __future__ import annotations

import math
import reprlib

QUOTE_LIMIT = 80
"""Longest quotation of a user value in an error message (characters, ellipsis included)."""

PATH_LIMIT = 320
"""Longest quotation of a file system path in an error message (the user's own argument, kept readable)."""

_REPR = reprlib.Repr()
_REPR.maxlevel = 3
_REPR.maxlist = _REPR.maxtuple = _REPR.maxset = _REPR.maxfrozenset = 8
_REPR.maxdict = 6
_REPR.maxstring = _REPR.maxother = QUOTE_LIMIT


def shorten(text: str, limit: int = QUOTE_LIMIT) -> str:
    """``text`` cut to ``limit`` characters, the last one an ellipsis when it was cut."""
    return text if len(text) <= limit else text[: limit - 1] + "…"


def short_repr(value: object, limit: int = QUOTE_LIMIT) -> str:
    """A ``repr`` of ``value`` of at most ``limit`` characters, never built in full.

    Long strings are cut before they are quoted, containers show their first items
    (:mod:`reprlib`), and an integer too long to print is described by its size.

    Examples
    --------
    >>> short_repr("x" * 1000, 12)
    "'xxxxxxxxxx…"
    >>> short_repr(10**5000)
    'an integer of 5001 digits'
    """
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int) and value.bit_length() > 256:
        return f"an integer of {math.floor(value.bit_length() * math.log10(2)) + 1} digits"
    if isinstance(value, str):
        return shorten(repr(value[:limit]), limit)
    return shorten(_REPR.repr(value), limit)


class DesignkitError(Exception):
    """Base class of every error designkit raises on purpose (exit code 2: bad input).

    Subclasses set :attr:`path` (the key path, argument or option at fault; may be empty) and
    :attr:`message` (what is wrong, one line).
    """

    exit_code: int = 2
    path: str = ""
    message: str = ""


class SpecError(DesignkitError):
    """Invalid user input: a spec file, a robot description or an argument.

    Parameters
    ----------
    path : str
        Key path of the offending field, e.g. ``"controller.poles[2]"``, or the name of the
        offending argument; empty for the whole input.
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
    def path(self) -> str:  # type: ignore[override]
        """Same as :attr:`field` (the key path relative to the model)."""
        return self.field


class OutputError(DesignkitError, OSError):
    """An output location that cannot be written; nothing was written or overwritten.

    Also an :class:`OSError`, so code that catches file system errors (``except OSError``) catches it.

    Parameters
    ----------
    path : str
        The argument or option naming the location (``"out_dir"``; the CLI says ``"--out"``).
    message : str
        What is wrong, naming the file system path, in one line.
    """

    def __init__(self, path: str, message: str) -> None:
        self.path = path
        self.message = message
        super().__init__(f"{path}: {message}" if path else message)


class NameNotFoundError(SpecError, KeyError):
    """A name looked up that does not exist; also a :class:`KeyError`.

    Parameters
    ----------
    path : str
        What was looked up (``"gains['K9']"``).
    message : str
        What exists instead, in one line.
    """

    def __str__(self) -> str:  # KeyError would quote the message
        return f"{self.path}: {self.message}" if self.path else self.message
