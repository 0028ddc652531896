"""Sensor models of the simulated robot: a rectified stereo camera and a 16-beam LiDAR.

Body frame: x forward, y left, z up (the IMU frame). Camera frames: z forward, x right, y down.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slslam.sim.raycast import RaycastScene
from slslam.sim.roadway import Mesh

#: Rotation from a camera frame (z forward, x right, y down) to the body frame.
R_BODY_CAM = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def _transform(R: np.ndarray, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


@dataclass(frozen=True)
class StereoCamera:
    """A rectified stereo pair: both cameras share K; cam1 sits ``baseline_m`` along cam0's x."""

    width: int = 752
    height: int = 480
    fx: float = 458.0  # [px], fy = fx
    baseline_m: float = 0.11
    mount_xyz_m: tuple[float, float, float] = (0.3, 0.0, 0.8)  # rig centre in the body frame

    @property
    def cx(self) -> float:
        return (self.width - 1) / 2

    @property
    def cy(self) -> float:
        return (self.height - 1) / 2

    def check(self) -> None:
        if not (16 <= self.width <= 4096 and 16 <= self.height <= 4096):
            raise ValueError(f"image size {self.width}x{self.height} out of range")
        if self.width % 8 or self.height % 8:
            raise ValueError(f"image size {self.width}x{self.height}: use multiples of 8")
        if not (self.fx > 0 and self.baseline_m > 0):
            raise ValueError("fx and baseline_m must be > 0")

    @property
    def T_body_cam0(self) -> np.ndarray:
        centre = np.asarray(self.mount_xyz_m)
        return _transform(R_BODY_CAM, centre + [0.0, self.baseline_m / 2, 0.0])

    @property
    def T_body_cam1(self) -> np.ndarray:
        centre = np.asarray(self.mount_xyz_m)
        return _transform(R_BODY_CAM, centre - [0.0, self.baseline_m / 2, 0.0])

    def pixel_directions(self) -> np.ndarray:
        """Unit ray directions (H*W, 3) in the camera frame, row-major over pixels."""
        u, v = np.meshgrid(np.arange(self.width), np.arange(self.height))
        d = np.stack([(u - self.cx) / self.fx, (v - self.cy) / self.fx, np.ones(u.shape)], -1)
        d = d.reshape(-1, 3)
        return d / np.linalg.norm(d, axis=1, keepdims=True)


@dataclass(frozen=True)
class Lidar:
    """A 16-beam spinning LiDAR like the RS-LiDAR-16 / VLP-16 (-15..+15 deg, 2 deg apart)."""

    beams: int = 16
    min_elevation_deg: float = -15.0
    max_elevation_deg: float = 15.0
    azimuth_steps: int = 1800  # 0.2 deg at 10 Hz
    max_range_m: float = 100.0
    min_range_m: float = 0.4
    range_noise_m: float = 0.02  # 1 sigma
    sweep_blocks: int = 60  # a sweep is ray cast in this many azimuth blocks (6 deg each)
    mount_xyz_m: tuple[float, float, float] = (0.1, 0.0, 1.4)
    directions: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        elevation = np.deg2rad(
            np.linspace(self.min_elevation_deg, self.max_elevation_deg, self.beams)
        )
        azimuth = np.linspace(0.0, 2 * np.pi, self.azimuth_steps, endpoint=False)
        el, az = np.meshgrid(elevation, azimuth, indexing="ij")
        d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1)
        object.__setattr__(self, "directions", d.reshape(-1, 3))

    @property
    def T_body_lidar(self) -> np.ndarray:
        return _transform(np.eye(3), self.mount_xyz_m)

    def scan(
        self,
        scene: RaycastScene,
        T_world_lidar: np.ndarray,
        rng: np.random.Generator,
        noise: bool = True,
        movers: Mesh | None = None,
    ) -> np.ndarray:
        """Points (N, 4): x, y, z in the LiDAR frame [m] and intensity in [0, 1].

        The scan is taken at one instant (no motion distortion within the sweep); ``movers``
        (moving objects at that instant) are seen like the walls.
        """
        return self.sweep(scene, T_world_lidar[None], rng, noise, movers)[0]

    def sweep_block(self) -> np.ndarray:
        """Index of the azimuth block of every ray (row of ``directions``) of a sweep."""
        azimuth = np.arange(len(self.directions)) % self.azimuth_steps
        return azimuth * self.sweep_blocks // self.azimuth_steps

    def block_times_s(self, period_s: float) -> np.ndarray:
        """Mid-times of the azimuth blocks after the sweep's start [s] (a sweep lasts
        ``period_s`` and turns counter-clockwise from azimuth 0, like a Velodyne/RoboSense)."""
        return (np.arange(self.sweep_blocks) + 0.5) * (period_s / self.sweep_blocks)

    def sweep(
        self,
        scene: RaycastScene,
        T_world_lidar: np.ndarray,
        rng: np.random.Generator,
        noise: bool = True,
        movers: Mesh | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """A spinning sweep with motion distortion: points (N, 4) as ``scan`` and each point's
        block index (N,).

        ``T_world_lidar`` is (B, 4, 4): the sensor pose at each block's time (B = 1: one instant,
        B = ``sweep_blocks``: block b covers azimuths [b, b + 1) * 360 / B deg). Each point is in
        the LiDAR frame of its own block's pose, as a real spinning sensor reports it.
        """
        poses = np.asarray(T_world_lidar, dtype=float)
        blocks = np.zeros(len(self.directions), int) if len(poses) == 1 else self.sweep_block()
        if len(poses) not in (1, self.sweep_blocks):
            raise ValueError(f"expected 1 or {self.sweep_blocks} poses, got {len(poses)}")
        r = np.empty(len(self.directions))
        cos_incidence = np.empty(len(self.directions))
        for b, T in enumerate(poses):
            rays = np.flatnonzero(blocks == b)
            dirs_world = self.directions[rays] @ T[:3, :3].T
            hits = scene.cast(T[:3, 3], dirs_world, movers)
            r[rays] = hits.t
            cos_incidence[rays] = np.abs(np.einsum("ij,ij->i", hits.normal, dirs_world))
        hit = np.isfinite(r)
        if noise:
            r += rng.normal(0.0, self.range_noise_m, r.shape)
        keep = hit & (r > self.min_range_m) & (r < self.max_range_m)
        points = self.directions[keep] * r[keep, None]
        scan = np.column_stack([points, cos_incidence[keep]]).astype(np.float32)
        return scan, blocks[keep]
