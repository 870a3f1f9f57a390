"""Limited-memory BFGS on backend vectors.

The unknowns of a window (all ``A_t`` and ``S_t`` stacked, millions of
values) stay in one flat backend array; every vector operation of the method
(the direction, the line search) runs through the backend's ``vecops``
kernels, so no full-size NumPy temporaries sit on the hot path; the
two-loop recursion itself runs on small coefficient vectors on the host.

References: Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 7.4
(two-loop recursion) and Alg. 3.1 (backtracking with the Armijo condition);
Chen, Wang & Zhou, "Large-scale L-BFGS using MapReduce", NIPS 2014
(vector-free L-BFGS).
"""
from __future__ import annotations

from collections import deque
from typing import Callable

import numpy as np

#: Default ``rel_tol`` of :meth:`LBFGS.minimize`: a quasi-Newton step that
#: changes the energy by less than this, relatively, ends the run as
#: converged.  It is a loose test: the energy of Eq. 2 has long, flat valleys
#: where steps of 1e-6 still move the albedo by percents (on 2-3 frames of
#: 16x24 to 20x28 with the true flow, runs stopped by it end 2-3% apart between
#: backends, their energies 2.5e-4 apart; at 1e-10 the energies agree to 1e-6
#: and the albedos to 0.2%; perf/RESULTS.md, "Backends agree once converged").
#: Every solve's default; a study that needs solves run to convergence lowers
#: it (with enough iterations: ``Params.lbfgs_iterations``, ``..._coarse``).
REL_TOL = 1e-6


class LBFGS:
    """Minimiser of a smooth function of a flat float32 backend vector.

    Parameters
    ----------
    be : backend (:func:`ivkernels.backends.get_backend`).
    n : number of unknowns.
    memory : number of correction pairs ``(s_k, y_k)`` kept.
    first_step : largest change (in the unknowns' units) of the very first
        step along ``-g``; later steps start from the quasi-Newton step 1.

    The two-loop recursion runs on coefficients rather than on vectors
    ("vector-free" L-BFGS, Chen, Wang & Zhou, NIPS 2014): the pairs and the
    last two gradients are the rows of one (2m + 2, n) basis, the solver keeps
    the Gram matrix of its rows on the host, and each iteration costs one
    pass that dots the new gradient with every row (``vecops.dots``) and one
    that forms the direction as a combination of rows (``vecops.combine``),
    instead of 4m passes.  The new pair's other dot products follow from
    ``s = step * d`` and ``y = g_new - g_old``.  All buffers are allocated
    once here and reused across calls.
    """

    def __init__(self, be, n: int, memory: int = 6, first_step: float = 0.1):
        if memory < 1:
            raise ValueError(f"memory must be >= 1, got {memory}")
        self.be = be
        self.n = n
        self.memory = memory
        self.first_step = first_step
        # basis rows: s of slot i at i, y of slot i at m + i, gradients at 2m, 2m + 1
        self._basis = be.zeros((2 * memory + 2, n))
        self._gram = np.zeros((2 * memory + 2, 2 * memory + 2))
        self._pairs: deque = deque()          # (slot, 1 / (s.y)) oldest first
        self._free = list(range(memory))
        self._g_rows = [2 * memory, 2 * memory + 1]     # [current, previous] gradient rows
        self._d = be.empty((n,))
        self._x_old = be.empty((n,))

    def reset(self) -> None:
        """Forget the curvature pairs (call when the objective changes)."""
        while self._pairs:
            self._free.append(self._pairs.popleft()[0])

    def _direction(self, cur: int) -> np.ndarray:
        """Coefficients over the basis rows of ``d = -H g`` (Nocedal & Wright
        Alg. 7.4, on coefficients; ``g`` is row ``cur``)."""
        m, G = self.memory, self._gram
        c = np.zeros(G.shape[0])
        c[cur] = 1.0
        alphas = []
        for slot, rho in reversed(self._pairs):
            a = rho * (G[slot] @ c)
            c[m + slot] -= a
            alphas.append(a)
        slot, rho = self._pairs[-1]
        c *= 1.0 / (rho * G[m + slot, m + slot])          # gamma = s.y / y.y
        for (slot, rho), a in zip(self._pairs, reversed(alphas)):
            b = rho * (G[m + slot] @ c)
            c[slot] += a - b
        return -c

    def _finish_pair(self, slot: int, cur: int, prev: int, live: list) -> None:
        """Gram entries of ``y = g_cur - g_prev`` (row m + slot); keep the pair if s.y > 0."""
        m, G = self.memory, self._gram
        y = m + slot
        for j in live:
            if j != y:
                G[y, j] = G[j, y] = G[cur, j] - G[prev, j]
        G[y, y] = G[y, cur] - G[y, prev]
        sy, yy = G[slot, y], G[y, y]
        # y.y from differences of float32 dots can round to 0 or below while s.y > 0;
        # such a pair would scale the two-loop by s.y / y.y = inf
        if yy > 0.0 and sy > 1e-12 * yy and np.isfinite(sy / yy):
            self._pairs.append((slot, 1.0 / sy))
        else:                                       # curvature condition fails: skip
            self._free.append(slot)

    def minimize(self, fun: Callable, x, g, iterations: int, *, rel_tol: float | None = None,
                 on_iteration: Callable | None = None) -> float:
        """Run up to ``iterations`` L-BFGS steps from ``x`` in place.

        ``fun(x, g) -> float`` returns the energy at ``x`` and writes its
        gradient into ``g``.  On return ``x`` holds the best point found and
        ``g`` its gradient; the energy there is returned.
        ``on_iteration(k, energy)`` is called after every accepted step.
        Afterwards :attr:`stop_reason` says why it stopped: ``"tolerance"``
        (relative energy change of a quasi-Newton step below ``rel_tol``,
        default :data:`REL_TOL`: converged; a steepest-descent step, the first of a run or after a
        restart, is scaled to ``first_step`` and says nothing about
        convergence, so it never stops the run), ``"stationary"``
        (zero gradient), ``"line search"`` (no decrease along steepest descent
        either: converged to float32 precision) or ``"budget"`` (``iterations``
        used up).
        """
        v, m, B, G = self.be.vecops, self.memory, self._basis, self._gram
        rel_tol = REL_TOL if rel_tol is None else float(rel_tol)
        f = fun(x, g)
        pending = None                              # slot whose y is formed next iteration
        self.stop_reason = "budget"
        for k in range(iterations):
            cur, prev = self._g_rows
            v.copy(g, B[cur])
            live = [r for slot, _ in self._pairs for r in (slot, m + slot)] + [cur]
            if pending is not None:
                v.lincomb(B[m + pending], 1.0, B[cur], -1.0, B[prev])
                live += [pending, m + pending, prev]
            gd = v.dots(B, B[cur], live)
            G[cur, live] = gd
            G[live, cur] = gd
            if pending is not None:
                self._finish_pair(pending, cur, prev, live)
                pending = None
            quasi_newton = bool(self._pairs)
            if quasi_newton:
                c = self._direction(cur)
                step = 1.0
            else:
                gmax = v.norm_inf(g)
                if gmax == 0.0:
                    self.stop_reason = "stationary"
                    break
                c = np.zeros(G.shape[0])
                c[cur] = -1.0
                step = self.first_step / gmax
            rows = np.flatnonzero(c)
            slope = float(G[cur, rows] @ c[rows])   # g . d
            if slope >= 0.0:                        # not a descent direction: restart
                self.reset()
                continue
            v.combine(self._d, B, rows, c[rows])
            v.copy(x, self._x_old)
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
                v.copy(B[cur], g)
                f = f_old
                if self._pairs:                     # retry once from steepest descent
                    self.reset()
                    continue
                self.stop_reason = "line search"
                break
            # s = step * d into a free slot (or the oldest pair's); its dot products with
            # the other rows follow from d's coefficients, before the slot is overwritten.
            slot = self._free.pop() if self._free else self._pairs.popleft()[0]
            s_dots = step * (G @ c)
            ss = step * step * float(c @ G @ c)
            v.lincomb(B[slot], step, self._d, 0.0, self._d)
            G[slot, :] = s_dots
            G[:, slot] = s_dots
            G[slot, slot] = ss
            pending = slot
            self._g_rows.reverse()
            if on_iteration is not None:
                on_iteration(k, f)
            if quasi_newton and abs(f_old - f) <= rel_tol * max(1.0, abs(f)):
                self.stop_reason = "tolerance"
                break
        if pending is not None:
            self._free.append(pending)
        return f
