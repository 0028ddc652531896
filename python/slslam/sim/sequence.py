"""A simulated coal-mine sequence: scene, robot trajectory, lights, sensors, and the writer loop.

    from slslam.sim import SimOptions, Simulator
    sim = Simulator(SimOptions(preset="loop", light=0.15, dust=True, frames=400))
    sim.write("out/loop_dark")          # EuRoC ASL layout, readable by slslam.datasets

Determinism: every random quantity derives from ``options.seed`` (and the frame index), so the
same options give byte-identical files.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from slslam import _core
from slslam.errors import InputError
from slslam.progress import progress_bar
from slslam.sim import centrelines
from slslam.sim.asl_writer import AslWriter
from slslam.sim.dust import DustCloud
from slslam.sim.movers import Mover, default_movers
from slslam.sim.raycast import Hits, RaycastScene
from slslam.sim.roadway import (
    CrossSection,
    Material,
    Mesh,
    Stations,
    end_cap,
    line_with_shotcrete,
    network_mesh,
)
from slslam.sim.sensors import Lidar, StereoCamera
from slslam.sim.trajectory import ImuNoise, RobotTrajectory, TrajectoryOptions

log = logging.getLogger(__name__)

Preset = Literal["straight", "loop", "junction", "dead_end"]
PRESETS: tuple[str, ...] = ("straight", "loop", "junction", "dead_end")
#: Power of each roof lamp and the direction-less ambient light [irradiance units (* m^2)].
ROOF_LAMP_POWER = 4.0
AMBIENT = 0.002
#: First timestamp of a simulated sequence [ns] (small enough to stay exact in float64 seconds).
T0_NS = 1_000_000_000_000
#: Smooth shotcrete lining: its albedo, and the faint grain on it: value noise on cells of
#: SHOTCRETE_GRAIN_M [m] in world coordinates (sub-centimetre, about one pixel at 3 m) that
#: scales the albedo by 1 +- SHOTCRETE_GRAIN_CONTRAST at most (uniform).
SHOTCRETE_ALBEDO = 0.55
SHOTCRETE_GRAIN_M = 0.006
SHOTCRETE_GRAIN_CONTRAST = 0.03
#: Relief of a lining with ``SimOptions.shotcrete_relief_m`` > 0: the coarsest lumps' wavelength
#: [m] and the octaves (about 10, 5 and 2.4 cm), as sprayed concrete's lumps (C++ ReliefOptions).
SHOTCRETE_RELIEF_WAVELENGTH_M = 0.1
SHOTCRETE_RELIEF_OCTAVES = 3


@dataclass(frozen=True)
class SimOptions:
    """Everything that defines a simulated sequence. Units in the comments."""

    preset: Preset = "loop"
    frames: int = 400  # stereo frames
    rate_hz: float = 20.0  # camera rate [Hz]
    light: float = 1.0  # global light level [-]: 1.0 / 0.5 / 0.15 like OIVIO's onboard light
    dust: bool = False  # floating dust lit by the headlamp
    flicker: bool = False  # exposure flicker (per-frame light variation of about 10 %)
    blackout: bool = False  # all lights go out for blackout_s [s] from blackout_at_s [s]
    blackout_s: float = 1.0  # [s]
    blackout_at_s: float | None = None  # start of the blackout [s]; None: centred mid-run
    movers: bool = False  # a walking worker and a moving cart cross the view
    roof_lamps: bool = False  # a roof lamp every roof_lamp_spacing_m
    roof_lamp_spacing_m: float = 20.0
    lidar: bool = True  # write 16-beam LiDAR scans
    cameras: bool = True  # render and write the stereo images (off: LiDAR + IMU only, fast)
    lidar_rate_hz: float = 10.0
    imu_rate_hz: float = 200.0
    noise: bool = True  # image, IMU and LiDAR noise (off: exact measurements)
    speed_mps: float = 0.8  # robot cruise speed [m/s]
    laps: int = 1  # loop preset: times the robot may drive round (frames decide how far it gets)
    loop_length_m: float = 40.0  # loop preset: length of the two straights [m]
    loop_radius_m: float = 10.0  # loop preset: radius of the two half circles [m]
    spin_at_s: float | None = None  # the robot stops and turns on the spot at this time [s]
    spin_deg: float = 360.0  # yaw turned on the spot [deg], > 0 = left; kept afterwards
    spin_duration_s: float = 6.0  # duration of the turn [s]
    stop_duration_s: float = 0.0  # with spin_at_s: standing still before the turn [s]
    # Smooth shotcrete lining over [shotcrete_start_m, + shotcrete_length_m] along the robot's
    # path (first lap) [m]: no arches, bolts, pipe, cables; walls, roof, floor (and a dead end's
    # face) nearly uniform. Length 0: none.
    shotcrete_start_m: float = 0.0
    shotcrete_length_m: float = 0.0
    # Relief of the lining [m]: the scale of a lumpy height field (sub-centimetre for sprayed
    # concrete; its RMS is about a fifth of this) that the headlamp shades as a faint texture
    # changing with the light's direction. 0: flat, the camera sees only the faint grain.
    shotcrete_relief_m: float = 0.0
    exposure: float = 2.0  # sensor exposure [-]: light 1.0 gives a median gray of about 90
    headlamp_power: float = 12.0  # [irradiance units * m^2]
    section: CrossSection = field(default_factory=CrossSection)
    camera: StereoCamera = field(default_factory=StereoCamera)
    seed: int = 0

    def check(self) -> None:
        """Raise ValueError with a clear message on any invalid option."""
        if self.preset not in PRESETS:
            raise ValueError(f"unknown preset '{self.preset}' (choose from {', '.join(PRESETS)})")
        if self.frames < 1:
            raise ValueError(f"frames must be >= 1, got {self.frames}")
        if not 0.0 <= self.light <= 4.0:
            raise ValueError(
                f"light must be in [0, 4] (1.0 = full onboard light), got {self.light}"
            )
        if not (self.rate_hz > 0 and self.imu_rate_hz > 0 and self.lidar_rate_hz > 0):
            raise ValueError("sensor rates must be > 0")
        if not (self.exposure > 0 and self.headlamp_power >= 0):
            raise ValueError("exposure must be > 0 and headlamp_power >= 0")
        if not 0.1 <= self.speed_mps <= 3.0:
            raise ValueError(f"speed_mps must be in [0.1, 3], got {self.speed_mps}")
        if not 1 <= self.laps <= 20:
            raise ValueError(f"laps must be in [1, 20], got {self.laps}")
        if not (2.0 <= self.loop_length_m <= 1000.0 and 3.0 <= self.loop_radius_m <= 500.0):
            raise ValueError(
                "loop_length_m must be in [2, 1000] and loop_radius_m in [3, 500], got "
                f"{self.loop_length_m} and {self.loop_radius_m}"
            )
        if not (np.isfinite(self.blackout_s) and self.blackout_s > 0):
            raise InputError("blackout_s", f"must be a duration > 0 [s], got {self.blackout_s}")
        if self.blackout_at_s is not None:
            end = self.frames / self.rate_hz
            if not (np.isfinite(self.blackout_at_s) and 0 <= self.blackout_at_s < end):
                raise InputError(
                    "blackout_at_s",
                    f"must be in [0, {end:g}) s (the {self.frames} frames' time), "
                    f"got {self.blackout_at_s}",
                )
        for name in ("shotcrete_start_m", "shotcrete_length_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InputError(name, f"must be a distance >= 0 [m], got {value}")
        relief = self.shotcrete_relief_m
        if not (np.isfinite(relief) and 0.0 <= relief <= 0.05):
            raise InputError("shotcrete_relief_m", f"must be in [0, 0.05] m, got {relief}")
        self.section.check()
        self.camera.check()
        self.trajectory_options()  # checks the spin options

    def trajectory_options(self) -> TrajectoryOptions:
        """How the robot drives: cruise speed, body height, vibration seed, turn on the spot."""
        return TrajectoryOptions(
            speed_mps=self.speed_mps,
            body_height_m=0.4,
            seed=self.seed,
            spin_at_s=self.spin_at_s,
            spin_deg=self.spin_deg,
            spin_duration_s=self.spin_duration_s,
            stop_duration_s=self.stop_duration_s,
        )

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def shotcrete_grain(points: np.ndarray) -> np.ndarray:
    """Faint grain of the smooth shotcrete at world points (N, 3) [m]: a factor in
    ``1 +- SHOTCRETE_GRAIN_CONTRAST`` per cell of ``SHOTCRETE_GRAIN_M``, from a hash of the cell,
    so every view of a point sees the same grain."""
    cell = np.floor(np.asarray(points, dtype=np.float64) / SHOTCRETE_GRAIN_M).astype(np.int64)
    primes = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], np.uint64)
    h = cell.view(np.uint64) * primes  # wraps modulo 2^64
    h = h[:, 0] ^ h[:, 1] ^ h[:, 2]
    for shift, mult in ((33, 0xFF51AFD7ED558CCD), (33, 0xC4CEB9FE1A85EC53)):  # murmur3 mixing
        h = (h ^ (h >> np.uint64(shift))) * np.uint64(mult)
    h ^= h >> np.uint64(33)
    uniform = (h >> np.uint64(11)).astype(np.float64) * (1.0 / 2.0**53)  # [0, 1)
    return 1.0 + SHOTCRETE_GRAIN_CONTRAST * (2.0 * uniform - 1.0)


def smooth_shotcrete_shading(
    hits: Hits, relief_m: float, fx: float
) -> tuple[np.ndarray, np.ndarray]:
    """Normals and material ids to shade hits with: smooth shotcrete pixels as SHOTCRETE whose
    procedural texture and bolt plates are cancelled; with ``relief_m`` > 0 their normals first
    tilted by the lining's relief (C++ ``relief_normals``, its octaves faded below a few pixel
    footprints ``t / fx`` [m], ``fx`` the camera's focal length [px]).

    The shading kernel's light is linear in the normal's length (irradiance = power * n.l / d^2,
    n is not renormalised), so scaling the normal by ``target / albedo`` (``albedo`` the kernel's
    SHOTCRETE texture at the point, bolt plates included) makes the lit radiance
    ``target * irradiance``: a uniform ``SHOTCRETE_ALBEDO`` times the grain. What stays of the
    texture: the direction-less ambient term (``AMBIENT``, < 1 % of the headlamp's light inside
    its cone) and, beyond about 9 m, the finest octave that the kernel fades out with distance
    and ``solid_texture`` (no pixel footprint) does not.
    """
    smooth = hits.material == Material.SMOOTH_SHOTCRETE
    if not np.any(smooth):
        return hits.normal, hits.material
    material = hits.material.copy()
    material[smooth] = Material.SHOTCRETE
    points = np.ascontiguousarray(hits.point[smooth], dtype=np.float32)
    normals = np.ascontiguousarray(hits.normal[smooth], dtype=np.float32)
    if relief_m > 0.0:
        footprint = np.ascontiguousarray(hits.t[smooth] / fx, dtype=np.float32)
        normals = _core.relief_normals(
            points,
            normals,
            footprint_m=footprint,
            height_m=relief_m,
            wavelength_m=SHOTCRETE_RELIEF_WAVELENGTH_M,
            octaves=SHOTCRETE_RELIEF_OCTAVES,
        )
    albedo = _core.solid_texture(points, material[smooth], normals)
    scale = SHOTCRETE_ALBEDO * shotcrete_grain(points) / np.maximum(albedo, 1e-3)
    normal = np.array(hits.normal, dtype=np.float32, copy=True)
    normal[smooth] = normals * scale[:, None].astype(np.float32)
    return normal, material


def preset_geometry(
    preset: str, laps: int = 1, loop_length_m: float = 40.0, loop_radius_m: float = 10.0
) -> tuple[list[np.ndarray], np.ndarray]:
    """Roadway centrelines and the robot's path for a preset (the loop's path goes round
    ``laps`` times)."""
    if preset == "straight":
        return [centrelines.straight(80.0)], centrelines.straight(80.0)[4:-4]
    if preset == "loop":
        line = centrelines.loop(loop_length_m, loop_radius_m)
        path = np.vstack([line] + [line[1:]] * (laps - 1))
        return [line], path
    if preset == "junction":
        return centrelines.junction_roadways(), centrelines.junction_path()
    if preset == "dead_end":
        return centrelines.dead_end_roadways(), centrelines.dead_end_path()
    raise ValueError(f"unknown preset '{preset}' (choose from {', '.join(PRESETS)})")


class Simulator:
    """Builds the scene once and renders any frame of the sequence on demand."""

    def __init__(self, options: SimOptions = SimOptions()):
        options.check()
        self.options = options
        roadways, path = preset_geometry(
            options.preset, options.laps, options.loop_length_m, options.loop_radius_m
        )
        self.mesh = network_mesh(roadways, options.section)
        if options.preset == "dead_end":  # the branch ends in a face
            self.mesh = Mesh.concat([self.mesh, end_cap(roadways[1], options.section)])
        self.shotcrete_triangles = 0
        if options.shotcrete_length_m > 0:
            self.mesh, lined = self._line_with_shotcrete(self.mesh)
            self.shotcrete_triangles = int(np.count_nonzero(lined))
        self.scene = RaycastScene(self.mesh)
        duration = (options.frames - 1) / options.rate_hz + 1.0 / options.rate_hz
        self.trajectory = RobotTrajectory(
            path, duration_s=duration, options=options.trajectory_options()
        )
        self.camera = options.camera
        self.lidar = Lidar()
        self._roof_lamps = (
            self._place_roof_lamps(roadways) if options.roof_lamps else np.zeros((0, 3))
        )
        self.movers = self._place_movers(path) if options.movers else []
        self.dust = DustCloud(seed=options.seed) if options.dust else None
        self._sensor = _core.SensorModel()
        self._sensor.noise = options.noise
        self._sensor.seed = options.seed
        self._sensor.exposure = options.exposure

    def _line_with_shotcrete(self, mesh: Mesh) -> tuple[Mesh, np.ndarray]:
        """The mesh with the shotcrete stretch of the options lined (along the first lap)."""
        opts = self.options
        _, path = preset_geometry(opts.preset, 1, opts.loop_length_m, opts.loop_radius_m)
        length = float(Stations.from_centreline(path).s[-1])
        if opts.shotcrete_start_m >= length:
            raise InputError(
                "shotcrete_start_m",
                f"{opts.shotcrete_start_m} m is past the end of the {length:.1f} m path of "
                f"preset '{opts.preset}'",
            )
        return line_with_shotcrete(
            mesh, path, opts.shotcrete_start_m, opts.shotcrete_length_m, opts.section
        )

    @property
    def frame_times_s(self) -> np.ndarray:
        return np.arange(self.options.frames) / self.options.rate_hz

    def _place_roof_lamps(self, roadways: list[np.ndarray]) -> np.ndarray:
        lamps = []
        for line in roadways:
            st = Stations.from_centreline(line)
            targets = np.arange(5.0, st.s[-1], self.options.roof_lamp_spacing_m)
            idx = np.searchsorted(st.s, targets)
            lamps.append(st.position[idx] + [0.0, 0.0, self.options.section.height_m - 0.25])
        return np.concatenate(lamps)

    def _place_movers(self, path: np.ndarray) -> list[Mover]:
        t = np.linspace(0.0, self.trajectory.duration_s, 400)
        p = self.trajectory.position(t)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        return default_movers(path, s, t, self.options.section.width_m)

    def movers_mesh(self, t: float) -> Mesh | None:
        meshes = [m for m in (mover.mesh(t) for mover in self.movers) if m is not None]
        return Mesh.concat(meshes) if meshes else None

    def light_level(self, frame: int) -> float:
        """Global light level of a frame: the option, times flicker, zero during a blackout."""
        level = self.options.light
        if self.options.flicker:
            rng = np.random.default_rng([self.options.seed, frame, 1])
            level *= float(np.clip(1.0 + 0.1 * rng.standard_normal(), 0.6, 1.4))
        if self.options.blackout:
            t = frame / self.options.rate_hz
            start = self.options.blackout_at_s
            if start is None:
                mid = 0.5 * self.options.frames / self.options.rate_hz
                dark = abs(t - mid) < self.options.blackout_s / 2
            else:
                dark = start <= t < start + self.options.blackout_s
            if dark:
                level = 0.0
        return level

    def cast_cameras(self, poses_world_cam: list[np.ndarray], t: float) -> list[Hits]:
        """Ray-cast every pixel of cameras at poses ``T_world_cam`` (world hits, row-major)."""
        cam = self.camera
        movers = self.movers_mesh(t)
        return [
            self.scene.cast_pinhole(
                T, cam.fx, cam.fx, cam.cx, cam.cy, cam.width, cam.height, movers
            )
            for T in poses_world_cam
        ]

    def _headlamp(self, T_world_body: np.ndarray) -> _core.HeadLamp:
        lamp = _core.HeadLamp()
        lamp.position = T_world_body[:3, :3] @ np.array([0.35, 0.0, 1.0]) + T_world_body[:3, 3]
        pitch_down = np.deg2rad(6.0)
        forward = np.array([np.cos(pitch_down), 0.0, -np.sin(pitch_down)])
        lamp.direction = T_world_body[:3, :3] @ forward
        lamp.power = self.options.headlamp_power
        lamp.half_angle_rad = np.deg2rad(40.0)
        return lamp

    def shade(
        self,
        hits: Hits,
        T_world_cam: np.ndarray,
        lamp: _core.HeadLamp,
        level: float,
        noise_index: int,
    ) -> np.ndarray:
        """Image formation (C++): textures, lights and sensor model for one camera's hits."""
        cam = self.camera
        # pybind11 takes any sequence for the position; the stub's Sequence excludes numpy arrays
        shading_camera = _core.ShadingCamera(  # type: ignore[call-overload]
            cam.fx, cam.fx, cam.cx, cam.cy, T_world_cam[:3, 3]
        )
        normal, material = smooth_shotcrete_shading(hits, self.options.shotcrete_relief_m, cam.fx)
        return _core.shade_image(
            hits.point,
            normal,
            material,
            cam.height,
            cam.width,
            shading_camera,
            lamp,
            self._roof_lamps,
            ROOF_LAMP_POWER,
            level,
            AMBIENT,
            self._sensor,
            noise_index,
        )

    def render_stereo(self, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Left and right uint8 images and the left depth map (z along the optical axis, m)."""
        t = frame / self.options.rate_hz
        T_world_body = self.trajectory.pose(np.array([t]))[0]
        level = self.light_level(frame)
        lamp = self._headlamp(T_world_body)
        cam = self.camera
        poses = [T_world_body @ cam.T_body_cam0, T_world_body @ cam.T_body_cam1]
        images, depth = [], None
        for k, (T_world_cam, hits) in enumerate(
            zip(poses, self.cast_cameras(poses, t), strict=True)
        ):
            image = self.shade(hits, T_world_cam, lamp, level, 2 * frame + k)
            if self.dust is not None:
                self.dust.draw(image, T_world_cam, cam, lamp, level, t)
            images.append(image)
            if k == 0:
                assert hits.depth is not None  # camera casts carry depth
                depth = hits.depth.reshape(cam.height, cam.width)
        assert depth is not None
        return images[0], images[1], depth

    def _render_record(self, frame: int, rng: np.random.Generator) -> dict:
        """Everything written for one frame: images, camera pose, LiDAR scan when due."""
        opts = self.options
        t = frame / opts.rate_hz
        T_world_body = self.trajectory.pose(np.array([t]))[0]
        record: dict[str, Any] = {"t_ns": T0_NS + round(t * 1e9)}
        if opts.cameras:
            record["left"], record["right"], _ = self.render_stereo(frame)
            record["T_world_cam0"] = T_world_body @ self.camera.T_body_cam0
        lidar_every = max(round(opts.rate_hz / opts.lidar_rate_hz), 1)
        if opts.lidar and frame % lidar_every == 0:
            record["lidar"] = self._render_sweep(t, rng)
        return record

    def _render_sweep(self, t: float, rng: np.random.Generator) -> tuple:
        """A LiDAR sweep starting at t [s]: points in the sensor frame of their azimuth block,
        the sensor pose at t, and each point's time after t [s] (its block's mid-time; blocks
        past the end of the run are clipped to it)."""
        block_t = t + self.lidar.block_times_s(1.0 / self.options.lidar_rate_hz)
        block_t = np.minimum(block_t, self.trajectory.duration_s)
        T_body_lidar = self.lidar.T_body_lidar
        poses = self.trajectory.pose(block_t) @ T_body_lidar
        scan, block = self.lidar.sweep(
            self.scene, poses, rng, noise=self.options.noise, movers=self.movers_mesh(t)
        )
        T_world_lidar = self.trajectory.pose(np.array([t]))[0] @ T_body_lidar
        return scan, T_world_lidar, (block_t[block] - t).astype(np.float32)

    @staticmethod
    def _write_record(writer: AslWriter, record: dict) -> None:
        if "left" in record:
            writer.write_stereo(record["t_ns"], record["left"], record["right"], _core.write_image)
            writer.write_camera_pose(record["t_ns"], record["T_world_cam0"])
        if "lidar" in record:
            writer.write_lidar(record["t_ns"], *record["lidar"])

    def write(
        self,
        out: str | Path,
        progress: bool = True,
        between_frames: Callable[[], None] | None = None,
    ) -> dict:
        """Write the whole sequence (EuRoC ASL layout); returns the manifest.

        ``between_frames`` is called once before anything is written and after each frame is
        handed to the writer; what it raises (``RunInterrupted`` from a signal) stops the run
        there: nothing is written when it raises first, else the frames so far are written whole
        and the manifest says ``"status": "interrupted"`` and how many (``frames_written``)."""
        opts = self.options
        if between_frames is not None:
            between_frames()
        writer = AslWriter(out, lidar=opts.lidar, cameras=opts.cameras)
        manifest: dict[str, Any] = {
            "status": "running",
            "preset": opts.preset,
            "seed": opts.seed,
            "options": opts.to_dict(),
            "frames_written": 0,
            "mesh_triangles": len(self.mesh.triangles),
            "shotcrete_triangles": self.shotcrete_triangles,
        }
        writer.write_manifest(manifest)
        imu_noise = ImuNoise()
        writer.write_calibration(
            self.camera,
            self.camera.T_body_cam0,
            self.camera.T_body_cam1,
            opts.rate_hz,
            opts.imu_rate_hz,
            imu_noise,
            self.lidar if opts.lidar else None,
            opts.lidar_rate_hz,
        )
        imu = self.trajectory.imu(
            opts.imu_rate_hz, imu_noise if opts.noise else None, seed=opts.seed
        )
        imu["t_ns"] = imu["t_ns"] + T0_NS
        writer.write_imu(imu)
        t_gt = np.arange(0.0, self.trajectory.duration_s, 1.0 / opts.imu_rate_hz)
        writer.write_body_groundtruth(
            T0_NS + np.round(t_gt * 1e9).astype(np.int64),
            self.trajectory.pose(t_gt),
            self.trajectory.velocity(t_gt),
        )
        rng = np.random.default_rng([opts.seed, 7])
        start = time.perf_counter()
        # Files of frame k are written on a second thread while frame k+1 renders (PNG encoding
        # releases the GIL); one pending frame at most, so records stay in order.
        pending: Future | None = None
        submitted = 0
        try:
            with ThreadPoolExecutor(max_workers=1) as pool:
                for frame in progress_bar(
                    range(opts.frames), desc="simulate", unit="frame", enabled=progress
                ):
                    record = self._render_record(frame, rng)
                    if pending is not None:
                        pending.result()
                        manifest["frames_written"] = submitted
                    pending = pool.submit(self._write_record, writer, record)
                    submitted += 1
                    if between_frames is not None:
                        between_frames()
                if pending is not None:
                    pending.result()
                    manifest["frames_written"] = opts.frames
            manifest["status"] = "complete"
        except BaseException as exc:
            manifest["status"] = "interrupted"
            manifest["stopped_by"] = str(exc) or type(exc).__name__
            # the pool waited for the frame in flight: counted when its files were written
            if pending is not None and pending.done() and not pending.cancelled():
                if pending.exception() is None:
                    manifest["frames_written"] = submitted
            raise
        finally:
            elapsed = time.perf_counter() - start
            manifest["seconds"] = round(elapsed, 3)
            manifest["frames_per_second"] = round(
                manifest["frames_written"] / max(elapsed, 1e-9), 3
            )
            writer.write_manifest(manifest)
            writer.close()
        log.info(
            "wrote %d frames to %s (%.2f frames/s)",
            manifest["frames_written"],
            out,
            manifest["frames_per_second"],
        )
        return manifest
