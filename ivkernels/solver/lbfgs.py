"""Limited-memory BFGS on backend vectors.

The unknowns of a window (all ``A_t`` and ``S_t`` stacked, millions of
values) stay in one flat backend array; every vector operation of the method
(two-loop recursion, line search) runs through the backend's ``vecops``
kernels, so no full-size NumPy temporaries sit on the hot path.

Reference: Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 7.4
(two-loop recursion) and Alg. 3.1 (backtracking with the Armijo condition).
"""
from __future__ import annotations

from collections import deque
from typing import Callable


class LBFGS:
    """Minimiser of a smooth function of a flat float32 backend vector.

    Parameters
    ----------
    be : backend (:func:`ivkernels.backends.get_backend`).
    n : number of unknowns.
    memory : number of correction pairs ``(s_k, y_k)`` kept.
    first_step : largest change (in the unknowns' units) of the very first
        step along ``-g``; later steps start from the quasi-Newton step 1.

    All buffers are allocated once here and reused across calls.
    """

    def __init__(self, be, n: int, memory: int = 6, first_step: float = 0.1):
        self.be = be
        self.n = n
        self.memory = memory
        self.first_step = first_step
        self._free = [(be.empty((n,)), be.empty((n,))) for _ in range(memory)]
        self._pairs: deque = deque()          # (s, y, 1 / (s.y)) oldest first
        self._d = be.empty((n,))
        self._x_old = be.empty((n,))
        self._g_old = be.empty((n,))

    def reset(self) -> None:
        """Forget the curvature pairs (call when the objective changes)."""
        while self._pairs:
            s, y, _ = self._pairs.popleft()
            self._free.append((s, y))

    def _direction(self, g) -> None:
        """``d = -H g`` by the two-loop recursion (Nocedal & Wright Alg. 7.4)."""
        v = self.be.vecops
        d = self._d
        v.copy(g, d)
        alphas = []
        for s, y, rho in reversed(self._pairs):
            a = rho * v.dot(s, d)
            v.axpy(-a, y, d)
            alphas.append(a)
        if self._pairs:
            s, y, rho = self._pairs[-1]
            v.scale(1.0 / (rho * v.dot(y, y)), d)   # gamma = s.y / y.y
        for (s, y, rho), a in zip(self._pairs, reversed(alphas)):
            b = rho * v.dot(y, d)
            v.axpy(a - b, s, d)
        v.scale(-1.0, d)

    def minimize(self, fun: Callable, x, g, iterations: int, *, rel_tol: float = 1e-6,
                 on_iteration: Callable | None = None) -> float:
        """Run up to ``iterations`` L-BFGS steps from ``x`` in place.

        ``fun(x, g) -> float`` returns the energy at ``x`` and writes its
        gradient into ``g``.  On return ``x`` holds the best point found and
        ``g`` its gradient; the energy there is returned.
        ``on_iteration(k, energy)`` is called after every accepted step.
        """
        v = self.be.vecops
        f = fun(x, g)
        for k in range(iterations):
            if self._pairs:
                self._direction(g)
                step = 1.0
            else:
                v.copy(g, self._d)
                v.scale(-1.0, self._d)
                gmax = v.norm_inf(g)
                if gmax == 0.0:
                    break
                step = self.first_step / gmax
            slope = v.dot(g, self._d)
            if slope >= 0.0:                        # not a descent direction: restart
                self.reset()
                continue
            v.copy(x, self._x_old)
            v.copy(g, self._g_old)
            f_old = f
            accepted = False
            for _ in range(20):                     # backtracking, Armijo c1 = 1e-4
                v.lincomb(x, 1.0, self._x_old, step, self._d)
                f = fun(x, g)
                if f <= f_old + 1e-4 * step * slope:
                    accepted = True
                    break
                step *= 0.3
            if not accepted:
                v.copy(self._x_old, x)
                v.copy(self._g_old, g)
                f = f_old
                if self._pairs:                     # retry once from steepest descent
                    self.reset()
                    continue
                break
            self._push_pair(x, g)
            if on_iteration is not None:
                on_iteration(k, f)
            if abs(f_old - f) <= rel_tol * max(1.0, abs(f)):
                break
        return f

    def _push_pair(self, x, g) -> None:
        v = self.be.vecops
        if self._free:
            s, y = self._free.pop()
        else:
            s, y, _ = self._pairs.popleft()
        v.lincomb(s, 1.0, x, -1.0, self._x_old)
        v.lincomb(y, 1.0, g, -1.0, self._g_old)
        sy = v.dot(s, y)
        if sy > 1e-12 * v.dot(y, y) and sy > 0.0:
            self._pairs.append((s, y, 1.0 / sy))
        else:                                       # curvature condition fails: skip
            self._free.append((s, y))
