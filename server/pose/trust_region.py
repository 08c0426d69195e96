"""scipy's `least_squares` (method "trf", no bounds, the exact trust-region solver, a callable
loss, a fixed `x_scale`) with its Python-level wrappers left out: the same iterates.

The outline fit (`server.pose.outline`) runs some ten fits a frame of ~100 iterations each on a
few hundred residuals; in `least_squares` most of an iteration's time is its wrappers
(`VectorFunction`'s copies and bookkeeping, `svd`'s argument checks, the loss's closure), not the
SVD or the residuals. This is `scipy.optimize._lsq.trf.trf_no_bounds` (scipy 1.17) and what
`least_squares` does before it, operation for operation: the same NumPy calls on the same
arrays in the same order, the SVD by the same LAPACK routine (`gesdd` with scipy's workspace),
so that every iterate, the cost, the status and the evaluation count are scipy's to the last bit
(tests/server/pose/test_trust_region.py holds them equal). What is left out is only what these
fits never use: bounds, `x_scale="jac"`, the "lsmr" solver, callbacks, verbosity.

A derived work of SciPy (scipy/optimize/_lsq/trf.py and least_squares.py, BSD 3-Clause,
Copyright (c) 2001-2002 Enthought, Inc. 2003, SciPy Developers): its licence is in
server/pose/LICENSE-scipy.txt (shipped with the package).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cache
from types import SimpleNamespace

import numpy as np
from scipy.linalg import LinAlgError, get_lapack_funcs
from scipy.linalg.lapack import _compute_lwork  # the workspace scipy's svd asks for

EPS = np.finfo(float).eps  # scipy.optimize._lsq.common.EPS


class RobustLoss:
    """`least_squares`' loss function for a callable loss `rho(z)` (rho (3, m) of z = (f /
    f_scale)^2; `construct_loss_function`'s closure), and the Jacobian's and residuals' scaling
    by it (`scale_for_robust_loss_function`). A compiled loss may stand in with the same results."""

    def __init__(self, rho: Callable[[np.ndarray], np.ndarray], f_scale: float):
        self.rho, self.f_scale = rho, f_scale

    def __call__(self, f: np.ndarray, cost_only: bool = False):
        """rho (3, m) of the residuals f (m,) in f_scale's units; or, `cost_only`, the cost."""
        z = (f / self.f_scale) ** 2
        rho = self.rho(z)
        if cost_only:
            return 0.5 * self.f_scale**2 * np.add.reduce(rho[0])  # np.sum
        rho[0] *= self.f_scale**2
        rho[2] /= self.f_scale**2
        return rho

    def scale(self, J: np.ndarray, f: np.ndarray, rho: np.ndarray) -> None:
        """J (m, n) and f (m,) scaled in place for the loss's rho (`__call__`'s)."""
        J_scale = rho[1] + 2 * rho[2] * f**2
        J_scale[J_scale < EPS] = EPS
        J_scale **= 0.5
        f *= rho[1] / J_scale
        J *= J_scale[:, np.newaxis]


def trust_region_fit(
    fun: Callable[[np.ndarray], np.ndarray],
    jac: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    f0: np.ndarray,
    loss_function: RobustLoss,
    x_scale: np.ndarray,
    max_nfev: int,
    ftol: float = 1e-8,
    xtol: float = 1e-8,
    gtol: float = 1e-8,
    pause_nfev: int | None = None,
    carry_on: Callable[[float], bool] = lambda cost: True,
) -> SimpleNamespace:
    """`least_squares(fun, x0, jac=jac, loss=rho, f_scale=f_scale, x_scale=x_scale,
    max_nfev=max_nfev)`'s x, cost, status (0: `max_nfev` stopped it), nfev and njev, with
    `f0 = fun(x0)` given (finite) and `loss_function` the `RobustLoss` of rho and f_scale.
    Raises ValueError as scipy does where the Jacobian stops being finite.

    With `pause_nfev`: where the fit with `max_nfev=pause_nfev` would stop at that cap,
    `carry_on(cost)` decides: False returns that fit; True goes on to `max_nfev`, the very fit
    from `x0` with `max_nfev` (only the cap stopped the first one, and from there the two are
    the same loop; the one difference, an SVD of the same Jacobian done again, gives the same
    factors), without its first `pause_nfev` evaluations done twice."""
    if max_nfev < 1 or (pause_nfev is not None and pause_nfev < 1):  # as least_squares refuses them: no cap, no end
        raise ValueError(f"max_nfev and pause_nfev must be >= 1, not {max_nfev} and {pause_nfev}")
    x0 = np.atleast_1d(x0).astype(float)
    x_scale = np.asarray(x_scale, dtype=float)
    if not np.all(np.isfinite(f0)):
        raise ValueError("Residuals are not finite in the initial point.")
    J0 = jac(x0)

    # trf_no_bounds from here
    x = x0.copy()
    f = f0
    nfev = 1
    J = J0
    njev = 1
    m, n = J.shape
    rho = loss_function(f)
    cost = 0.5 * np.add.reduce(rho[0])
    loss_function.scale(J, f, rho)
    g = J.T.dot(f)
    scale, scale_inv = x_scale, 1 / x_scale
    Delta = _norm(x0 * scale_inv)
    if Delta == 0:
        Delta = 1.0
    alpha = 0.0
    termination_status = None
    cap = max_nfev if pause_nfev is None else min(pause_nfev, max_nfev)
    while True:
        g_norm = np.abs(g).max()  # norm(g, ord=np.inf)
        if g_norm < gtol:
            termination_status = 1
        if termination_status is not None:
            break
        if nfev == cap:
            if cap == max_nfev or not carry_on(cost):
                break
            cap = max_nfev
        d = scale
        g_h = d * g
        J_h = J * d
        U, s, V = _svd(J_h)
        V = V.T
        uf = U.T.dot(f)
        actual_reduction = -1
        while actual_reduction <= 0 and nfev < cap:
            step_h, alpha = _solve_lsq_trust_region(n, m, uf, s, V, Delta, alpha)
            Js = J_h.dot(step_h)  # common.evaluate_quadratic
            predicted_reduction = -(0.5 * np.dot(Js, Js) + np.dot(step_h, g_h))
            step = d * step_h
            x_new = x + step
            f_new = fun(x_new)
            nfev += 1
            step_h_norm = _norm(step_h)
            if not np.isfinite(f_new).all():
                Delta = 0.25 * step_h_norm
                continue
            cost_new = loss_function(f_new, cost_only=True)
            actual_reduction = cost - cost_new
            Delta_new, ratio = _update_tr_radius(
                Delta, actual_reduction, predicted_reduction, step_h_norm, step_h_norm > 0.95 * Delta
            )
            step_norm = _norm(step)
            termination_status = _check_termination(actual_reduction, cost, step_norm, _norm(x), ratio, ftol, xtol)
            if termination_status is not None:
                break
            alpha *= Delta / Delta_new
            Delta = Delta_new
        if actual_reduction > 0:
            x = x_new
            f = f_new
            cost = cost_new
            J = jac(x)
            njev += 1
            rho = loss_function(f)
            loss_function.scale(J, f, rho)
            g = J.T.dot(f)
    if termination_status is None:
        termination_status = 0
    return SimpleNamespace(x=x, cost=cost, status=termination_status, nfev=nfev, njev=njev)


def _norm(v: np.ndarray) -> float:
    """numpy.linalg.norm of a vector: the square root of its dot product with itself, as numpy takes it
    (a NumPy float: a division by a zero norm gives inf as there, not an exception)."""
    return np.float64(math.sqrt(v.dot(v)))


def _solve_lsq_trust_region(n, m, uf, s, V, Delta, initial_alpha, rtol=0.01, max_iter=10):
    """common.solve_lsq_trust_region (an `initial_alpha` given): the step and its alpha."""

    def phi_and_derivative(alpha, suf, s, Delta):
        denom = s**2 + alpha
        p_norm = _norm(suf / denom)
        phi = p_norm - Delta
        phi_prime = -np.add.reduce(suf**2 / denom**3) / p_norm  # np.sum
        return phi, phi_prime

    suf = s * uf
    if m >= n:
        threshold = EPS * m * s[0]
        full_rank = s[-1] > threshold
    else:
        full_rank = False
    if full_rank:
        p = -V.dot(uf / s)
        if _norm(p) <= Delta:
            return p, 0.0
    alpha_upper = _norm(suf) / Delta
    if full_rank:
        phi, phi_prime = phi_and_derivative(0.0, suf, s, Delta)
        alpha_lower = -phi / phi_prime
    else:
        alpha_lower = 0.0
    if initial_alpha is None or not full_rank and initial_alpha == 0:
        alpha = max(0.001 * alpha_upper, (alpha_lower * alpha_upper) ** 0.5)
    else:
        alpha = initial_alpha
    for _ in range(max_iter):
        if alpha < alpha_lower or alpha > alpha_upper:
            alpha = max(0.001 * alpha_upper, (alpha_lower * alpha_upper) ** 0.5)
        phi, phi_prime = phi_and_derivative(alpha, suf, s, Delta)
        if phi < 0:
            alpha_upper = alpha
        ratio = phi / phi_prime
        alpha_lower = max(alpha_lower, alpha - ratio)
        alpha -= (phi + Delta) * ratio / Delta
        if np.abs(phi) < rtol * Delta:
            break
    p = -V.dot(suf / (s**2 + alpha))
    # (scipy's own: the norm of p made Delta, so that p stays inside the trust region)
    p *= Delta / _norm(p)
    return p, alpha


def _update_tr_radius(Delta, actual_reduction, predicted_reduction, step_norm, bound_hit):
    """common.update_tr_radius."""
    if predicted_reduction > 0:
        ratio = actual_reduction / predicted_reduction
    elif predicted_reduction == actual_reduction == 0:
        ratio = 1
    else:
        ratio = 0
    if ratio < 0.25:
        Delta = 0.25 * step_norm
    elif ratio > 0.75 and bound_hit:
        Delta *= 2.0
    return Delta, ratio


def _check_termination(dF, F, dx_norm, x_norm, ratio, ftol, xtol):
    """common.check_termination."""
    ftol_satisfied = dF < ftol * F and ratio > 0.25
    xtol_satisfied = dx_norm < xtol * (xtol + x_norm)
    if ftol_satisfied and xtol_satisfied:
        return 4
    if ftol_satisfied:
        return 2
    if xtol_satisfied:
        return 3
    return None


def _svd(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scipy.linalg.svd(a, full_matrices=False): the same LAPACK call, its checks but one lookup."""
    if not np.isfinite(a).all():
        raise ValueError("array must not contain infs or NaNs")
    gesdd, lwork = _gesdd(*a.shape)
    u, s, v, info = gesdd(a, compute_uv=True, lwork=lwork, full_matrices=False, overwrite_a=False)
    if info > 0:
        raise LinAlgError("SVD did not converge")
    if info < 0:
        raise ValueError(f"illegal value in {-info}th argument of internal gesdd")
    return u, s, v


@cache
def _gesdd(m: int, n: int) -> tuple[Callable, int]:
    """LAPACK's dgesdd and the workspace scipy's `svd` asks for an (m, n) matrix."""
    like = np.zeros((1, 1))
    gesdd, gesdd_lwork = get_lapack_funcs(("gesdd", "gesdd_lwork"), (like,), ilp64="preferred")
    return gesdd, _compute_lwork(gesdd_lwork, m, n, compute_uv=True, full_matrices=False)
