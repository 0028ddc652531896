"""Floating dust: small particles near the camera that scatter the headlamp's light.

Particles live in world coordinates inside a box that follows the camera (positions wrap
around the box), drift slowly, and are drawn into both images of the stereo pair from the same
3-D positions, so they are stereo-consistent like real dust.
"""

from __future__ import annotations

import numpy as np


class DustCloud:
    """``count`` particles in a ``box_m`` cube around the camera, drifting at ``drift_mps``."""

    def __init__(
        self, count: int = 600, box_m: float = 4.0, drift_mps: float = 0.05, seed: int = 0
    ):
        rng = np.random.default_rng([seed, 11])
        self.box_m = box_m
        self.origin = rng.uniform(0.0, box_m, (count, 3))
        self.velocity = rng.normal(0.0, drift_mps, (count, 3))
        self.size_px = rng.uniform(0.6, 1.6, count)

    def positions(self, centre: np.ndarray, t: float) -> np.ndarray:
        """World positions at time t, wrapped into the box centred on ``centre``."""
        raw = self.origin + self.velocity * t
        corner = centre - self.box_m / 2
        return corner + np.mod(raw - corner, self.box_m)

    def draw(
        self,
        image: np.ndarray,
        T_world_cam: np.ndarray,
        camera,
        lamp,
        light_level: float,
        t: float,
    ) -> None:
        """Add the lit particles to ``image`` (uint8, in place)."""
        if light_level <= 0.0:
            return
        R, c = T_world_cam[:3, :3], T_world_cam[:3, 3]
        # The box is centred 1.5 m ahead of the camera so most particles are in view.
        p_world = self.positions(c + R[:, 2] * 1.5, t)
        p_cam = (p_world - c) @ R
        z = p_cam[:, 2]
        keep = z > 0.3
        u = camera.fx * p_cam[keep, 0] / z[keep] + camera.cx
        v = camera.fx * p_cam[keep, 1] / z[keep] + camera.cy
        to_lamp = np.asarray(lamp.position) - p_world[keep]
        dist2 = np.einsum("ij,ij->i", to_lamp, to_lamp)
        brightness = np.clip(60.0 * light_level / np.maximum(dist2, 0.05), 0, 200)
        radius = self.size_px[keep] / z[keep]
        h, w = image.shape
        acc = np.zeros((h, w), np.float32)
        for du in (-1, 0, 1):
            for dv in (-1, 0, 1):
                weight = np.exp(-(du * du + dv * dv) / (2 * np.maximum(radius, 0.35) ** 2))
                ui = np.round(u).astype(int) + du
                vi = np.round(v).astype(int) + dv
                inside = (ui >= 0) & (ui < w) & (vi >= 0) & (vi < h)
                np.add.at(acc, (vi[inside], ui[inside]), (brightness * weight)[inside])
        image[:] = np.clip(image.astype(np.float32) + acc, 0, 255).astype(np.uint8)
