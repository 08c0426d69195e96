"""Draw docs/figures/measuring-a-panel.png: how to measure a panel's side_m and corner_radius_m.

`python scripts/figure_measuring_a_panel.py [OUT.png]` (matplotlib). Left: the panel from below, a tape across
the lit area edge to edge (side_m). Right: one corner close up, a ruler laid along a side: the straight edge leaves
the ruler at the radius from where the two sides, extended, cross (corner_radius_m); a coin of that radius laid
in the corner touches both sides and follows the arc.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import Circle, FancyBboxPatch, Rectangle

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures" / "measuring-a-panel.png"
SIDE_M, RADIUS_M = 0.6, 0.02
LIT, FRAME, TAPE = "#fff6c8", "#9a9a9a", "#e8b400"


def draw(out: Path) -> None:
    figure, (whole, corner) = plt.subplots(1, 2, figsize=(10, 4.6), gridspec_kw={"width_ratios": [1.15, 1]})
    half = SIDE_M / 2
    # the panel from below: a frame around the lit area, whose outline the map describes
    whole.add_patch(Rectangle((-half - 0.03, -half - 0.03), SIDE_M + 0.06, SIDE_M + 0.06, color=FRAME))
    whole.add_patch(FancyBboxPatch((-half + RADIUS_M, -half + RADIUS_M), SIDE_M - 2 * RADIUS_M,
                                   SIDE_M - 2 * RADIUS_M, boxstyle=f"round,pad={RADIUS_M}", color=LIT, ec="k", lw=1))
    whole.add_patch(Rectangle((-half, -0.02), SIDE_M, 0.04, color=TAPE, alpha=0.9))
    for tick in range(0, 61, 5):
        x = -half + tick / 100
        whole.plot([x, x], [-0.02, -0.005 if tick % 10 else 0.005], color="k", lw=0.8)
    whole.annotate("", (-half, 0.07), (half, 0.07), arrowprops={"arrowstyle": "<->", "lw": 1.2})
    whole.text(0, 0.09, "side_m: the lit area, edge to edge\n(not the frame around it)", ha="center", va="bottom")
    whole.text(0, -0.06, "a tape across the middle, parallel to a side", ha="center", va="top", fontsize=9)
    whole.add_patch(Rectangle((half - 0.12, half - 0.12), 0.12, 0.12, fill=False, ls="--", ec="C0"))
    whole.set_title("1. The side: measure the light, not the frame")
    whole.set_xlim(-0.4, 0.4), whole.set_ylim(-0.4, 0.4)

    # one corner close up (mm): sides along x = 0 and y = 0 extended cross at the origin
    r = RADIUS_M * 1000
    corner.add_patch(FancyBboxPatch((-150 + r, -150 + r), 150 - 2 * r, 150 - 2 * r,
                                    boxstyle=f"round,pad={r}", color=LIT, ec="k", lw=1.2))
    corner.add_patch(Rectangle((-85, 0), 85, 7, color=TAPE, alpha=0.9))  # a ruler along the top side
    for tick in range(0, 86, 5):
        corner.plot([-tick, -tick], [0, 3 if tick % 10 else 5], color="k", lw=0.8)
    corner.plot([0, 0], [-30, 12], color="k", ls=":", lw=1), corner.plot([-30, 12], [0, 0], color="k", ls=":", lw=1)
    corner.annotate("", (-r, 10), (0, 10), arrowprops={"arrowstyle": "<->", "lw": 1.2})
    corner.text(-r / 2, 12, "corner_radius_m", ha="center", va="bottom")
    corner.plot([-r], [0], "o", color="C0")
    corner.text(-r - 2, -3, "the edge leaves\nthe ruler here", ha="right", va="top", fontsize=9)
    corner.text(2, 2, "the sides, extended,\ncross here", ha="left", va="bottom", fontsize=9)
    corner.add_patch(Circle((-r, -r), r, fill=False, ec="C3", lw=1.5, ls="--"))
    corner.text(-r, -2.2 * r, f"or a coin of radius {r:.0f} mm in the corner\ntouches both sides and the arc",
                ha="center", va="top", fontsize=9, color="C3")
    corner.set_title("2. The corner radius (close-up of the dashed box, mm)")
    corner.set_xlim(-60, 25), corner.set_ylim(-60, 25)

    for axes in (whole, corner):
        axes.set_aspect("equal")
        axes.set_xticks([]), axes.set_yticks([])
    figure.suptitle("Measuring a panel for the map (seen from below, the phone's view)")
    figure.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=110)
    plt.close(figure)


if __name__ == "__main__":
    draw(Path(sys.argv[1]) if len(sys.argv) > 1 else OUT)
