"""`lumipose bench render`: how long one full-resolution frame of a scene takes to render.

A figure, not a test: the median over `repeats` renders of one sample of a bundled scene
(default the paper's bench, Mi 8 front camera at 3880 x 5184, panel under the camera), as wall
and as CPU time (the CPU time does not depend on what else the machine runs), with one
full-frame Gaussian draw timed on its own for scale.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from simulator.sampling import render_pose, series_poses
from simulator.scene import find_scene


def bench_render(scene_name: str = "paper-bench", repeats: int = 10, sample: int | None = None) -> dict:
    scene = find_scene(scene_name)
    poses = series_poses(scene)
    pose = poses[len(poses) // 2 if sample is None else sample]
    render_pose(scene, pose)  # warm-up: imports, first allocations
    render_ms, cpu_ms = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        pixels, _ = render_pose(scene, pose)
        render_ms.append((time.perf_counter() - start) * 1000)
        cpu_ms.append((time.process_time() - start_cpu) * 1000)
    rng = np.random.default_rng(0)
    noise_ms = []
    for _ in range(repeats):
        start = time.perf_counter()
        rng.standard_normal(pixels.shape, dtype=np.float32)
        noise_ms.append((time.perf_counter() - start) * 1000)
    return {"scene": scene.name, "frame": f"{pixels.shape[1]}x{pixels.shape[0]}", "sample": pose.index,
            "repeats": repeats, "median_ms": statistics.median(render_ms), "max_ms": max(render_ms),
            "cpu_median_ms": statistics.median(cpu_ms), "load_average_1min": os.getloadavg()[0],
            "gaussian_noise_median_ms": statistics.median(noise_ms), "cpu_count": os.cpu_count()}
