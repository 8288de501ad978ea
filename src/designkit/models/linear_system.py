"""A continuous-time linear system as a frozen value (state space with named signals)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

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

    def to_control(self, name: str | None = None):
        """The same system as a :class:`control.StateSpace` (imports python-control lazily).

        Parameters
        ----------
        name : str, optional
            System name in python-control (default: python-control's generated name).

        Returns
        -------
        control.StateSpace
            ``A, B, C, D`` unchanged (so poles in 1/s, gains in the units of the named signals), with
            ``states``, ``inputs`` and ``outputs`` as its state, input and output labels.
        """
        import control

        kwargs = {} if name is None else {"name": name}
        return control.ss(
            self.A, self.B, self.C, self.D, states=list(self.states), inputs=list(self.inputs),
            outputs=list(self.outputs), **kwargs,
        )

    @classmethod
    def from_control(cls, sys: Any) -> LinearSystem:
        """A :class:`LinearSystem` from a continuous-time python-control system.

        Parameters
        ----------
        sys : control.StateSpace or control.TransferFunction
            A transfer function is first realised with ``control.ss`` (its states are then
            python-control's generated names).  Signal labels become ``states``, ``inputs`` and
            ``outputs``.

        Returns
        -------
        LinearSystem
            The same matrices: ``LinearSystem.from_control(ls.to_control())`` equals ``ls``
            matrix for matrix and name for name.

        Raises
        ------
        ValueError
            For a discrete-time system (``dt`` neither 0 nor None).
        """
        import control

        if not isinstance(sys, control.StateSpace):
            sys = control.ss(sys)
        if sys.dt not in (0, None):
            raise ValueError(f"expected a continuous-time system, got dt = {sys.dt}")
        return cls(A=np.asarray(sys.A, float), B=np.asarray(sys.B, float), C=np.asarray(sys.C, float),
                   D=np.asarray(sys.D, float), states=tuple(sys.state_labels), inputs=tuple(sys.input_labels),
                   outputs=tuple(sys.output_labels))

    def transfer_coefficients(self, output: int | str = 0, input: int | str = 0) -> tuple[np.ndarray, np.ndarray]:
        """Numerator and denominator of one channel, ``y_output(s) / r_input(s)``.

        Computed with the matrix determinant lemma rather than a generic state-space to transfer
        function conversion: for ``G(s) = c (sI - A)^-1 b + d``,

            ``G(s) = (det(sI - A + b c) - det(sI - A)) / det(sI - A) + d``,

        so both polynomials are characteristic polynomials, formed from eigenvalues.  Rounding is
        cleaned in two places: an eigenvalue of magnitude below ``1e-9 ||M||_2`` is taken as 0
        (an integrator stays an exact root at the origin), and a numerator coefficient below
        ``1e-9`` times the sum of the magnitudes of the terms it was computed from is set to 0
        (exact cancellation, e.g. a relative degree above one).  Common factors are *not*
        cancelled: the denominator has degree ``n`` (the number of states); use
        ``control.minreal`` to cancel them.

        Parameters
        ----------
        output, input : int or str
            Index or name of the output and of the input.

        Returns
        -------
        num, den : numpy.ndarray
            Coefficients, highest power of ``s`` first (``s`` in 1/s); ``den`` is monic.

        Examples
        --------
        >>> ls = LinearSystem(A=[[0.0, 1.0], [-2.0, -3.0]], B=[[0.0], [1.0]], C=[[1.0, 0.0]], D=[[0.0]],
        ...                   states=("p", "v"), inputs=("f",), outputs=("p",))
        >>> num, den = ls.transfer_coefficients("p", "f")
        >>> np.round(num, 12).tolist(), np.round(den, 12).tolist()
        ([1.0], [1.0, 3.0, 2.0])
        """
        i = output if isinstance(output, int) else self.outputs.index(output)
        j = input if isinstance(input, int) else self.inputs.index(input)
        b = self.B[:, [j]]
        c = self.C[[i], :]
        d = float(self.D[i, j])
        if self.A.shape[0] == 0:
            return np.array([d]), np.array([1.0])
        den, den_terms = _charpoly(self.A)
        other, other_terms = _charpoly(self.A - b @ c)
        num = other - den + d * den
        num[0] = d  # the leading coefficients (both 1) cancel exactly
        terms = other_terms + (1.0 + abs(d)) * den_terms
        num = np.where(np.abs(num) <= 1e-9 * terms, 0.0, num)
        nz = np.flatnonzero(num)
        return (num[nz[0]:] if nz.size else np.array([0.0])), den

    def to_transfer(self, name: str | None = None):
        """The system as a :class:`control.TransferFunction` (one entry per output/input pair).

        Each entry comes from :meth:`transfer_coefficients` (no pole-zero cancellation; apply
        ``control.minreal`` to cancel).

        Parameters
        ----------
        name : str, optional
            System name in python-control.

        Returns
        -------
        control.TransferFunction
            With ``inputs`` and ``outputs`` as its input and output labels.
        """
        import control

        p, m = len(self.outputs), len(self.inputs)
        nums = [[None] * m for _ in range(p)]
        dens = [[None] * m for _ in range(p)]
        for i in range(p):
            for j in range(m):
                nums[i][j], dens[i][j] = (c.tolist() for c in self.transfer_coefficients(i, j))
        kwargs = {} if name is None else {"name": name}
        if p == 1 and m == 1:
            return control.tf(nums[0][0], dens[0][0], inputs=list(self.inputs), outputs=list(self.outputs), **kwargs)
        return control.tf(nums, dens, inputs=list(self.inputs), outputs=list(self.outputs), **kwargs)


def _charpoly(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``det(sI - M)`` (monic, highest power first) and, per coefficient, the sum of the magnitudes
    of its terms (the scale of its rounding error); eigenvalues below ``1e-9 ||M||_2`` are taken as 0."""
    lam = np.linalg.eigvals(M)
    lam = np.where(np.abs(lam) <= 1e-9 * np.linalg.norm(M, 2), 0.0, lam)
    return np.real(np.poly(lam)), np.real(np.poly(-np.abs(lam)))
