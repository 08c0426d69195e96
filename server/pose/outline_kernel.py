"""The outline fit's distances and their Jacobian for one parameter vector, compiled (numba).

A fit evaluates them some hundred times on a few hundred points: in NumPy each evaluation is
~100 array calls whose fixed cost, not the arithmetic, is most of a frame. This is the same
arithmetic point by point in one call. `server.pose.outline._Problem._terms` and `.jacobian`
stay the reference (tests/server/pose/test_outline_kernel.py holds the two equal): every
operation here is theirs, in their order and without fast-math, and the 3 x 3 products are
fused in the order OpenBLAS's matmul sums them, so that on this machine the two agree to the
last bit and the fits' results do not move.

Conventions as in `server.pose.outline`: params (9,) = yaw, pitch, roll (rad; R_wc = Rz Ry
Rx), the camera's position (m), the growth D (px) and its gradient (px per unit of normalised
image coordinate); rays (3, N); each panel's geometry (centres (3, M), axes (3, 2, M), inner
(2, M), radius (M,)) per point, or once (M = 1) when all points are on one panel.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def _fma(typingctx, a, b, c):
    """a * b + c rounded once (LLVM's llvm.fma): how OpenBLAS's kernels sum a product."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, sig, args):
        double = ir.DoubleType()
        function = cgutils.get_or_insert_function(builder.module, ir.FunctionType(double, [double] * 3), "llvm.fma.f64")
        return builder.call(function, args)

    return signature, codegen


@njit(cache=True)
def _dot3(a0, a1, a2, b0, b1, b2):
    """a . b as NumPy's matmul gives it here (OpenBLAS: a0 b0, then each next product fused in)."""
    return _fma(a2, b2, _fma(a1, b1, a0 * b0))


@njit(cache=True)
def _maximum(a, b):
    """np.maximum of two floats: a NaN propagates (Python's max would drop it)."""
    return a if a >= b or a != a else b


@njit(cache=True)
def _minimum(a, b):
    """np.minimum of two floats."""
    return a if a <= b or a != a else b


@njit(cache=True)
def outline_residuals(params, rays, centres, axes, inner, radius, spread, focal_x, focal_y, blur_sq, on_arc, frozen,
                      prior_columns, prior_values, prior_sigmas, prior_wrapped, behind_px, point_sigma_px, residuals,
                      jacobian):  # fmt: skip
    """Fill `residuals` (N + m,): each point's signed distance to the grown outline (px) over
    `point_sigma_px`, then the m priors (`_Problem._prior_terms`' rows); and, when `jacobian`
    has as many rows, d residuals / d params (N + m, 9). `on_arc` (N,) holds the points on an
    arc when `frozen`; else a point beyond its arc's centre is on it. `blur_sq` is the edge's
    blur squared (px^2); `behind_px` the distance of a point whose panel is behind the camera."""
    points = rays.shape[1]
    with_jacobian = jacobian.shape[0] == residuals.shape[0]
    for row in range(prior_columns.shape[0]):
        column = prior_columns[row]
        difference = params[column] - prior_values[row]
        if prior_wrapped[row]:
            difference = (difference + math.pi) % (2 * math.pi) - math.pi  # `server.pose.outline._wrap`
        residuals[points + row] = difference / prior_sigmas[row]
        if with_jacobian:
            jacobian[points + row, :] = 0.0
            jacobian[points + row, column] = 1.0 / prior_sigmas[row]
    cy, sy = math.cos(params[0]), math.sin(params[0])
    cp, sp = math.cos(params[1]), math.sin(params[1])
    cr, sr = math.cos(params[2]), math.sin(params[2])
    rot = np.empty((3, 3))
    rot[0, 0], rot[0, 1], rot[0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    rot[1, 0], rot[1, 1], rot[1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    rot[2, 0], rot[2, 1], rot[2, 2] = -sp, cp * sr, cp * cr
    # d R / d (yaw, pitch, roll): Kz R, Rz Ry Ky Rx, R Kx (the products of the generators
    # written out: each entry is one product, as in the NumPy matmuls)
    turns = np.zeros((3, 3, 3))
    for i in range(3):
        turns[0, 0, i], turns[0, 1, i] = -rot[1, i], rot[0, i]
        turns[2, i, 1], turns[2, i, 2] = rot[i, 2], -rot[i, 1]
    ryz = ((cy * cp, cy * sp), (sy * cp, sy * sp), (-sp, cp))  # Rz Ry's first and last columns
    for i in range(3):
        turns[1, i, 0], turns[1, i, 1], turns[1, i, 2] = -ryz[i][1], ryz[i][0] * sr, ryz[i][0] * cr
    single = centres.shape[1] == 1
    seen = np.empty((3, 2))  # the panel's axes in the camera frame, R^T (x_B, y_B)
    d_reach, d_signed = np.zeros(6), np.empty(6)
    d_plane, d_q = np.empty((6, 2)), np.empty((6, 2))
    for j in range(points):
        g = 0 if single else j
        r0, r1, r2 = rays[0, j], rays[1, j], rays[2, j]
        a0 = _dot3(rot[0, 0], rot[0, 1], rot[0, 2], r0, r1, r2)
        a1 = _dot3(rot[1, 0], rot[1, 1], rot[1, 2], r0, r1, r2)
        a2 = _dot3(rot[2, 0], rot[2, 1], rot[2, 2], r0, r1, r2)
        rise = a2 if abs(a2) > 1e-9 else 1e-9
        reach = (centres[2, g] - params[5]) / rise
        o0 = params[3] + reach * a0 - centres[0, g]
        o1 = params[4] + reach * a1 - centres[1, g]
        o2 = params[5] + reach * a2 - centres[2, g]
        px = axes[0, 0, g] * o0 + axes[1, 0, g] * o1 + axes[2, 0, g] * o2
        py = axes[0, 1, g] * o0 + axes[1, 1, g] * o1 + axes[2, 1, g] * o2
        qx, qy = abs(px) - inner[0, g], abs(py) - inner[1, g]
        outside = math.hypot(_maximum(qx, 0.0), _maximum(qy, 0.0))
        signed = outside + _minimum(_maximum(qx, qy), 0.0) - radius[g]
        corner = qx > 0 and qy > 0
        sx, sy_ = np.sign(px), np.sign(py)
        gx = (_maximum(qx, 0.0) / _maximum(outside, 1e-12) if corner else (1.0 if qx >= qy else 0.0)) * sx
        gy = (_maximum(qy, 0.0) / _maximum(outside, 1e-12) if corner else (1.0 if qx < qy else 0.0)) * sy_
        m0 = axes[0, 0, g] * gx + axes[0, 1, g] * gy
        m1 = axes[1, 0, g] * gx + axes[1, 1, g] * gy
        m2 = axes[2, 0, g] * gx + axes[2, 1, g] * gy
        n0 = _dot3(rot[0, 0], rot[1, 0], rot[2, 0], m0, m1, m2)
        n1 = _dot3(rot[0, 1], rot[1, 1], rot[2, 1], m0, m1, m2)
        n2 = _dot3(rot[0, 2], rot[1, 2], rot[2, 2], m0, m1, m2)
        x, y, z = r0 * reach, r1 * reach, r2 * reach
        du = focal_x / z * (n0 - x / z * n2)
        dv = focal_y / z * (n1 - y / z * n2)
        scale = math.hypot(du, dv)
        growth = params[6] + params[7] * spread[0, j] + params[8] * spread[1, j]
        arc = on_arc[j] if frozen else corner
        arc_px = radius[g] * scale + growth if arc else math.inf
        value = signed * scale - growth + blur_sq / (2 * _maximum(arc_px, 1.0))
        residuals[j] = (value if reach > 0 else behind_px) / point_sigma_px
        if not with_jacobian:
            continue
        # the chain rule of `_Problem.jacobian`, term by term
        grazing = abs(a2) <= 1e-9
        ap0 = axes[0, 0, g] * a0 + axes[1, 0, g] * a1 + axes[2, 0, g] * a2
        ap1 = axes[0, 1, g] * a0 + axes[1, 1, g] * a1 + axes[2, 1, g] * a2
        d_reach[5] = -1.0 / rise
        for t in range(3):
            t0 = _dot3(turns[t, 0, 0], turns[t, 0, 1], turns[t, 0, 2], r0, r1, r2)
            t1 = _dot3(turns[t, 1, 0], turns[t, 1, 1], turns[t, 1, 2], r0, r1, r2)
            t2 = _dot3(turns[t, 2, 0], turns[t, 2, 1], turns[t, 2, 2], r0, r1, r2)
            d_reach[t] = -reach / rise * t2 * (1.0 if not grazing else 0.0)
            d_plane[t, 0] = d_reach[t] * ap0 + reach * (axes[0, 0, g] * t0 + axes[1, 0, g] * t1 + axes[2, 0, g] * t2)
            d_plane[t, 1] = d_reach[t] * ap1 + reach * (axes[0, 1, g] * t0 + axes[1, 1, g] * t1 + axes[2, 1, g] * t2)
        for i in range(3):
            d_plane[3 + i, 0] = d_reach[3 + i] * ap0 + axes[i, 0, g]
            d_plane[3 + i, 1] = d_reach[3 + i] * ap1 + axes[i, 1, g]
        width = _maximum(outside, 1e-12)
        w0, w1 = _maximum(qx, 0.0) / width, _maximum(qy, 0.0) / width
        for t in range(6):
            d_signed[t] = gx * d_plane[t, 0] + gy * d_plane[t, 1]
            d_q[t, 0], d_q[t, 1] = sx * d_plane[t, 0], sy_ * d_plane[t, 1]
        if j == 0 or not single:
            for i in range(3):
                for b in range(2):
                    seen[i, b] = _dot3(rot[0, i], rot[1, i], rot[2, i], axes[0, b, g], axes[1, b, g], axes[2, b, g])
        bends = arc and arc_px > 1.0
        d_arc = -blur_sq / (2 * (arc_px * arc_px)) if bends else 0.0
        for t in range(6):
            dg0 = dg1 = 0.0  # the normal turns only on an arc (the reference's product with 0, unsigned)
            if corner:
                along_w = w0 * d_q[t, 0] + w1 * d_q[t, 1]
                dg0 = (d_q[t, 0] - w0 * along_w) / width * sx
                dg1 = (d_q[t, 1] - w1 * along_w) / width * sy_
            dn0, dn1, dn2 = seen[0, 0] * dg0 + seen[0, 1] * dg1, seen[1, 0] * dg0 + seen[1, 1] * dg1, \
                seen[2, 0] * dg0 + seen[2, 1] * dg1  # fmt: skip
            if t < 3:
                dn0 += _dot3(turns[t, 0, 0], turns[t, 1, 0], turns[t, 2, 0], m0, m1, m2)
                dn1 += _dot3(turns[t, 0, 1], turns[t, 1, 1], turns[t, 2, 1], m0, m1, m2)
                dn2 += _dot3(turns[t, 0, 2], turns[t, 1, 2], turns[t, 2, 2], m0, m1, m2)
            d_z = d_reach[t] * r2
            d_du = focal_x * (dn0 - x / z * dn2) / z - du * d_z / z
            d_dv = focal_y * (dn1 - y / z * dn2) / z - dv * d_z / z
            d_scale = (du * d_du + dv * d_dv) / scale
            d_pose = d_signed[t] * scale + (signed + d_arc * radius[g]) * d_scale
            jacobian[j, t] = d_pose * (1.0 if reach > 0 else 0.0) / point_sigma_px
        d_growth = d_arc - 1.0
        jacobian[j, 6] = d_growth * 1.0 * (1.0 if reach > 0 else 0.0) / point_sigma_px
        jacobian[j, 7] = d_growth * spread[0, j] * (1.0 if reach > 0 else 0.0) / point_sigma_px
        jacobian[j, 8] = d_growth * spread[1, j] * (1.0 if reach > 0 else 0.0) / point_sigma_px


@njit(cache=True)
def huber_rho(z):
    """scipy's "huber" loss as a callable `least_squares` loss (`scipy.optimize._lsq.least_squares.huber`,
    the same arithmetic): rho (3, m) of z = (f / f_scale)^2, its value and first two derivatives."""
    rho = np.empty((3, z.shape[0]))
    for i in range(z.shape[0]):
        if z[i] <= 1:
            rho[0, i], rho[1, i], rho[2, i] = z[i], 1.0, 0.0
        else:
            rho[0, i] = 2 * math.sqrt(z[i]) - 1
            rho[1, i] = z[i] ** -0.5
            rho[2, i] = -0.5 * z[i] ** -1.5
    return rho


@njit(cache=True)
def huber_terms(f, f_scale, f_scale_sq, cost_only):
    """`least_squares`' loss function of its "huber" at f_scale (`construct_loss_function`'s,
    with `huber_rho`): rho (3, m) of the residuals f (m,), rho[0] times f_scale^2 and rho[2] over
    it; or, `cost_only`, rho (1, m) of rho[0] as the loss gives it (the cost is 0.5 f_scale^2 times
    its sum: NumPy's pairwise sum, taken by the caller). The same operations, point by point."""
    rho = np.empty((1 if cost_only else 3, f.shape[0]))
    for i in range(f.shape[0]):
        q = f[i] / f_scale
        z = q * q  # NumPy's ** 2
        if z <= 1:
            rho[0, i] = z
            if not cost_only:
                rho[1, i], rho[2, i] = 1.0, 0.0
        else:
            rho[0, i] = 2 * math.sqrt(z) - 1
            if not cost_only:
                rho[1, i] = z**-0.5
                rho[2, i] = -0.5 * z**-1.5
        if not cost_only:
            rho[0, i] *= f_scale_sq
            rho[2, i] /= f_scale_sq
    return rho


@njit(cache=True)
def scale_for_robust_loss(J, f, rho, eps):
    """scipy's `scale_for_robust_loss_function` in place: f and the rows of J (m, n) by the loss's
    rho (3, m); `eps` the machine epsilon the scale is held above."""
    for i in range(f.shape[0]):
        scale = rho[1, i] + 2 * rho[2, i] * (f[i] * f[i])
        if scale < eps:
            scale = eps
        scale = math.sqrt(scale)  # NumPy's ** 0.5
        f[i] *= rho[1, i] / scale
        for j in range(J.shape[1]):
            J[i, j] *= scale
