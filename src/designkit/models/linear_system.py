"""A continuous-time linear system as a frozen value (state space with named signals)."""

from __future__ import annotations

import math
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

    def dc_gain(self) -> np.ndarray:
        """``G(0) = D - C A^-1 B`` (outputs per input, in their units), NumPy only.

        Raises
        ------
        numpy.linalg.LinAlgError
            When ``A`` is singular (a pole at the origin: the DC gain is infinite).
        """
        return self.D - self.C @ np.linalg.solve(self.A, self.B)

    def margins(self, output: int | str = 0, input: int | str = 0) -> tuple[float, float, float, float, float, float]:
        """Stability margins of the channel ``output/input`` taken as a loop transfer ``L(s)``.

        :func:`siso_margins` on :meth:`transfer_coefficients`: the values of python-control's
        ``stability_margins`` without importing python-control or SciPy.

        Returns
        -------
        gm, pm, sm, wpc, wgc, wms : float
            Gain margin (ratio), phase margin (deg), stability margin (dimensionless) and their
            frequencies (rad/s); see :func:`siso_margins`.
        """
        return siso_margins(*self.transfer_coefficients(output, input))

    def forced_response(self, time: Any, inputs: Any, x0: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Response to inputs sampled at ``time``, interpolated linearly between samples (first-order hold).

        Exact for piecewise-linear inputs: with ``h`` the (uniform) step, the matrix exponential of
        ``[[A h, B h, 0], [0, 0, I], [0, 0, 0]]`` gives ``Phi``, ``Gamma1``, ``Gamma2`` and
        ``x[k+1] = Phi x[k] + (Gamma1 - Gamma2) u[k] + Gamma2 u[k+1]`` -- the discretisation that
        python-control's ``forced_response`` uses for a uniform time grid.  SciPy's ``expm`` is
        imported lazily (SciPy's linear algebra only, not ``scipy.signal``).

        Parameters
        ----------
        time : array_like, shape (N,)
            Increasing, evenly spaced instants (s).
        inputs : array_like, shape (m, N) (or (N,) for one input)
            The inputs at those instants, in the units of the named inputs.
        x0 : array_like, shape (n,), optional
            Initial state (default zero).

        Returns
        -------
        outputs : numpy.ndarray, shape (p, N)
        states : numpy.ndarray, shape (n, N)

        Raises
        ------
        ValueError
            When the instants are not evenly spaced (relative spread of the steps above 1e-9) or the
            input shape does not match.
        """
        from scipy.linalg import expm

        t = np.asarray(time, dtype=float)
        n, m = self.B.shape
        u = np.asarray(inputs, dtype=float).reshape(m, t.size)
        x = np.zeros((n, t.size))
        x[:, 0] = 0.0 if x0 is None else np.asarray(x0, dtype=float)
        if t.size > 1:
            steps = np.diff(t)
            h = float(steps.mean())
            if not (h > 0 and np.max(np.abs(steps - h)) <= 1e-9 * h):
                raise ValueError("forced_response needs increasing, evenly spaced instants")
            M = np.zeros((n + 2 * m, n + 2 * m))
            M[:n, :n] = self.A * h
            M[:n, n:n + m] = self.B * h
            M[n:n + m, n + m:] = np.eye(m)
            E = expm(M)
            Phi, G1, G2 = E[:n, :n], E[:n, n:n + m], E[:n, n + m:]
            for k in range(t.size - 1):
                x[:, k + 1] = Phi @ x[:, k] + (G1 - G2) @ u[:, k] + G2 @ u[:, k + 1]
        return self.C @ x + self.D @ u, x

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


def _iw(coefficients: np.ndarray) -> np.ndarray:
    """Coefficients of ``p(jw)`` as a polynomial in ``w`` (highest power first)."""
    c = np.asarray(coefficients, dtype=complex)
    return (1j) ** np.arange(len(c) - 1, -1, -1) * c


def _abs2(p_iw: np.ndarray) -> np.ndarray:
    return np.real(np.polymul(p_iw, p_iw.conj()))


def _positive_real_roots(poly: np.ndarray, strict: bool) -> np.ndarray:
    poly = np.trim_zeros(np.asarray(poly, dtype=float), "f")
    if poly.size <= 1:
        return np.array([])
    w = np.roots(poly)
    w = np.real(w[np.isreal(w)])
    return w[w > 0] if strict else w[w >= 0]


def siso_margins(num: Any, den: Any) -> tuple[float, float, float, float, float, float]:
    """Gain, phase and stability margins of a continuous-time SISO loop ``L = num/den`` (NumPy only).

    The same computation as python-control's ``stability_margins`` on a continuous-time transfer
    function (its ``"poly"`` method, which ``"best"`` uses there), without importing python-control
    or SciPy: with ``N(jw)`` and ``D(jw)`` as polynomials in ``w``, the phase crossovers are the real
    roots ``w >= 0`` of ``Im N Re D - Re N Im D`` where ``L(jw) <= 0``, the gain crossovers the real
    roots ``w > 0`` of ``|N|^2 - |D|^2``, and the stability-margin frequencies the local minima of
    ``|1 + L(jw)|``.  The reported gain margin is the one closest to 1 in ratio (smallest
    ``|log GM|``), the phase margin the smallest in magnitude.

    Parameters
    ----------
    num, den : array_like
        Coefficients of ``L(s)``, highest power of ``s`` first (``s`` in 1/s).

    Returns
    -------
    gm, pm, sm, wpc, wgc, wms : float
        Gain margin (ratio, ``inf`` without phase crossover), phase margin (deg, ``inf`` without
        gain crossover), stability margin ``min |1 + L(jw)|`` at the local minima (``inf`` when
        there is none), and their frequencies (rad/s, ``nan`` when absent).
    """
    num_iw, den_iw = _iw(num), _iw(den)

    def value(w: np.ndarray) -> np.ndarray:
        s = 1j * np.asarray(w, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.polyval(np.asarray(num, dtype=float), s) / np.polyval(np.asarray(den, dtype=float), s)

    test_180 = np.polysub(np.polymul(num_iw.imag, den_iw.real), np.polymul(num_iw.real, den_iw.imag))
    w180 = np.sort(_positive_real_roots(test_180, strict=False))
    r180 = value(w180)
    keep = np.real(r180) <= 0.0
    w180, r180 = w180[keep], np.real(r180[keep])
    wc = np.sort(_positive_real_roots(np.polysub(_abs2(num_iw), _abs2(den_iw)), strict=True))
    rc = value(wc)
    stab_n, stab_d = _abs2(np.polyadd(num_iw, den_iw)), _abs2(den_iw)
    test_stab = np.polysub(np.polymul(np.polyder(stab_n), stab_d), np.polymul(np.polyder(stab_d), stab_n))
    ws = _positive_real_roots(test_stab, strict=True)
    ws = np.sort(ws[np.polyval(np.polyder(test_stab), ws) > 0.0]) if ws.size else ws
    sm_all = np.abs(value(ws) + 1.0)
    with np.errstate(divide="ignore"):
        gm_all = 1.0 / np.abs(r180)
    pm_all = np.remainder(np.angle(rc, deg=True), 360.0) - 180.0
    if gm_all.size and not np.isinf(gm_all).all():
        with np.errstate(divide="ignore"):
            k = int(np.argmin(np.abs(np.log(gm_all))))
        gm, wpc = float(gm_all[k]), float(w180[k])
    else:
        gm, wpc = math.inf, math.nan
    if pm_all.size:
        k = int(np.argmin(np.abs(pm_all)))
        pm, wgc = float(pm_all[k]), float(wc[k])
    else:
        pm, wgc = math.inf, math.nan
    if sm_all.size:
        k = int(np.argmin(sm_all))
        sm, wms = float(sm_all[k]), float(ws[k])
    else:
        sm, wms = math.inf, math.nan
    return gm, pm, sm, wpc, wgc, wms
