"""The sub-pixel stage's arithmetic after the sampling, compiled (numba).

At quarter resolution a frame's sides are a few hundred crossings: in NumPy the stage is ~470
array calls whose fixed cost, not their arithmetic, is most of its time. These are the same
operations element by element, a call each. `server.vision.subpixel`'s NumPy functions stay the
reference (tests/server/vision/test_subpixel_kernel.py holds the two equal on the benches'
frames): every operation here is theirs, in their order and without fast-math; a reduction over
a row sums in eight running sums as NumPy's does (`_sum`), a 2-vector product is fused as OpenBLAS's is
(`server.pose.outline_kernel._fma`). What is left different: the 12 x 12 normal equations of the
pixel-locking fit, summed here in row order where OpenBLAS's GEMM blocks them (last bits), and
solved by OpenCV's own LU (`cv2.solve`'s `DECOMP_LU`, written out).

Conventions as in `server.vision.subpixel`: sides (4, n) of n crossings each; points x, y.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from server.pose.outline_kernel import _fma

ROW_LIMIT = 128  # crossings a side: NumPy sums a row of up to this many as one block (`_sum`)


@njit(cache=True)
def _sum(values, start, count):
    """values[start:start + count] summed as NumPy's `add.reduce` sums a contiguous row of up to
    `ROW_LIMIT` values (`pairwise_sum`'s block: in order below 8 values, else in eight interleaved
    running sums, then the rest in order; a longer row it sums in halves, which is not done here)."""
    if count < 8:
        total = 0.0
        for i in range(start, start + count):
            total += values[i]
        return total
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    i = 8
    while i < count - count % 8:
        j = start + i
        r0 += values[j]
        r1 += values[j + 1]
        r2 += values[j + 2]
        r3 += values[j + 3]
        r4 += values[j + 4]
        r5 += values[j + 5]
        r6 += values[j + 6]
        r7 += values[j + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < count:
        total += values[start + i]
        i += 1
    return total


@njit(cache=True)
def _row_sum(values):
    """A 1-D array summed as NumPy sums it."""
    return _sum(values, 0, values.shape[0])


@njit(cache=True)
def _kth_smallest(values, k):
    """The k-th smallest of `values` (1-D, no NaN; 0-based): what a sort puts at k. Quickselect in
    place, not np.sort, whose compiled sort costs numba more than the rest of a kernel."""
    low, high = 0, values.shape[0] - 1
    while low < high:
        pivot = values[(low + high) // 2]
        i, j = low, high
        while i <= j:
            while values[i] < pivot:
                i += 1
            while values[j] > pivot:
                j -= 1
            if i <= j:
                values[i], values[j] = values[j], values[i]
                i += 1
                j -= 1
        if k <= j:
            high = j
        elif k >= i:
            low = i
        else:
            break
    return values[k]


@njit(cache=True)
def _sign(value):
    """np.sign of a float (NaN stays NaN)."""
    if value > 0:
        return 1.0
    if value < 0:
        return -1.0
    return value  # 0.0, -0.0 or NaN, as np.sign gives them


@njit(cache=True)
def _mod_one(value):
    """np.mod(value, 1.0): in [0, 1), NumPy's own divmod (fmod, moved up by 1 when negative)."""
    remainder = np.fmod(value, 1.0)
    if remainder != 0.0:
        if remainder < 0.0:
            remainder += 1.0
    else:
        remainder = 0.0
    return remainder


@njit(cache=True)
def level_crossings(profiles, offsets, level, order, out):
    """`server.vision.subpixel.level_crossings` into `out` (n,): `order` the sample indices in
    the order of nearness to offset 0 (`np.argsort(np.abs(offsets[:-1]), kind="stable")`)."""
    level = np.float32(level)  # NumPy compares and subtracts a Python float in the profiles' float32
    step = offsets[1] - offsets[0]
    for row in range(profiles.shape[0]):
        out[row] = np.nan
        for j in order:
            if profiles[row, j] >= level and not profiles[row, j + 1] >= level:
                v0, v1 = profiles[row, j], profiles[row, j + 1]
                fraction = (v0 - level) / max(v0 - v1, np.float32(1e-9))
                out[row] = offsets[j] + fraction * step
                break
    return out


@njit(cache=True)
def _lu_solve(matrix, rhs):
    """OpenCV's `hal::LU64f` (`cv2.solve(..., DECOMP_LU)`): Gaussian elimination with partial
    pivoting, in place; False when a pivot is below 100 epsilon (singular)."""
    m = matrix.shape[0]
    eps = 2.220446049250313e-16 * 100
    for i in range(m):
        k = i
        for j in range(i + 1, m):
            if abs(matrix[j, i]) > abs(matrix[k, i]):
                k = j
        if abs(matrix[k, i]) < eps:
            return False
        if k != i:
            for j in range(i, m):
                matrix[i, j], matrix[k, j] = matrix[k, j], matrix[i, j]
            rhs[i], rhs[k] = rhs[k], rhs[i]
        d = -1 / matrix[i, i]
        for j in range(i + 1, m):
            alpha = matrix[j, i] * d
            for k in range(i + 1, m):
                matrix[j, k] += alpha * matrix[i, k]
            rhs[j] += alpha * rhs[i]
    for i in range(m - 1, -1, -1):
        s = rhs[i]
        for k in range(i + 1, m):
            s -= matrix[i, k] * rhs[k]
        rhs[i] = s / matrix[i, i]
    return True


@njit(cache=True)
def fit_lines(points, weights, outward, phase_points, harmonics, min_phase_span_px, min_period_span_px):
    """`server.vision.subpixel._fit_lines` with its pixel-locking refit and offset sigma:
    (lines (4, 3), rms (4,), line sigma, solved). `solved` False: the reference is to be asked,
    for a side of more than `ROW_LIMIT` crossings or equations that are singular (nothing else
    is then to be read)."""
    sides, n = weights.shape
    if n > ROW_LIMIT:
        return np.zeros((sides, 3)), np.zeros(sides), 0.0, False
    weights = weights.copy()
    centres = np.empty((2, sides))
    deltas = np.empty((2, sides, n))
    normal = np.empty((2, sides))
    residuals = np.empty((sides, n))
    row = np.empty(n)
    kept_distances = np.empty(n)
    for _ in range(2):
        for s in range(sides):
            total_weight = _row_sum(weights[s])
            for c in range(2):
                for i in range(n):
                    row[i] = weights[s, i] * points[s, i, c]
                centres[c, s] = _row_sum(row) / total_weight
                for i in range(n):
                    deltas[c, s, i] = points[s, i, c] - centres[c, s]
            for i in range(n):
                row[i] = weights[s, i] * deltas[0, s, i] * deltas[0, s, i]
            sxx = _row_sum(row)
            for i in range(n):
                row[i] = weights[s, i] * deltas[1, s, i] * deltas[1, s, i]
            syy = _row_sum(row)
            for i in range(n):
                row[i] = weights[s, i] * deltas[0, s, i] * deltas[1, s, i]
            sxy = _row_sum(row)
            along = 0.5 * math.atan2(2 * sxy, sxx - syy)
            n0, n1 = -math.sin(along), math.cos(along)
            flip = _sign(n0 * outward[s, 0] + n1 * outward[s, 1])
            normal[0, s], normal[1, s] = n0 * flip, n1 * flip
            kept = 0
            for i in range(n):
                residuals[s, i] = deltas[0, s, i] * normal[0, s] + deltas[1, s, i] * normal[1, s]
                if weights[s, i] > 0:
                    kept_distances[kept] = abs(residuals[s, i])
                    kept += 1
            spread = _kth_smallest(kept_distances[:kept], kept // 2) * 1.4826 if kept > 0 else np.inf
            bound = 3.5 * max(spread, 1e-3)
            for i in range(n):
                weights[s, i] = weights[s, i] * (1.0 if abs(residuals[s, i]) <= bound else 0.0)
    lines = np.empty((sides, 3))
    for s in range(sides):
        lines[s, 0], lines[s, 1] = normal[0, s], normal[1, s]
        lines[s, 2] = -(normal[0, s] * centres[0, s] + normal[1, s] * centres[1, s])
    solved = _remove_pixel_locking(lines, points, weights, phase_points, centres, harmonics, min_phase_span_px,
                                   min_period_span_px, residuals)  # fmt: skip
    if not solved:
        return lines, np.zeros(sides), 0.0, False
    rms = np.empty(sides)
    for s in range(sides):
        for i in range(n):
            row[i] = weights[s, i] * (residuals[s, i] * residuals[s, i])
        rms[s] = math.sqrt(_row_sum(row) / _row_sum(weights[s]))
    return lines, rms, _line_offset_sigma(residuals, weights, rms), True


@njit(cache=True)
def _remove_pixel_locking(lines, points, weights, phase_points, centres, harmonics, min_phase_span_px,
                          min_period_span_px, residuals):  # fmt: skip
    """`server.vision.subpixel._remove_pixel_locking`: `lines` (4, 3) and `residuals` (4, n)
    replaced in place (or left as they are when no side crosses `min_period_span_px`);
    `centres` (2, 4). False when its equations are singular."""
    sides, n = weights.shape
    tangent = np.empty((sides, 2))
    phase = np.empty((sides, n))
    along = np.empty((sides, n))
    spans = np.empty(sides)
    for s in range(sides):
        n0, n1 = lines[s, 0], lines[s, 1]
        tangent[s, 0], tangent[s, 1] = -n1, n0
        axis = 0 if abs(n0) >= abs(n1) else 1
        sign = _sign(lines[s, axis])
        low, high = np.inf, -np.inf
        for i in range(n):
            phase[s, i] = _mod_one(sign * phase_points[s, i, axis])
            o0, o1 = points[s, i, 0] - centres[0, s], points[s, i, 1] - centres[1, s]
            residuals[s, i] = o0 * n0 + o1 * n1
            along[s, i] = o0 * tangent[s, 0] + o1 * tangent[s, 1]
            if weights[s, i] > 0:
                low, high = min(low, along[s, i]), max(high, along[s, i])
        spans[s] = abs(tangent[s, axis]) * (high - low)
    if spans.max() < min_period_span_px:
        return True
    # the design's rows (a small turn and a shift of each side, then the series), each added to the
    # normal equations as it is made
    columns = 8 + 2 * harmonics
    design = np.zeros(columns)
    cosines, sines = np.empty((sides, n, harmonics)), np.empty((sides, n, harmonics))
    normal_matrix = np.zeros((columns, columns))
    rhs = np.zeros(columns)
    for s in range(sides):
        sampled = 1.0 if spans[s] >= min_phase_span_px else 0.0
        for i in range(n):
            design[:8] = 0.0
            design[s] = along[s, i]
            design[4 + s] = 1.0
            turn = 2 * np.pi * phase[s, i]
            for h in range(harmonics):
                angle = turn * float(h + 1)
                cosines[s, i, h], sines[s, i, h] = math.cos(angle), math.sin(angle)
                design[8 + 2 * h] = -cosines[s, i, h] * sampled
                design[9 + 2 * h] = -sines[s, i, h] * sampled
            w = weights[s, i]
            for a in range(columns):
                weighted = design[a] * w
                for b in range(columns):
                    normal_matrix[a, b] += weighted * design[b]
                rhs[a] += weighted * residuals[s, i]
    rhs = -rhs
    solution = rhs.copy()
    if not _lu_solve(normal_matrix.copy(), solution):
        return False
    moments = np.empty((3, sides))
    for s in range(sides):
        moments[0, s], moments[1, s], moments[2, s] = normal_matrix[s + 4, s + 4], normal_matrix[s, s + 4], \
            normal_matrix[s, s]  # fmt: skip
    row_turn, row_shift = np.empty(n), np.empty(n)
    locking = np.empty((sides, n))
    for s in range(sides):
        for i in range(n):
            value = cosines[s, i, 0] * solution[8]
            for h in range(1, harmonics):
                value = _fma(cosines[s, i, h], solution[8 + 2 * h], value)
            term = sines[s, i, 0] * solution[9]
            for h in range(1, harmonics):
                term = _fma(sines[s, i, h], solution[9 + 2 * h], term)
            locking[s, i] = value + term
            target = locking[s, i] - residuals[s, i]
            row_turn[i] = weights[s, i] * along[s, i] * target
            row_shift[i] = weights[s, i] * target
        rhs_turn, rhs_shift = _row_sum(row_turn), _row_sum(row_shift)
        moment_0, moment_1, moment_2 = moments[0, s], moments[1, s], moments[2, s]
        determinant = moment_2 * moment_0 - moment_1**2
        if determinant == 0:  # NaN passes, as in the reference
            return False
        turn = (moment_0 * rhs_turn - moment_1 * rhs_shift) / determinant
        shift = (moment_2 * rhs_shift - moment_1 * rhs_turn) / determinant
        new_0, new_1 = lines[s, 0] + turn * tangent[s, 0], lines[s, 1] + turn * tangent[s, 1]
        scale = math.sqrt(new_0 * new_0 + new_1 * new_1)
        c = lines[s, 2] + shift - turn * (tangent[s, 0] * centres[0, s] + tangent[s, 1] * centres[1, s])
        lines[s, 0], lines[s, 1], lines[s, 2] = new_0 / scale, new_1 / scale, c / scale
        for i in range(n):
            residuals[s, i] = (
                points[s, i, 0] * lines[s, 0] + points[s, i, 1] * lines[s, 1] + lines[s, 2] - locking[s, i]
            )
    return True


@njit(cache=True)
def _line_offset_sigma(residuals, weights, rms):
    """`server.vision.subpixel._line_offset_sigma` with its 8 chunks."""
    chunks = 8
    sides, n = weights.shape
    length = n // chunks
    products = np.empty(n)
    chunk_weights, means = np.empty(chunks), np.empty(chunks)
    total = np.empty(sides)
    for s in range(sides):
        count = _row_sum(weights[s])
        for i in range(n):
            products[i] = weights[s, i] * residuals[s, i]
        for k in range(chunks):
            chunk_weights[k] = _sum(weights[s], k * length, length)
            means[k] = _sum(products, k * length, length) / max(chunk_weights[k], 1.0)
        for k in range(chunks):
            means[k] = chunk_weights[k] * means[k] ** 2
        wave = _row_sum(means) / max(_row_sum(chunk_weights), 1.0)
        wave = max(wave - chunks * rms[s] ** 2 / count, 0.0)
        total[s] = rms[s] ** 2 / count + wave
    return math.sqrt(_row_sum(total) / sides)


@njit(cache=True)
def arc_growth(plane, corners_px, radius_fraction, unit_square, corner_axes):
    """`server.vision.subpixel.contour_growth` from the arc points already in the unit square's
    plane (4, m, 2): the growth (px), NaN where the reference gives None. `unit_square` (4, 2) and
    `corner_axes` (4, 2, 2): `server.vision.subpixel`'s (the axes' entries are 0 and +-1: their
    product is exact in any order)."""
    corners, points = plane.shape[0], plane.shape[1]
    radii = np.empty(corners * points)
    usable = 0
    for k in range(corners):
        for i in range(points):
            d0, d1 = plane[k, i, 0] - unit_square[k, 0], plane[k, i, 1] - unit_square[k, 1]
            x = d0 * corner_axes[k, 0, 0] + d1 * corner_axes[k, 1, 0]
            y = d0 * corner_axes[k, 0, 1] + d1 * corner_axes[k, 1, 1]
            if x > 0 and y > 0:  # NaN compares False
                radii[usable] = x + y + math.sqrt(2 * x * y)
                usable += 1
    if usable < 8:
        return np.nan
    scratch = radii[:usable]
    low, high = _kth_smallest(scratch, (usable - 1) // 2), _kth_smallest(scratch, usable // 2)
    growth_units = ((low + high) / 2 - radius_fraction) / (1.0 - 2.0 * radius_fraction)
    lengths = np.empty(corners)
    for k in range(corners):
        e0 = corners_px[(k + 1) % corners, 0] - corners_px[k, 0]
        e1 = corners_px[(k + 1) % corners, 1] - corners_px[k, 1]
        lengths[k] = math.sqrt(e0 * e0 + e1 * e1)
    return growth_units * (_row_sum(lengths) / corners)


@njit(cache=True)
def _linspace(start, stop, num):
    """`server.vision.subpixel._linspace` (np.linspace's values, num >= 2)."""
    values = np.empty(num)
    step = (stop - start) / (num - 1)
    for i in range(num):
        values[i] = float(i) * step + start
    values[num - 1] = stop
    return values


@njit(cache=True)
def profile_layout(corners, straight_fraction, offsets, width, height, corner_margin, max_profiles_per_side,
                   max_profiles_per_corner, arc_span_deg, min_corner_radius_px):  # fmt: skip
    """`server.vision.subpixel._profile_layout`'s reference (`_outward_normals`, `_side_profiles`,
    `_arc_profiles`, `sample_profiles`' maps and the test of each profile's ends against the ROI
    of `width` x `height`): (directions, normals, lengths, radius_px, bases (n, 2), across (n, 2),
    n_along, n_arc, map_x, map_y (n, m) float32, inside (n,)). No arcs when the radius is under
    `min_corner_radius_px`."""
    directions, normals, lengths = np.empty((4, 2)), np.empty((4, 2)), np.empty(4)
    mean_x = corners[0, 0] + corners[1, 0] + corners[2, 0] + corners[3, 0]
    mean_y = corners[0, 1] + corners[1, 1] + corners[2, 1] + corners[3, 1]
    mean_x, mean_y = mean_x / 4, mean_y / 4
    for s in range(4):
        e = (s + 1) % 4
        d0, d1 = corners[e, 0] - corners[s, 0], corners[e, 1] - corners[s, 1]
        lengths[s] = math.sqrt(d0 * d0 + d1 * d1)
        d0, d1 = d0 / lengths[s], d1 / lengths[s]
        directions[s, 0], directions[s, 1] = d0, d1
        n0, n1 = d1 * 1.0, d0 * -1.0
        mid0, mid1 = (corners[s, 0] + corners[e, 0]) / 2 - mean_x, (corners[s, 1] + corners[e, 1]) / 2 - mean_y
        flip = _sign(n0 * mid0 + n1 * mid1)
        normals[s, 0], normals[s, 1] = n0 * flip, n1 * flip
    radius_fraction = (1.0 - straight_fraction) / 2
    radius_px = radius_fraction * (_row_sum(lengths) / 4)
    n_along = int(min(max(lengths.min() / 2, 12), max_profiles_per_side))
    start = (1.0 - straight_fraction) / 2 + corner_margin
    along = _linspace(start, 1.0 - start, n_along)
    n_arc = 0
    if radius_px >= min_corner_radius_px:
        n_arc = int(min(max(np.pi / 2 * radius_px * arc_span_deg / 90.0, 6), max_profiles_per_corner))
    count = 4 * (n_along + n_arc)
    bases, across = np.empty((count, 2)), np.empty((count, 2))
    for s in range(4):
        for i in range(n_along):
            r = s * n_along + i
            for c in range(2):
                bases[r, c] = corners[s, c] + along[i] * (lengths[s] * directions[s, c])
                across[r, c] = normals[s, c]
    if n_arc:
        half_span = math.radians(arc_span_deg) / 2
        turns = _linspace(-half_span, half_span, n_arc)
        for k in range(4):
            p = (k + 3) % 4
            u0, u1, v0, v1 = directions[k, 0], directions[k, 1], -directions[p, 0], -directions[p, 1]
            centre_0, centre_1 = corners[k, 0] + radius_px * (u0 + v0), corners[k, 1] + radius_px * (u1 + v1)
            for i in range(n_arc):
                t = np.pi / 4 + turns[i]
                cos_t, sin_t = math.cos(t), math.sin(t)
                o0, o1 = -(cos_t * v0 + sin_t * u0), -(cos_t * v1 + sin_t * u1)
                norm = math.sqrt(o0 * o0 + o1 * o1)
                o0, o1 = o0 / norm, o1 / norm
                r = 4 * n_along + k * n_arc + i
                across[r, 0], across[r, 1] = o0, o1
                bases[r, 0], bases[r, 1] = centre_0 + radius_px * o0, centre_1 + radius_px * o1
    samples = offsets.shape[0]
    map_x, map_y = np.empty((count, samples), np.float32), np.empty((count, samples), np.float32)
    inside = np.empty(count, np.bool_)
    right, bottom = np.float32(width - 1), np.float32(height - 1)
    for r in range(count):
        b0, b1 = np.float32(bases[r, 0]), np.float32(bases[r, 1])
        a0, a1 = np.float32(across[r, 0]), np.float32(across[r, 1])
        for j in range(samples):
            map_x[r, j] = b0 + offsets[j] * a0
            map_y[r, j] = b1 + offsets[j] * a1
        inside[r] = True
        for j in (0, samples - 1):
            x, y = b0 + offsets[j] * a0, b1 + offsets[j] * a1
            if not (x >= 0 and x <= right and y >= 0 and y <= bottom):
                inside[r] = False
    return directions, normals, lengths, radius_px, bases, across, n_along, n_arc, map_x, map_y, inside
