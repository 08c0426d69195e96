"""The camera pose from points on whatever part of a panel's outline is in view (beyond the paper).

The corner path needs four corners; a panel cut by the frame border, a rectangle seen at a
steep angle or a round downlight has none to give. Here the pose is fitted to the outline
points of `server.vision.outline` directly:

- model: the panel's exact outline (straight sides and corner arcs, any `Beacon` shape) as a
  signed distance in its own plane. Each point's viewing ray is cut with the ceiling plane
  and its signed distance to the outline there is turned into pixels by the projection's
  scale along the outline's normal: the residual is the point's distance to the projected
  outline, to first order, without projecting a dense outline or searching nearest points.
- growth: the mid-level contour of an overexposed, blurred panel lies outside its outline by
  some D px (`server.vision.subpixel`), less s^2 / (2 R) on the arcs (a blurred curved edge);
  D is a parameter (the arcs and opposite sides tell it from the distance), or known from the
  device's complete panels; so is its gradient across the image (vignetting), with a prior.
- unknowns: yaw, pitch, roll, the camera's 3-D position, D and its gradient; pitch and roll
  are weighed against the gravity vector (sensor sigma), yaw against the heading for a circle
  (nothing else in a circle shows it). Several panels may share one fit (`fit_outlines`).
- starts: tilt from gravity (level without it); in the levelled view the panel's image is a
  similarity of its outline, so the visible straight sides give the yaw (modulo the shape's
  symmetry, settled by the contract's orientation rule), and opposite sides or the panel's
  known size the distance; without any opposite pair, a few distances are tried. The most
  promising start (lowest cost) is fitted first; another one still `hopeless_cost_ratio` times a
  converged start's cost after `scout_evaluations` is left there (not expected to end below it).
- uncertainty: the position's covariance from the fit's information (the points' noise and
  its correlation along the outline measured from the fit's own residuals, a shared offset
  per side or arc, the priors), widened until it explains fits with the growth held low and
  high (growth trades against distance along a curved valley). A fit whose position it does
  not pin down to `max_sigma_m` (the map's `required_sigma_m`) is refused (`pose_uncertain`);
  of one it does, two minima it does not explain are `pose_ambiguous`.
- evaluation: inside the fits, the residuals, their Jacobian and the Huber loss come from
  compiled kernels (`server.pose.outline_kernel`, numba): the NumPy `_Problem.residuals` and
  `.jacobian` here are their reference, equal to them to the last bit on this machine. The
  fits are scipy's `least_squares` (TRF) iteration for iteration, without its wrappers
  (`server.pose.trust_region`, tested equal to it to the last bit).

All image points here are undistorted pixel coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cache, cached_property
from types import ModuleType, SimpleNamespace

import numpy as np

from server.geometry import beacon_rotation, rotation_from_ypr, worst_sigma_2d_m
from server.outcomes import Refusal
from server.pose.trust_region import EPS, RobustLoss, trust_region_fit
from server.vision.subpixel import blur_sigma_px
from shared_schemas import Beacon, FailureReason, OrientationRule

HELD_GROWTH_PX = 1.0  # a typical growth (docs/accuracy.md: 0.5-2 px), only to start from
BEHIND_PX = 1e4  # the residual of a point whose panel is behind the camera


@dataclass(frozen=True)
class OutlineFitRules:
    min_points: int = 40
    max_rms_px: float = 0.8  # the fit's RMS distance (px) of the points to the outline
    max_sigma_m: float = 0.01  # 1-sigma 2-D position error above this: refused (the map's required_sigma_m)
    point_sigma_floor_px: float = 0.02  # what one frame cannot show: lens calibration, quantisation
    # Pixel locking: a level crossing interpolated between pixels is off by up to ~0.1 px as a
    # function of the edge's sub-pixel phase (docs/accuracy.md); along a side near the pixel
    # grid's direction the phase hardly changes, so the whole side shares one such error.
    segment_sigma_px: float = 0.05
    heading_sigma_deg: float = 5.0  # a phone compass, for the yaw of a circle
    # of a growth measured on the device's complete panels: elsewhere in the frame, where the
    # growth differs by up to ~0.5 px (its gradient, below)
    growth_sigma_px: float = 0.3
    # Lenses vignette by 20-50 % towards the corners. The growth of a clipped edge is s z with
    # Phi(-z) = 0.5 / A (blur s, overexposure A), so dD / d ln A = s (0.5 / A) / phi(z): 0.9 px
    # for s = 1.5 px, A = 4; 1.8 px for s = 2, A = 1.6. A 30 % fall over 0.6 units of normalised
    # image coordinate (the frame's half width) is d ln A = 0.36 over it: 0.5-1.1 px per unit.
    # The growth's gradient across a panel is a parameter with this prior sigma.
    growth_gradient_sigma_px: float = 1.0
    huber_px: float = 1.0  # points further than this from the outline count linearly
    distances_m: tuple[float, ...] = (0.8, 1.2, 1.8, 2.7, 4.0)  # starts when nothing gives the distance
    growth_probes_px: tuple[float, ...] = (0.3, 2.5)  # where a second minimum is looked for
    max_evaluations: int = 60  # of one fit's residuals
    # A start is fitted this far first; one still this many times the cost of a fit already
    # converged from another start is left there (a rectangle's start with the sides swapped
    # costs 1e5 times the answer after 60 evaluations): its cost, above the best, cannot win.
    scout_evaluations: int = 30
    hopeless_cost_ratio: float = 10.0
    ambiguous_apart_m: float = 0.005  # two minima further apart than this are two answers ...
    ambiguity_chi2: float = 9.0  # ... unless the worse one's chi-square is this much higher (3 sigma)


@dataclass(frozen=True)
class OutlineFit:
    position_m: np.ndarray  # (3,) camera optical centre, map frame
    rotation_wc: np.ndarray  # (3, 3)
    covariance_m2: np.ndarray  # (3, 3) of position_m
    growth_px: float
    rms_px: float
    point_sigma_px: float  # the points' noise, correlation included
    points: int
    orientation_rule: OrientationRule | None  # None: a circle, whose yaw came from the heading
    # per point, for the shape test (`server.pose.shape`): its signed distance (px) to the fitted outline
    residuals_px: np.ndarray = field(default_factory=lambda: np.zeros(0))
    parameters: int = 9  # the fit's free parameters (pose, growth and its gradient)

    @property
    def sigma_2d_m(self) -> float:
        """The 2-D position's 1-sigma along its worst direction."""
        return worst_sigma_2d_m(self.covariance_m2)


@dataclass(frozen=True)
class _Problem:
    """One fit's fixed inputs: rays (3, N) of the points, the panel each point is on
    (`panel_of`, an index into `panels`), the priors."""

    rays: np.ndarray
    panels: tuple[Beacon, ...]
    panel_of: np.ndarray
    focal_px: tuple[float, float]
    tilt_rad: tuple[float, float] | None  # measured (pitch, roll)
    tilt_sigma_rad: float
    yaw_prior_rad: float | None
    yaw_sigma_rad: float
    growth_prior_px: float | None
    growth_sigma_px: float
    blur_px: float  # the edge's blur: a curved edge's level set lies s^2 / (2 R) inside its offset
    gradient_sigma_px: float  # of the growth's change per unit of normalised image coordinate
    on_arc: np.ndarray | None = None  # (N,) bool: the points on a corner arc, for that term

    @property
    def beacon(self) -> Beacon:
        return self.panels[0]

    @cached_property
    def _spread(self) -> np.ndarray:
        """The points' normalised image coordinates (2, N) about their mean."""
        return self.rays[:2] - self.rays[:2].mean(axis=1, keepdims=True)

    @cached_property
    def _geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per point: its panel's centre (3, N), axes x_B, y_B in the map (3, 2, N), the half
        size of the rectangle of the arcs' centres (2, N) and the arcs' radius (N,); N is 1
        (broadcast, the same arithmetic on fewer numbers) when all points are on one panel."""
        of = self.panel_of if len(self.panels) > 1 else np.zeros(1, int)
        centres = np.array([b.center_m for b in self.panels], float)[of].T
        axes = np.array([beacon_rotation(b)[:, :2] for b in self.panels])[of].transpose(1, 2, 0)
        inner = np.array([[w / 2 - b.outline_radius_m, h / 2 - b.outline_radius_m] for b in self.panels
                          for w, h in [b.extent_m]])[of].T  # fmt: skip
        radius = np.array([b.outline_radius_m for b in self.panels])[of]
        return centres, axes, inner, radius

    def _on_panels(self, batch: np.ndarray):
        """For k parameter vectors (k, 9): each ray's length to its panel's plane (k, N), the
        rotations (k, 3, 3), the points in their panel's axes (k, 2, N), the q of the signed
        distance (k, 2, N): |point| - inner (both > 0 beyond an arc's centre), and the rays in
        the map (k, 3, N)."""
        centres, axes, inner, _ = self._geometry
        rotation = _rotations(batch[:, 0], batch[:, 1], batch[:, 2])  # (k, 3, 3) camera to map
        along = rotation @ self.rays  # (k, 3, N)
        rise = np.where(np.abs(along[:, 2]) > 1e-9, along[:, 2], 1e-9)
        reach = (centres[2] - batch[:, 5, None]) / rise  # ray length to the ceiling plane, in ray units
        offset = batch[:, 3:6, None] + reach[:, None, :] * along - centres[None]
        plane = np.sum(axes[None] * offset[:, :, None, :], axis=1)  # (k, 2, N) in the panel's axes
        return reach, rotation, plane, np.abs(plane) - inner[None], along

    def _terms(self, batch: np.ndarray) -> SimpleNamespace:
        """The distances (k, N) of k parameter vectors (k, 9) and what they are made of, which
        the analytic Jacobian reuses."""
        _, axes, _, radius = self._geometry
        reach, rotation, plane, q, along = self._on_panels(batch)
        qx, qy = q[:, 0], q[:, 1]
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        signed = outside + np.minimum(np.maximum(qx, qy), 0.0) - radius
        # the outline's normal in the plane: radial beyond a corner's centre, else the nearer side's
        corner = (qx > 0) & (qy > 0)
        gx = np.where(corner, np.maximum(qx, 0.0) / np.maximum(outside, 1e-12), (qx >= qy)) * np.sign(plane[:, 0])
        gy = np.where(corner, np.maximum(qy, 0.0) / np.maximum(outside, 1e-12), (qx < qy)) * np.sign(plane[:, 1])
        # ... in the camera frame: R_wc^T R_wb (gx, gy, 0)
        in_map = axes[None, :, 0] * gx[:, None, :] + axes[None, :, 1] * gy[:, None, :]  # (k, 3, N)
        normal = np.matmul(rotation.transpose(0, 2, 1), in_map)
        x, y, z = self.rays[:, None, :] * reach[None]  # the point on the panel, camera frame (3, k, N)
        fx, fy = self.focal_px
        du = fx / z * (normal[:, 0] - x / z * normal[:, 2])
        dv = fy / z * (normal[:, 1] - y / z * normal[:, 2])
        scale = np.hypot(du, dv)  # px per metre across the outline
        # growth varies across the image (vignetting, the lens's blur away from the centre):
        # D + a gradient over the points' spread in normalised image coordinates
        spread = self._spread
        growth = batch[:, 6, None] + batch[:, 7, None] * spread[0] + batch[:, 8, None] * spread[1]
        # (which points lie on an arc is frozen per fit: a point crossing from side to arc would
        # make the term jump, and the Jacobian's differences with it)
        on_arc = corner if self.on_arc is None else self.on_arc
        arc_px = np.where(on_arc, radius * scale + growth, np.inf)
        distances = signed * scale - growth + self.blur_px**2 / (2 * np.maximum(arc_px, 1.0))
        # a panel behind the camera (the ray meets its plane backwards) is no pose it can be seen
        # from: a residual far beyond any real one, finite so that the Jacobian's differences are
        distances = np.where(reach > 0, distances, BEHIND_PX)
        return SimpleNamespace(
            reach=reach, rotation=rotation, along=along, plane=plane, q=q, outside=outside, signed=signed,
            corner=corner, gx=gx, gy=gy, in_map=in_map, normal=normal, x=x, y=y, z=z, du=du, dv=dv, scale=scale,
            on_arc=np.broadcast_to(on_arc, distances.shape), arc_px=arc_px, distances=distances,
        )  # fmt: skip

    def distances_px(self, params: np.ndarray) -> np.ndarray:
        """Signed distance (px, outward positive) of each point to the outline grown by D:
        (N,) for one parameter vector (9,), (k, N) for k of them (k, 9) at once."""
        distances = self._terms(np.atleast_2d(params)).distances
        return distances if np.ndim(params) == 2 else distances[0]

    def segments(self, params: np.ndarray) -> np.ndarray:
        """Which part of which panel's outline (N,) each point lies on at `params`: 8 per panel,
        0-3 its four sides (left, right, bottom, top in its axes), 4-7 its four corner arcs."""
        _, _, plane, q, _ = self._on_panels(params[None])
        (px, py), (qx, qy) = plane[0], q[0]
        side = np.where(qx >= qy, (px > 0).astype(int), 2 + (py > 0))
        arc = 4 + (px > 0) + 2 * (py > 0)
        return np.where((qx > 0) & (qy > 0), arc, side) + 8 * self.panel_of

    def on_arcs(self, params: np.ndarray) -> np.ndarray:
        """Whether each point (N,) lies on one of its panel's corner arcs at `params`."""
        return self.segments(params) % 8 >= 4

    @cached_property
    def _prior_terms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The gravity, heading and growth priors as rows (m,): the parameter each one weighs
        (its column in params), its prior value, its sigma, and whether the difference is an
        angle wrapped to [-pi, pi) (the heading's)."""
        rows = []
        if self.tilt_rad is not None:
            pitch, roll = self.tilt_rad
            rows += [(1, pitch, self.tilt_sigma_rad, False), (2, roll, self.tilt_sigma_rad, False)]
        if self.yaw_prior_rad is not None:
            rows.append((0, self.yaw_prior_rad, self.yaw_sigma_rad, True))
        if self.growth_prior_px is not None:
            rows.append((6, self.growth_prior_px, self.growth_sigma_px, False))
        rows += [(7, 0.0, self.gradient_sigma_px, False), (8, 0.0, self.gradient_sigma_px, False)]
        columns, values, sigmas, wrapped = zip(*rows, strict=True)
        return np.array(columns), np.array(values, float), np.array(sigmas, float), np.array(wrapped)

    def priors(self, params: np.ndarray) -> np.ndarray:
        """The prior residuals, each parameter less its prior in its own sigmas: (m,) or (k, m)."""
        columns, values, sigmas, wrapped = self._prior_terms
        differences = np.atleast_2d(params)[:, columns] - values
        stacked = np.where(wrapped, _wrap(differences), differences) / sigmas
        return stacked if np.ndim(params) == 2 else stacked[0]

    def residuals(self, params: np.ndarray, point_sigma_px: float) -> np.ndarray:
        """Points' distances in their sigma, then the priors: (n,) or (k, n)."""
        return np.concatenate([self.distances_px(params) / point_sigma_px, self.priors(params)], axis=-1)

    def jacobian(self, params: np.ndarray, point_sigma_px: float) -> np.ndarray:
        """d residuals / d params (n, 9) at one parameter vector (9,), by the chain rule through
        `_terms`; `numeric_jacobian` is its reference."""
        t = self._terms(params[None])
        _, axes, _, radius = self._geometry
        rotation, reach, along, plane = t.rotation[0], t.reach[0], t.along[0], t.plane[0]
        # d R_wc / d (yaw, pitch, roll) of R = Rz Ry Rx: Kz R, Rz Ry Ky Rx, R Kx (K: the generators)
        cy, sy, cp, sp, cr, sr = (f(a) for a in params[:3] for f in (math.cos, math.sin))
        rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
        rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
        turns = np.stack([_GENERATORS[2] @ rotation, rz @ ry @ _GENERATORS[1] @ rx, rotation @ _GENERATORS[0]])
        # per pose parameter (yaw, pitch, roll, x, y, z: the first axis, 6) the ray's length to
        # the plane (6, N) and the point's move in the panel's axes (6, 2, N); the position moves
        # the point by itself, less the ray's change of length
        turned = turns @ self.rays  # (3, 3, N) the rays' turn in the map
        grazing = np.abs(along[2]) <= 1e-9  # the rise is held at 1e-9 there: no derivative
        rise = np.where(grazing, 1e-9, along[2])
        d_reach = np.zeros((6, len(reach)))
        d_reach[:3] = -reach / rise * turned[:, 2] * ~grazing
        d_reach[5] = -1.0 / rise
        along_panel = np.sum(axes * along[:, None], axis=0)  # (2, N)
        d_plane = d_reach[:, None] * along_panel
        d_plane[:3] += reach * np.sum(axes * turned[:, :, None], axis=1)
        d_plane[3:] += axes  # (3, 2, N or 1): each map axis in the panel's axes x_B, y_B
        gx, gy, corner, outside = t.gx[0], t.gy[0], t.corner[0], t.outside[0]
        d_signed = gx * d_plane[:, 0] + gy * d_plane[:, 1]
        # the normal turns with the point on an arc: d w = (d q - w (w . d q)) / |q|, w = q / |q|
        sign = np.sign(plane)
        d_q = sign * d_plane
        width = np.maximum(outside, 1e-12)
        w = np.maximum(t.q[0], 0.0) / width
        d_w = (d_q - w * (w[0] * d_q[:, 0] + w[1] * d_q[:, 1])[:, None]) / width
        d_g = d_w * (sign * corner)  # (6, 2, N); zero on the sides
        # ... in the camera frame: d (R^T n_map) = R^T (x_B dgx + y_B dgy) + dR^T n_map
        seen_axes = np.matmul(rotation.T, axes.transpose(2, 0, 1))  # (N or 1, 3, 2)
        d_normal = seen_axes[:, :, 0].T * d_g[:, None, 0] + seen_axes[:, :, 1].T * d_g[:, None, 1]
        d_normal[:3] += turns.transpose(0, 2, 1) @ t.in_map[0]
        x, y, z = t.x[0], t.y[0], t.z[0]
        d_z = d_reach * self.rays[2]
        fx, fy = self.focal_px
        # du = fx (n_x - x / z n_z) / z with x / z the ray's own (no derivative)
        d_du = fx * (d_normal[:, 0] - x / z * d_normal[:, 2]) / z - t.du[0] * d_z / z
        d_dv = fy * (d_normal[:, 1] - y / z * d_normal[:, 2]) / z - t.dv[0] * d_z / z
        scale = t.scale[0]
        d_scale = (t.du[0] * d_du + t.dv[0] * d_dv) / scale
        # the curved edge's term b^2 / (2 (R s + D)) where it is above its floor of 1 px
        bends = t.on_arc[0] & (t.arc_px[0] > 1.0)
        d_arc = np.where(bends, -(self.blur_px**2) / (2 * np.where(bends, t.arc_px[0], 1.0) ** 2), 0.0)
        d_pose = d_signed * scale + (t.signed[0] + d_arc * radius) * d_scale
        d_growth = (d_arc - 1.0) * np.vstack([np.ones_like(scale), self._spread])
        d_distances = np.vstack([d_pose, d_growth]).T * (reach > 0)[:, None]  # (N, 9); behind: held
        return np.vstack([d_distances / point_sigma_px, self._priors_jacobian])

    @cached_property
    def _priors_jacobian(self) -> np.ndarray:
        """d priors / d params (m, 9): each term is one parameter less its prior, in its sigma."""
        columns, _, sigmas, _ = self._prior_terms
        jacobian = np.zeros((len(columns), 9))
        jacobian[np.arange(len(columns)), columns] = 1.0 / sigmas
        return jacobian

    @cached_property
    def _kernel_inputs(self) -> tuple:
        """`outline_kernel.outline_residuals`'s fixed arguments: rays and geometry (contiguous
        float arrays), the spread, focal lengths, blur squared, the frozen arcs and whether they
        are, the priors' rows, the distance of a point behind the camera."""
        frozen = self.on_arc is not None
        on_arc = self.on_arc if self.on_arc is not None else np.zeros(len(self.rays[0]), bool)
        arrays = (self.rays, *self._geometry, self._spread)
        # writable C-ordered copies: the types the kernel was compiled (and warmed) for
        return (*(np.array(a, float, order="C") for a in arrays), *self.focal_px, self.blur_px**2,
                np.array(on_arc, bool), frozen, *self._prior_terms, BEHIND_PX)  # fmt: skip

    def compiled_residuals(
        self, params: np.ndarray, point_sigma_px: float, with_jacobian: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """`residuals` (n,) and, when asked, `jacobian` (n, 9) of one parameter vector (9,) by the
        compiled kernel (`server.pose.outline_kernel`, equal to them); the Jacobian (0, 9) if not."""
        rows, inputs = self._kernel_rows_and_inputs
        values, jacobian = np.empty(rows), np.empty((rows, 9)) if with_jacobian else _NO_JACOBIAN
        point = np.ascontiguousarray(params, float)
        _kernels().outline_residuals(point, *inputs, float(point_sigma_px), values, jacobian)
        return values, jacobian

    @cached_property
    def _kernel_rows_and_inputs(self) -> tuple[int, tuple]:
        """The residuals' count (points and priors) and `_kernel_inputs`: looked up once, not at
        each of a fit's hundred-odd evaluations."""
        return len(self.rays[0]) + len(self._priors_jacobian), self._kernel_inputs

    def numeric_jacobian(self, params: np.ndarray, point_sigma_px: float) -> np.ndarray:
        """d residuals / d params (n, 9), central differences, all eighteen in one batch: the
        reference `jacobian` is tested against."""
        steps = np.diag(_STEPS)
        values = self.residuals(np.vstack([params + steps, params - steps]), point_sigma_px)
        return ((values[:9] - values[9:]) / (2 * _STEPS[:, None])).T


_NO_JACOBIAN = np.empty((0, 9))  # what the kernel is given when only the residuals are asked: it writes none


@cache
def _kernels() -> ModuleType:
    """`server.pose.outline_kernel`, imported at the first fit: numba takes ~0.7 s to import,
    which every command and service start would pay otherwise."""
    from server.pose import outline_kernel

    return outline_kernel


def warm_kernels() -> None:
    """Load the compiled kernels (compile them, on a cold cache: seconds) with a fit's own argument
    types, so that the first fit does not wait for them (`server.api.main` at start-up)."""
    square = Beacon(id=1, center_m=[0.0, 0.0, 1.0], side_m=0.2)
    corners = np.array([[90.0, 90.0], [110.0, 90.0], [110.0, 110.0], [90.0, 110.0]])
    camera = np.array([[100.0, 0.0, 100.0], [0.0, 100.0, 100.0], [0.0, 0.0, 1.0]])
    problem = _problem([(square, corners)], 1.0, camera, None, 1.0, None, None, OutlineFitRules())
    values, jacobian = problem.compiled_residuals(np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]), 0.1, True)
    _kernels().huber_rho(values**2)
    loss = _CompiledHuber(10.0)
    loss(values, cost_only=True)
    loss.scale(jacobian, values, loss(values))


# d R / d angle at 0 about x, y, z: R(a + da) = R(a) (I + da K) for each elemental rotation
_GENERATORS = np.array(
    [[[0, 0, 0], [0, 0, -1], [0, 1, 0]], [[0, 0, 1], [0, 0, 0], [-1, 0, 0]], [[0, -1, 0], [1, 0, 0], [0, 0, 0]]], float
)
_STEPS = np.array([1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-4, 1e-3, 1e-3])  # rad, m, px, px per unit


def _rotations(yaw: np.ndarray, pitch: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """R_wc = Rz(yaw) Ry(pitch) Rx(roll) (`server.geometry.rotation_from_ypr`), radians, (k, 3, 3)."""
    cy, sy, cp, sp, cr, sr = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    rotations = np.empty((len(yaw), 3, 3))  # filled entry by entry: one array, no stacking
    rotations[:, 0, 0], rotations[:, 0, 1], rotations[:, 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    rotations[:, 1, 0], rotations[:, 1, 1], rotations[:, 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    rotations[:, 2, 0], rotations[:, 2, 1], rotations[:, 2, 2] = -sp, cp * sr, cp * cr
    return rotations


def _blur_px(growth_px: float, level_gap_px: float) -> float:
    """The edge's blur from its growth and level gap; 0 (no curvature term) when unmeasured."""
    blur = blur_sigma_px(growth_px, level_gap_px) if math.isfinite(growth_px) else None
    return blur if blur is not None and math.isfinite(blur) else 0.0


def _wrap(angle_rad):
    """An angle (or an array of them) in [-pi, pi)."""
    return (angle_rad + math.pi) % (2 * math.pi) - math.pi


def tilt_from_gravity(gravity_camera: np.ndarray) -> tuple[float, float]:
    """(pitch, roll) in degrees of R_wc = Rz(yaw) Ry(pitch) Rx(roll) from gravity in the camera frame."""
    g = np.asarray(gravity_camera, float)
    g = g / np.linalg.norm(g)
    return math.degrees(math.asin(max(-1.0, min(1.0, g[0])))), math.degrees(math.atan2(-g[1], -g[2]))


def _side_direction_deg(level_xy: np.ndarray, fold: int) -> float:
    """The dominant direction (degrees, modulo 360 / fold) of the tangents along points (N, 2)
    in contour order: straight sides agree on it, arcs spread evenly and cancel."""
    tangent = np.roll(level_xy, -2, axis=0) - np.roll(level_xy, 2, axis=0)
    angle = np.arctan2(tangent[:, 1], tangent[:, 0])
    length = np.linalg.norm(tangent, axis=1)
    # neighbours across a gap (where the frame border cut the outline) give no direction
    ordinary = length < 3 * np.median(length)
    total = np.sum(np.exp(1j * fold * angle[ordinary]))
    return math.degrees(np.angle(total) / fold)


def _extent_start(
    v: np.ndarray, size: tuple[float, float], distances_m: tuple[float, ...]
) -> list[tuple[float, np.ndarray]]:
    """(height above camera, panel-frame camera offset (2,)) starts from levelled points v (N, 2)
    already turned to the panel's axes: opposite sides give the scale, one side the offset."""
    seen = []
    for axis in (0, 1):
        lo, hi = v[:, axis].min(), v[:, axis].max()
        tolerance = 0.02 * (hi - lo)
        # a side of the panel is in view when many points share its extreme coordinate
        seen.append((np.mean(v[:, axis] < lo + tolerance) > 0.08, np.mean(v[:, axis] > hi - tolerance) > 0.08))
    heights = [size[a] / (v[:, a].max() - v[:, a].min()) for a in (0, 1) if all(seen[a])]
    if not heights:
        span = max(np.ptp(v[:, 0]), np.ptp(v[:, 1]), 1e-6)
        heights = [h for h in distances_m if max(size) / h > 0.9 * span] or [max(size) / span]
    starts = []
    for height in heights:
        offset = np.zeros(2)
        for axis in (0, 1):
            low_seen, high_seen = seen[axis]
            if low_seen and not high_seen:
                offset[axis] = -size[axis] / 2 - height * v[:, axis].min()
            elif high_seen and not low_seen:
                offset[axis] = size[axis] / 2 - height * v[:, axis].max()
            else:
                offset[axis] = -height * (v[:, axis].min() + v[:, axis].max()) / 2
        starts.append((height, offset))
    return starts


def _starts(
    problem: _Problem, heading_deg: float | None, distances_m: tuple[float, ...]
) -> list[tuple[np.ndarray, OrientationRule | None]]:
    """Start parameters, each with the orientation rule that chose its yaw (`distances_m`: the
    distances tried when nothing in view gives the scale)."""
    beacon = problem.beacon
    pitch, roll = problem.tilt_rad or (0.0, 0.0)
    level = rotation_from_ypr(0.0, math.degrees(pitch), math.degrees(roll)) @ problem.rays
    level_xy = (level[:2] / level[2]).T  # where the rays meet a plane 1 m above, camera yaw 0
    beacon_yaw = math.radians(beacon.yaw_deg)
    width, height = beacon.extent_m
    if not beacon.has_corners:
        yaws: list[tuple[float, OrientationRule | None]] = [(problem.yaw_prior_rad or 0.0, None)]
    else:
        square = math.isclose(width, height)
        # perpendicular sides agree modulo 90 degrees; arcs spread evenly and cancel
        side = math.radians(_side_direction_deg(level_xy, 4))
        expected = beacon_yaw - math.radians(heading_deg) if heading_deg is not None else 0.0
        rule: OrientationRule | None
        if heading_deg is not None:
            rule = OrientationRule.heading
        else:
            rule = OrientationRule.yaw_within_45deg if square else OrientationRule.yaw_within_90deg
        # the panel's x_B axis appears at angle beacon_yaw - camera_yaw in the levelled view; a
        # square looks the same every quarter turn, a rectangle every half turn, and which of
        # its two side directions is the width the fit tells
        symmetry = math.pi / 2 if square else math.pi
        yaws = []
        for seen in [side] if square else [side, side + math.pi / 2]:
            seen -= symmetry * round((seen - expected) / symmetry)
            yaws.append((_wrap(beacon_yaw - seen), rule))
    starts: list[tuple[np.ndarray, OrientationRule | None]] = []
    for yaw, yaw_rule in yaws:
        to_panel = np.array([[math.cos(yaw - beacon_yaw), -math.sin(yaw - beacon_yaw)],
                             [math.sin(yaw - beacon_yaw), math.cos(yaw - beacon_yaw)]])  # fmt: skip
        v = level_xy @ to_panel.T
        for above, offset in _extent_start(v, (width, height), distances_m):
            offset_map = np.asarray(beacon.center_m[:2]) + beacon_rotation(beacon)[:2, :2] @ offset
            position = [offset_map[0], offset_map[1], beacon.center_m[2] - above]
            growth = problem.growth_prior_px if problem.growth_prior_px is not None else HELD_GROWTH_PX
            starts.append((np.array([yaw, pitch, roll, *position, growth, 0.0, 0.0]), yaw_rule))
    return starts


def _as_the_rule_expects(params: np.ndarray, beacon: Beacon, heading_deg: float | None) -> np.ndarray:
    """The pose among the panel's symmetric copies that the orientation rule expects.

    A rectangle looks the same turned by half a turn about its centre, a square by a quarter:
    a fit may end in any copy (from a start with the width along the other side, say). The
    copy turned by k * symmetry about the panel's vertical axis has the camera's yaw + k *
    symmetry and its position turned likewise about the panel's centre; the rule (heading, or
    the camera's yaw within half the symmetry of the beacon's) picks k.
    """
    width, height = beacon.extent_m
    if not beacon.has_corners:
        return params
    symmetry = math.pi / 2 if math.isclose(width, height) else math.pi
    expected = math.radians(beacon.yaw_deg - heading_deg) if heading_deg is not None else 0.0
    seen = math.radians(beacon.yaw_deg) - params[0]
    turn = symmetry * round(_wrap(seen - expected) / symmetry)
    if turn == 0:
        return params
    centre = np.asarray(beacon.center_m[:2], float)
    cos, sin = math.cos(turn), math.sin(turn)
    offset = params[3:5] - centre
    turned = params.copy()
    turned[0] = _wrap(params[0] + turn)
    turned[3:5] = centre + [cos * offset[0] - sin * offset[1], sin * offset[0] + cos * offset[1]]
    return turned


def _held(problem: _Problem) -> _Problem:
    """The problem for a first fit: without a known growth, the growth held near a typical one
    (far from the answer, a free growth can run off and trade itself for distance)."""
    if problem.growth_prior_px is not None:
        return problem
    return replace(problem, growth_prior_px=HELD_GROWTH_PX, growth_sigma_px=0.3)


def _from_first_fit(problem: _Problem, params: np.ndarray, level_gap_px: float) -> _Problem:
    """The problem with the blur and the points on arcs taken at a first fit's `params`."""
    return replace(problem, blur_px=_blur_px(params[6], level_gap_px), on_arc=problem.on_arcs(params))


def _fit(
    problem: _Problem,
    start: np.ndarray,
    point_sigma_px: float,
    huber_px: float,
    max_evaluations: int,
    scout: tuple[int, Callable[[float], bool]] | None = None,
) -> SimpleNamespace:
    """The robust least-squares fit from `start` (x, cost, status: 0 when `max_evaluations`
    stopped it); cost infinite when the start itself is not a pose the residuals exist for (the
    panel's plane behind or edge-on to a ray). scipy's `least_squares` (TRF, its huber loss
    compiled) by `server.pose.trust_region`, the same iterates without its wrappers. With `scout`
    (evaluations, carry_on): the fit to that many evaluations, and on to `max_evaluations` where
    `carry_on(its cost)` says so (`trust_region_fit`'s pause: the same as fitting again)."""
    failed = SimpleNamespace(x=start, cost=math.inf, status=-1)
    residuals = problem.compiled_residuals(start, point_sigma_px)[0]
    if not np.all(np.isfinite(residuals)):
        return failed
    try:
        return trust_region_fit(
            lambda params: problem.compiled_residuals(params, point_sigma_px)[0],
            lambda params: problem.compiled_residuals(params, point_sigma_px, with_jacobian=True)[1],
            start,
            residuals,
            _CompiledHuber(huber_px / point_sigma_px),
            x_scale=_X_SCALE,
            max_nfev=max_evaluations,
            pause_nfev=None if scout is None else scout[0],
            carry_on=(lambda cost: True) if scout is None else scout[1],
        )
    except ValueError as error:
        # scipy's own check: the residuals or their Jacobian stopped being finite on the way
        # (a ray grazing the panel's plane); this start gives no fit
        if "finite" not in str(error) and "infs or NaNs" not in str(error):
            raise
        return failed


class _CompiledHuber(RobustLoss):
    """`RobustLoss` of scipy's "huber" at `f_scale`, by the compiled kernels (`huber_terms`,
    `scale_for_robust_loss`: the same operations point by point, one call instead of ten)."""

    def __init__(self, f_scale: float):
        super().__init__(_kernels().huber_rho, f_scale)
        self.f_scale_sq = f_scale**2

    def __call__(self, f: np.ndarray, cost_only: bool = False):
        rho = _kernels().huber_terms(f, self.f_scale, self.f_scale_sq, cost_only)
        return 0.5 * self.f_scale_sq * np.add.reduce(rho[0]) if cost_only else rho  # np.sum

    def scale(self, J: np.ndarray, f: np.ndarray, rho: np.ndarray) -> None:
        _kernels().scale_for_robust_loss(J, f, rho, EPS)


_X_SCALE = np.array([0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.5, 1.0, 1.0])  # rad, m, px, px per unit


def _fit_starts(
    problem: _Problem, starts: list[np.ndarray], point_sigma_px: float, rules: OutlineFitRules
) -> list[SimpleNamespace]:
    """The fits from `starts`, in their order: the most promising (lowest cost) fitted first, each
    other to `scout_evaluations`, and on to the end (again from its start: the same fit as
    without the scouting) unless it converged there or is hopeless against the best so far."""
    huber = rules.huber_px
    fits: list[SimpleNamespace | None] = [None] * len(starts)
    best = math.inf
    for index in sorted(range(len(starts)), key=lambda i: _robust_chi2(problem, starts[i], point_sigma_px, huber)):
        scout = (rules.scout_evaluations, lambda cost, best=best: not cost > rules.hopeless_cost_ratio * best)
        fit = _fit(problem, starts[index], point_sigma_px, huber, rules.max_evaluations,
                   scout if math.isfinite(best) else None)  # fmt: skip
        if fit.status != 0:
            best = min(best, fit.cost)  # converged: what a left start's cost is held against
        fits[index] = fit
    return [fit for fit in fits if fit is not None]


def _robust_chi2(problem: _Problem, params: np.ndarray, point_sigma_px: float, huber_px: float) -> float:
    """Twice the fit's cost (Huber beyond `huber_px`) in the points' sigma: comparable between minima."""
    residuals = problem.compiled_residuals(params, point_sigma_px)[0]
    if not np.all(np.isfinite(residuals)):
        return math.inf
    limit = huber_px / point_sigma_px
    size = np.abs(residuals)
    return float(np.sum(np.where(size <= limit, size**2, 2 * limit * size - limit**2)))


def _explain_probes(
    problem: _Problem,
    best: np.ndarray,
    probes: list[np.ndarray],
    covariance_m2: np.ndarray,
    sigma_px: float,
    huber_px: float,
) -> np.ndarray:
    """The position's covariance widened until it explains the probes (fits with the growth
    held elsewhere): a probe that moves the position by d at a chi-square cost c says the
    variance along d is at least |d|^2 / c. Where growth trades against distance along a
    curved valley the linear covariance at the minimum does not see how far the valley goes."""
    chi2 = _robust_chi2(problem, best, sigma_px, huber_px)
    for probe in probes:
        moved = probe[3:6] - best[3:6]
        cost = max(_robust_chi2(problem, probe, sigma_px, huber_px) - chi2, 1.0)
        if moved @ np.linalg.solve(covariance_m2, moved) > cost:
            covariance_m2 = covariance_m2 + np.outer(moved, moved) / cost
    return covariance_m2


def _noise_px(distances: np.ndarray, floor_px: float) -> float:
    """The points' noise as one sigma per independent point: robust spread, times the
    square root of how many neighbours along the outline share an error (lag-one correlation
    of the residuals in contour order, as an AR(1) process's variance inflation)."""
    centred = distances - np.median(distances)
    spread = 1.4826 * float(np.median(np.abs(centred)))
    if len(centred) > 3 and np.var(centred) > 0:
        rho = float(np.clip(np.corrcoef(centred[:-1], centred[1:])[0, 1], 0.0, 0.96))
    else:
        rho = 0.0
    return max(spread, floor_px) * math.sqrt((1 + rho) / (1 - rho))


def _covariance(
    problem: _Problem, params: np.ndarray, point_sigma_px: float, segment_sigma_px: float
) -> np.ndarray | None:
    """The parameters' covariance (9, 9) from the residuals' Jacobian, with the points' errors
    white (`point_sigma_px`) plus one shared offset per side or arc (`segment_sigma_px`): the
    information J^T Sigma^-1 J, Sigma's inverse per part by the Sherman-Morrison formula."""
    jacobian = problem.compiled_residuals(params, point_sigma_px, with_jacobian=True)[1]  # rows in point sigmas
    points = len(problem.rays[0])
    information = jacobian.T @ jacobian
    share = (segment_sigma_px / point_sigma_px) ** 2
    parts = problem.segments(params)
    for part in np.unique(parts):
        rows = jacobian[:points][parts == part]
        total = rows.sum(axis=0)
        information -= share / (1.0 + share * len(rows)) * np.outer(total, total)
    if not np.all(np.isfinite(information)) or np.linalg.cond(information) > 1e14:
        return None
    covariance = np.linalg.inv(information)
    covariance = (covariance + covariance.T) / 2
    return covariance if np.all(np.diag(covariance) > 0) else None


def _problem(
    panels: list[tuple[Beacon, np.ndarray]],
    level_gap_px: float,
    camera_matrix: np.ndarray,
    gravity_camera: np.ndarray | None,
    gravity_sigma_deg: float,
    yaw_prior_deg: float | None,
    growth_px: float | None,
    rules: OutlineFitRules,
) -> _Problem:
    points = np.vstack([p for _, p in panels])
    tilt = None
    if gravity_camera is not None:
        pitch, roll = tilt_from_gravity(gravity_camera)
        tilt = (math.radians(pitch), math.radians(roll))
    return _Problem(
        rays=np.linalg.solve(camera_matrix, np.vstack([points.T, np.ones(len(points))])),
        panels=tuple(b for b, _ in panels),
        panel_of=np.concatenate([np.full(len(p), k) for k, (_, p) in enumerate(panels)]),
        focal_px=(float(camera_matrix[0, 0]), float(camera_matrix[1, 1])),
        tilt_rad=tilt,
        tilt_sigma_rad=math.radians(max(gravity_sigma_deg, 1e-3)),
        yaw_prior_rad=None if yaw_prior_deg is None else math.radians(yaw_prior_deg),
        yaw_sigma_rad=math.radians(rules.heading_sigma_deg),
        growth_prior_px=growth_px,
        growth_sigma_px=rules.growth_sigma_px,
        gradient_sigma_px=rules.growth_gradient_sigma_px,
        blur_px=_blur_px(HELD_GROWTH_PX if growth_px is None else growth_px, level_gap_px),
    )


def fit_outline(
    points_px: np.ndarray,
    level_gap_px: float,
    beacon: Beacon,
    camera_matrix: np.ndarray,
    gravity_camera: np.ndarray | None,
    gravity_sigma_deg: float,
    heading_deg: float | None,
    growth_px: float | None = None,
    rules: OutlineFitRules = OutlineFitRules(),
) -> OutlineFit | Refusal:
    """Camera pose from undistorted points (N, 2) on the visible outline of map beacon `beacon`."""
    if len(points_px) < rules.min_points:
        return Refusal(FailureReason.beacon_cut_off, f"only {len(points_px)} points of the panel's outline in view")
    if not beacon.has_corners and heading_deg is None:
        return Refusal(
            FailureReason.pose_failed,
            "a round panel shows no yaw: the frame needs heading_deg (or a second panel in view)",
        )
    yaw_prior = None if beacon.has_corners else heading_deg
    problem = _problem(
        [(beacon, points_px)],
        level_gap_px,
        camera_matrix,
        gravity_camera,
        gravity_sigma_deg,
        yaw_prior,
        growth_px,
        rules,
    )
    sigma = 0.1  # a first guess of the points' noise; measured from the residuals below
    # first with the growth held (`_held`), then free
    held = _held(problem)
    starts = _starts(problem, heading_deg, rules.distances_m)
    fits = zip(
        _fit_starts(held, [start for start, _ in starts], sigma, rules), [rule for _, rule in starts], strict=True
    )
    first, rule = min(fits, key=lambda item: item[0].cost)
    if not math.isfinite(first.cost):
        return Refusal(FailureReason.pose_failed, "no start pose puts the panel's outline in front of the camera")
    problem = _from_first_fit(problem, first.x, level_gap_px)
    fitting = (rules.huber_px, rules.max_evaluations)
    seeds = [first.x]
    if growth_px is None:
        # Growth trades against distance where no opposite sides are in view, and the trade
        # can make a second minimum: look for it from the growth held low and high.
        for probe in rules.growth_probes_px:
            probed = replace(problem, growth_prior_px=probe, growth_sigma_px=0.3)
            seeds.append(_fit(probed, np.concatenate([first.x[:6], [probe], first.x[7:]]), sigma, *fitting).x)
    minima = [_as_the_rule_expects(_fit(problem, seed, sigma, *fitting).x, beacon, heading_deg) for seed in seeds]
    best = min(minima, key=lambda x: _robust_chi2(problem, x, sigma, rules.huber_px))
    probes = [_as_the_rule_expects(seed, beacon, heading_deg) for seed in seeds]
    return _finish(
        problem, best, sigma, probes, minima, rule, lambda x: _as_the_rule_expects(x, beacon, heading_deg), rules
    )


def fit_outlines(
    panels: list[tuple[Beacon, np.ndarray]],
    level_gap_px: float,
    camera_matrix: np.ndarray,
    gravity_camera: np.ndarray | None,
    gravity_sigma_deg: float,
    start_position_m: np.ndarray,
    start_yaw_deg: float,
    growth_px: float | None,
    rules: OutlineFitRules = OutlineFitRules(),
) -> OutlineFit | Refusal:
    """Camera pose from the visible outlines of several map panels at once, each with its
    undistorted points (N_i, 2), from a start (a device's track): two panels cut by the frame
    border pin down together what neither does alone (their distance apart is the scale)."""
    panels = [(b, p) for b, p in panels if len(p) > 0]
    count = sum(len(p) for _, p in panels)
    if count < rules.min_points:
        return Refusal(FailureReason.beacon_cut_off, f"only {count} points of the panels' outlines in view")
    problem = _problem(panels, level_gap_px, camera_matrix, gravity_camera, gravity_sigma_deg, None, growth_px, rules)
    pitch, roll = problem.tilt_rad or (0.0, 0.0)
    growth = HELD_GROWTH_PX if growth_px is None else growth_px
    start = np.array([math.radians(start_yaw_deg), pitch, roll, *start_position_m, growth, 0.0, 0.0])
    sigma = 0.1
    first = _fit(_held(problem), start, sigma, rules.huber_px, rules.max_evaluations)
    if not math.isfinite(first.cost):
        return Refusal(FailureReason.pose_failed, "the track's pose puts the panels' outlines behind the camera")
    problem = _from_first_fit(problem, first.x, level_gap_px)
    best = _fit(problem, first.x, sigma, rules.huber_px, rules.max_evaluations).x
    return _finish(problem, best, sigma, [first.x], [best], None, lambda x: x, rules)


def _finish(
    problem: _Problem,
    best: np.ndarray,
    sigma: float,
    probes: list[np.ndarray],
    minima: list[np.ndarray],
    rule: OrientationRule | None,
    as_expected: Callable[[np.ndarray], np.ndarray],
    rules: OutlineFitRules,
) -> OutlineFit | Refusal:
    """The fit refined with its measured noise, checked, with its covariance; or why it is no fix."""
    if not math.isfinite(_robust_chi2(problem, best, sigma, rules.huber_px)):
        return Refusal(FailureReason.pose_failed, "the outline fit left the poses the panel can be seen from")
    problem = replace(problem, on_arc=problem.on_arcs(best))
    measured = _noise_px(problem.distances_px(best), rules.point_sigma_floor_px)
    if not math.isclose(measured, sigma, rel_tol=0.5):
        best = _fit(
            problem, best, measured, rules.huber_px, rules.max_evaluations
        ).x  # the priors' weight against the points depends on it
    best = as_expected(best)
    distances = problem.distances_px(best)
    rms = float(np.sqrt(np.mean(distances**2)))
    if rms > rules.max_rms_px or not np.all(np.isfinite(best)):
        return Refusal(
            FailureReason.beacon_cut_off, f"the visible edges do not fit the panel's outline (RMS {rms:.2f} px)"
        )
    chi2 = _robust_chi2(problem, best, measured, rules.huber_px)
    covariance = _covariance(problem, best, measured, rules.segment_sigma_px)
    if covariance is None:
        return Refusal(FailureReason.beacon_cut_off, "the visible part of the panel does not fix the position")
    position_covariance = _explain_probes(problem, best, probes, covariance[3:6, 3:6], measured, rules.huber_px)
    fit = OutlineFit(
        position_m=best[3:6].copy(),
        rotation_wc=rotation_from_ypr(*np.degrees(best[:3])),
        covariance_m2=position_covariance,
        growth_px=float(best[6]),
        rms_px=rms,
        point_sigma_px=measured,
        points=len(distances),
        orientation_rule=rule,
        residuals_px=distances,
    )
    # Uncertain before ambiguous: a second answer matters only where the best one alone would be a fix.
    # Where the best one is not pinned down, where along its flat valley the other fits stopped (the
    # optimiser's last digits) would otherwise decide which of the two is said.
    if fit.sigma_2d_m > rules.max_sigma_m:
        return Refusal(
            FailureReason.pose_uncertain,
            f"the visible part of the panel ({len(distances)} outline points) fixes the position only to "
            f"{fit.sigma_2d_m * 1000:.0f} mm (1 sigma); the map's required_sigma_m is "
            f"{rules.max_sigma_m * 1000:.3g} mm",
        )
    for other in minima:
        moved = other[3:6] - best[3:6]
        apart = float(np.linalg.norm(moved))
        gap = _robust_chi2(problem, other, measured, rules.huber_px) - chi2
        # a second answer: far, about as good, and not within the first one's own uncertainty
        # (along a flat valley the fits stop anywhere; the covariance already says how flat)
        unexplained = moved @ np.linalg.solve(position_covariance, moved) > rules.ambiguity_chi2
        if apart > rules.ambiguous_apart_m and gap < rules.ambiguity_chi2 and unexplained:
            return Refusal(
                FailureReason.pose_ambiguous,
                f"two poses {apart * 1000:.0f} mm apart fit the visible part of the panel almost equally "
                f"(chi-square {chi2:.0f} and {chi2 + gap:.0f})",
            )
    return fit
