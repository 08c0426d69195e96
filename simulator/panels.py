"""Real panels (issue 13): what a photo of an LED ceiling panel shows besides its luminous area.

The map's outline (`shared_schemas.Beacon`: sides, corner radius) is the panel's LUMINOUS area, the
outline the pipeline must find. A real panel adds, as knobs of `PanelSpec` (docs/simulator.md, "Real
panels", gives the physical reasoning for each value):

- a **bezel**: the frame (white-painted or bare aluminium, 8-15 mm) around the luminous area, whose
  luminance is the light it reflects (the room's, most of it the panels' own);
- **edge fall-off**: an edge-lit diffuser is darker towards its edges;
- a **glossy ceiling**: a sheen on the ceiling around the panel, falling off with the distance from
  its outer edge.

A second lamp or a window in view is a `simulator.scene.LightSourceSpec`. Every knob is off by
default (existing scenes and benches render byte-identical frames); `PanelSpec.typical()` gives the
documented values, as `simulator.chain.IspSpec.phone()` does for the ISP.

`panel_emitters` is the one place that turns a beacon and its `PanelSpec` into the renderer's
emitters: nested outlines (the exact offsets of the map's shapes, `offset_beacon`) each projected by
the caller and drawn with the renderer's exact coverage; a profile is drawn as bands between them,
each band at the profile's level at its middle.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal

import numpy as np
from pydantic import Field

from shared_schemas import Beacon, PanelShape
from shared_schemas.models import Strict
from simulator.render import Emitter

SeenOutline = tuple[np.ndarray, tuple[np.ndarray, ...]]  # an outline, and at the exposure's instants (render.exposure_polygons_px)

TYPICAL_BEZEL_WIDTH_M = 0.010  # recessed / surface LED panels: an 8-15 mm aluminium frame
BEZEL_FRACTIONS = {"white": 0.03, "metal": 0.015}  # luminance / the panel's centre's (docs: reasoned, not measured)
TYPICAL_EDGE_RATIO = 0.8  # GT004-2012: luminance uniformity (min / mean) of an LED flat panel >= 0.8
TYPICAL_FALLOFF_WIDTH_M = 0.03
GLOSSY_SHEEN_FRACTION = 0.02  # half a gloss finish's ~4 % Fresnel reflectance (n = 1.5) at the panel's edge
GLOSSY_SHEEN_LENGTH_M = 0.03
FALLOFF_BANDS = 8  # steps of the edge fall-off: (1 - edge ratio) / 8 each, ~2.5 % of the level at 0.8
SHEEN_BANDS = 8  # of half a sheen length each: out to 4 lengths (e^-4 = 2 % of the edge's sheen)


class PanelSpec(Strict):
    """What a real panel shows around and across its luminous area; every knob off by default."""

    bezel_width_m: float = Field(default=0.0, ge=0, description="the frame around the luminous area; 0 = none")
    bezel_fraction: float = Field(default=0.0, ge=0, le=1, description="the frame's luminance / the panel's centre's")
    edge_ratio: float = Field(default=1.0, gt=0, le=1,
                              description="the luminous area's luminance at its edge / at its centre; 1 = flat")
    falloff_width_m: float = Field(default=TYPICAL_FALLOFF_WIDTH_M, gt=0,
                                   description="depth from the edge over which the luminance climbs to the centre's")
    sheen_fraction: float = Field(default=0.0, ge=0, le=1,
                                  description="glossy ceiling: its luminance at the panel's outer edge / the panel's")
    sheen_length_m: float = Field(default=GLOSSY_SHEEN_LENGTH_M, gt=0, description="the sheen's e-folding distance")

    @classmethod
    def typical(cls, bezel: Literal["white", "metal"] = "white", glossy_ceiling: bool = False) -> PanelSpec:
        """A commercial edge-lit panel: a 10 mm frame, 80 % at the edge; a matte ceiling unless `glossy_ceiling`."""
        return cls(bezel_width_m=TYPICAL_BEZEL_WIDTH_M, bezel_fraction=BEZEL_FRACTIONS[bezel],
                   edge_ratio=TYPICAL_EDGE_RATIO, falloff_width_m=TYPICAL_FALLOFF_WIDTH_M,
                   sheen_fraction=GLOSSY_SHEEN_FRACTION if glossy_ceiling else 0.0,
                   sheen_length_m=GLOSSY_SHEEN_LENGTH_M)

    def only(self, effect: Literal["bezel", "falloff", "sheen"]) -> PanelSpec:
        """This spec with every other effect off (one effect at a time, as the robustness bench runs them)."""
        keep = {"bezel": ("bezel_width_m", "bezel_fraction"), "falloff": ("edge_ratio", "falloff_width_m"),
                "sheen": ("sheen_fraction", "sheen_length_m")}[effect]
        return PanelSpec(**{name: getattr(self, name) for name in keep})


def edge_profile(panel: PanelSpec, depth_m: float) -> float:
    """The luminous area's luminance / its centre's at `depth_m` inside its edge: `edge_ratio` at the
    edge, rising as 1 - (1 - ratio) (1 - depth / width)^2 to 1 at `falloff_width_m`, flat beyond."""
    t = min(max(depth_m / panel.falloff_width_m, 0.0), 1.0)
    return 1.0 - (1.0 - panel.edge_ratio) * (1.0 - t) ** 2


def sheen_profile(panel: PanelSpec, distance_m: float) -> float:
    """The glossy ceiling's luminance / the panel's at `distance_m` outside the panel's outer edge (the bezel's)."""
    return panel.sheen_fraction * math.exp(-max(distance_m, 0.0) / panel.sheen_length_m)


def panel_bands(panel: PanelSpec, half_size_m: float) -> list[tuple[float, float]]:
    """(offset m, luminance / the panel's centre's), outermost first.

    Band k is the area between the outline offset by offset_k (outward positive) and the one offset
    by offset_{k+1}; the last band is the whole innermost outline. Insets that leave nothing of a
    panel `half_size_m` across its half are dropped. Without effects: [(0, 1)], the bare panel.
    """
    bands = []
    if panel.sheen_fraction > 0:
        step = panel.sheen_length_m / 2
        bands += [(panel.bezel_width_m + (j + 1) * step, sheen_profile(panel, (j + 0.5) * step))
                  for j in reversed(range(SHEEN_BANDS))]
    if panel.bezel_width_m > 0:
        bands.append((panel.bezel_width_m, panel.bezel_fraction))
    if panel.edge_ratio < 1:
        step = panel.falloff_width_m / FALLOFF_BANDS
        inside = [(-k * step, edge_profile(panel, (k + 0.5) * step)) for k in range(FALLOFF_BANDS)] + [
            (-panel.falloff_width_m, 1.0)]
        bands += [(offset, level) for offset, level in inside if -offset < half_size_m]
    else:
        bands.append((0.0, 1.0))
    return bands


def offset_beacon(beacon: Beacon, offset_m: float) -> Beacon:
    """`beacon` with its outline moved outward by `offset_m` (inward when negative); exact for the map's
    shapes: a rounded rectangle's sides grow by 2 offset and its corner radius by offset (not below 0),
    a circle's diameter by 2 offset. Not validated: an inset may be smaller than a map's panel may be."""
    if offset_m == 0:
        return beacon
    if beacon.shape is PanelShape.circle:
        return beacon.model_copy(update={"diameter_m": beacon.extent_m[0] + 2 * offset_m})
    sizes = {name: getattr(beacon, name) + 2 * offset_m for name in ("side_m", "width_m", "height_m")
             if getattr(beacon, name) is not None}
    return beacon.model_copy(update={**sizes, "corner_radius_m": max(beacon.corner_radius_m + offset_m, 0.0)})


def ring(outer_px: np.ndarray, inner_px: np.ndarray) -> np.ndarray:
    """One closed polygon for the area between two nested outlines of the same orientation: the outer one,
    then the inner one backwards, joined by a bridge drawn both ways (its crossings cancel, so the
    renderer's coverage is the outer's minus the inner's, exactly)."""
    return np.vstack([outer_px, outer_px[:1], inner_px[::-1], inner_px[-1:]])


def panel_emitters(beacon: Beacon, panel: PanelSpec | None, outline_px: Callable[[Beacon], SeenOutline | None],
                   level_dn: float, row_gain: np.ndarray | None = None, defocus_px: float = 0.0) -> list[Emitter]:
    """The renderer's emitters for `beacon` as `panel` draws it (none: the bare luminous area, one emitter).

    `outline_px` projects a beacon's outline into the frame's pixels as `render.exposure_polygons_px`
    does (None: not in view; with the outline at the exposure's instants when the camera moves);
    `level_dn` is the luminous area's centre. The bezel and the sheen are the panel's light
    reflected, so they carry its `row_gain` (a coded panel's bezel blinks with it) and its `defocus_px`.
    """
    bands = panel_bands(panel or PanelSpec(), min(beacon.extent_m) / 2)
    seen = [outline_px(offset_beacon(beacon, offset)) for offset, _ in bands] + [None]
    if len(bands) > 1 and any(s is not None and s[1] for s in seen):
        raise ValueError("a panel's bezel, fall-off or sheen is not drawn for a moving camera yet (simulator.panels)")
    emitters = []
    for (_, share), outer, inner in zip(bands, seen[:-1], seen[1:], strict=True):
        if outer is None or share == 0:
            continue
        polygon = outer[0] if inner is None else ring(outer[0], inner[0])
        emitters.append(Emitter(polygon, share * level_dn, row_gain, defocus_px=defocus_px,
                                exposure_outlines_px=outer[1] if inner is None else ()))
    return emitters
