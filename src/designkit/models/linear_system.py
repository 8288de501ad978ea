"""A continuous-time linear system as a frozen value (state space with named signals)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class LinearSystem:
    """``x' = A x + B r``, ``y = C x + D r``.

    Parameters
    ----------
    A, B, C, D : numpy.ndarray
        State-space matrices (SI units of the named signals).
    states, inputs, outputs : tuple of str
        Signal names, e.g. states ``("x1", "x2", "x3")``, inputs ``("xD",)``, outputs ``("x1", "u")``.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]

    def __post_init__(self) -> None:
        for name in ("A", "B", "C", "D"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A`` (rad/s)."""
        return np.linalg.eigvals(self.A)

    def to_control(self):
        """The same system as a :class:`control.StateSpace` (imports python-control lazily)."""
        import control

        return control.ss(
            self.A, self.B, self.C, self.D, states=list(self.states), inputs=list(self.inputs),
            outputs=list(self.outputs),
        )
