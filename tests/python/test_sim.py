"""Simulator checks: stereo geometry, LiDAR ranges, read-back, determinism, options."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from slslam.cli import main
from slslam.datasets import EurocSequence, read_trajectory
from slslam.errors import InputError
from slslam.sim import SimOptions, Simulator
from slslam.sim.roadway import Material
from slslam.sim.sensors import StereoCamera

SMALL = StereoCamera(width=320, height=240, fx=200.0)


def _small(**kwargs) -> SimOptions:
    return SimOptions(camera=SMALL, **{"frames": 5, **kwargs})


@pytest.fixture(scope="module")
def noiseless_loop() -> Simulator:
    return Simulator(_small(preset="loop", noise=False, frames=60))


def test_stereo_geometry_right_rays_hit_the_left_points(noiseless_loop):
    """The right camera's ray through (u - fx b / z, v) hits the point the left ray hit."""
    sim = noiseless_loop
    cam = sim.camera
    T_world_body = sim.trajectory.pose(np.array([1.0]))[0]
    left, _right = sim.cast_cameras(
        [T_world_body @ cam.T_body_cam0, T_world_body @ cam.T_body_cam1], 1.0
    )
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, cam.width * cam.height, 400)
    depth = left.depth[pixels]
    ok = np.isfinite(depth) & (depth < 15.0)
    u = pixels % cam.width
    v = pixels // cam.width
    u_right = u - cam.fx * cam.baseline_m / depth
    inside = ok & (u_right > 0)
    # Cast exactly through the predicted sub-pixel position in the right camera.
    d = np.column_stack([(u_right - cam.cx) / cam.fx, (v - cam.cy) / cam.fx, np.ones(len(u))])[
        inside
    ]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    T_world_cam1 = T_world_body @ cam.T_body_cam1
    hits = sim.scene.cast(T_world_cam1[:3, 3], d @ T_world_cam1[:3, :3].T)
    gap = np.linalg.norm(hits.point - left.point[pixels[inside]], axis=1)
    assert inside.sum() > 300
    # Points on the same surface: equal up to grazing-angle effects at occlusion edges.
    assert np.median(gap) < 1e-3
    assert np.mean(gap < 0.01) > 0.95


def _block_disparity(left: np.ndarray, right: np.ndarray, u: int, v: int, max_d: int) -> float:
    """Sub-pixel disparity by SSD block matching along the row (7x7 block, parabola fit)."""
    r = 3
    patch = left[v - r : v + r + 1, u - r : u + r + 1].astype(float)
    costs = np.array(
        [
            np.sum((right[v - r : v + r + 1, u - d - r : u - d + r + 1] - patch) ** 2)
            for d in range(max_d)
        ]
    )
    best = int(np.argmin(costs))
    if 0 < best < max_d - 1:
        c0, c1, c2 = costs[best - 1 : best + 2]
        denominator = c0 - 2 * c1 + c2
        if denominator > 0:
            return best + 0.5 * (c0 - c2) / denominator
    return float(best)


def test_stereo_images_have_disparity_fx_b_over_depth(noiseless_loop):
    """Image content agrees with the ray-cast depth: block-matched disparity = fx b / z."""
    left, right, depth = noiseless_loop.render_stereo(20)
    cam = noiseless_loop.camera
    rng = np.random.default_rng(2)
    errors = []
    for _ in range(3000):
        u, v = int(rng.integers(40, cam.width - 10)), int(rng.integers(10, cam.height - 10))
        z = depth[v, u]
        patch = left[v - 3 : v + 4, u - 3 : u + 4]
        local = depth[v - 3 : v + 4, u - 3 : u + 4]
        if not np.isfinite(z) or patch.std() < 4 or np.ptp(local) > 0.05 * z:
            continue  # textureless, void or an occlusion edge: no reliable match
        expected = cam.fx * cam.baseline_m / z
        if u - expected < 8:
            continue
        errors.append(
            _block_disparity(left.astype(float), right.astype(float), u, v, int(expected) + 6)
            - expected
        )
    errors = np.abs(np.asarray(errors))
    assert len(errors) > 100
    assert np.median(errors) < 0.5, f"median disparity error {np.median(errors):.3f} px"


def _open3d():
    return pytest.importorskip("open3d", reason="open3d (test extra) cross-checks the ray caster")


def _open3d_scene(sim: Simulator):
    """An independent ray caster of the same mesh (Open3D's RaycastingScene)."""
    o3d = _open3d()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(sim.mesh.vertices.astype(np.float32)),
        o3d.core.Tensor(sim.mesh.triangles.astype(np.uint32)),
    )
    return scene


def test_camera_hits_agree_with_open3d(noiseless_loop):
    sim = noiseless_loop
    cam = sim.camera
    T = sim.trajectory.pose(np.array([2.0]))[0] @ cam.T_body_cam0
    o3d = _open3d()
    ours = sim.cast_cameras([T], 2.0)[0]
    directions = cam.pixel_directions() @ T[:3, :3].T
    rays = np.hstack([np.broadcast_to(T[:3, 3], directions.shape), directions])
    theirs = _open3d_scene(sim).cast_rays(o3d.core.Tensor(rays.astype(np.float32)))
    t_o3d = theirs["t_hit"].numpy()
    assert np.array_equal(np.isfinite(ours.t), np.isfinite(t_o3d))
    hit = np.isfinite(t_o3d)
    assert np.max(np.abs(ours.t[hit] - t_o3d[hit])) < 1e-3
    ids = theirs["primitive_ids"].numpy()[hit]
    assert np.mean(ours.material[hit] == sim.mesh.material[ids]) > 0.999


def test_lidar_points_lie_on_the_roadway_surface():
    sim = Simulator(_small(preset="straight", noise=False))
    T_world_lidar = sim.trajectory.pose(np.array([0.1]))[0] @ sim.lidar.T_body_lidar
    scan = sim.lidar.scan(sim.scene, T_world_lidar, np.random.default_rng(0), noise=False)
    assert scan.shape[1] == 4 and len(scan) > 10_000
    world = scan[:, :3] @ T_world_lidar[:3, :3].T + T_world_lidar[:3, 3]
    # Distance to the mesh, measured by another library: the points lie on the surface.
    o3d = _open3d()
    distance = _open3d_scene(sim).compute_distance(o3d.core.Tensor(world.astype(np.float32)))
    assert np.max(distance.numpy()) < 2e-3
    # Floor returns sit on z = 0; the roadway is 4.4 m wide: nothing beyond its walls.
    floor = (world[:, 2] < 0.3) & (np.abs(world[:, 1]) < 2.0)  # away from walls and arches
    assert floor.sum() > 100 and np.max(np.abs(world[floor, 2])) < 2e-3
    assert np.max(np.abs(world[:, 1])) < 2.2 + 1e-3
    # With noise, ranges scatter by the configured sigma.
    noisy = sim.lidar.scan(sim.scene, T_world_lidar, np.random.default_rng(0), noise=True)
    ranges = np.linalg.norm(scan[:, :3], axis=1)
    noisy_ranges = np.linalg.norm(noisy[:, :3], axis=1)
    n = min(len(ranges), len(noisy_ranges))
    assert np.std(noisy_ranges[:n] - ranges[:n]) == pytest.approx(sim.lidar.range_noise_m, rel=0.2)


def test_written_sequence_reads_back(tmp_path):
    out = tmp_path / "seq"
    manifest = Simulator(_small(preset="junction", frames=6, movers=True)).write(
        out, progress=False
    )
    assert manifest["status"] == "complete" and manifest["frames_written"] == 6
    seq = EurocSequence(out)
    assert len(seq) == 6
    assert seq.camera.fx == pytest.approx(SMALL.fx, abs=1e-6)
    assert seq.camera.baseline_m == pytest.approx(SMALL.baseline_m, abs=1e-9)
    frame = seq[3]
    assert frame.left.shape == (SMALL.height, SMALL.width)
    gt = seq.groundtruth(frame="cam0")
    tum = read_trajectory(out / "groundtruth_cam0.tum")
    # The TUM camera ground truth equals body ground truth composed with cam0's T_BS.
    i = np.searchsorted(gt.timestamps, tum.timestamps[3] - 1e-6)
    np.testing.assert_allclose(gt.positions_xyz[i], tum.positions_xyz[3], atol=1e-6)
    imu = seq.imu()
    assert len(imu["t_ns"]) >= 200 * 0.25
    scans = sorted((out / "mav0" / "lidar0" / "data").glob("*.bin"))
    assert len(scans) == 3  # 10 Hz LiDAR beside 20 Hz cameras
    points = np.fromfile(scans[0], dtype=np.float32).reshape(-1, 4)
    assert len(points) > 1000


def _tree_bytes(root: Path) -> dict[str, bytes]:
    files = {}
    for path in sorted(root.rglob("*")):
        if path.is_file() and path.name != "manifest.json":
            files[str(path.relative_to(root))] = path.read_bytes()
    manifest = json.loads((root / "manifest.json").read_text())
    for timing in ("seconds", "frames_per_second"):
        manifest.pop(timing)
    files["manifest"] = json.dumps(manifest, sort_keys=True).encode()
    return files


def test_same_seed_gives_identical_bytes_and_another_seed_differs(tmp_path):
    options = _small(preset="loop", frames=3, dust=True, flicker=True, movers=True)
    a = _tree_bytes(
        Path(Simulator(options).write(tmp_path / "a", progress=False) and tmp_path / "a")
    )
    b = _tree_bytes(
        Path(Simulator(options).write(tmp_path / "b", progress=False) and tmp_path / "b")
    )
    assert a.keys() == b.keys() and len(a) > 10
    assert all(a[k] == b[k] for k in a)
    other = SimOptions(**{**options.__dict__, "seed": 1})
    Simulator(other).write(tmp_path / "c", progress=False)
    c = _tree_bytes(tmp_path / "c")
    left = "mav0/cam0/data"
    assert any(a[k] != c[k] for k in a if k.startswith(left))


def test_light_levels_blackout_and_movers():
    bright = Simulator(_small(light=1.0, noise=False)).render_stereo(2)[0]
    dark = Simulator(_small(light=0.15, noise=False)).render_stereo(2)[0]
    assert dark.mean() < 0.75 * bright.mean()
    assert dark.mean() > 5  # dim, not black: structure must stay visible
    blackout = Simulator(_small(blackout=True, frames=40, noise=False))
    assert blackout.render_stereo(20)[0].mean() < 0.2 * blackout.render_stereo(2)[0].mean()
    sim = Simulator(_small(movers=True, frames=400))
    worker = next(m for m in sim.movers if m.kind == "worker")
    t = 0.5 * (worker.t0 + worker.t1)
    T = sim.trajectory.pose(np.array([t]))[0] @ sim.camera.T_body_cam0
    hits = sim.cast_cameras([T], t)[0]
    assert np.count_nonzero(hits.material == Material.WORKER) > 50


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"preset": "mine"}, "unknown preset"),
        ({"frames": 0}, "frames must be >= 1"),
        ({"light": -1.0}, "light must be in"),
        ({"speed_mps": 9.0}, "speed_mps"),
    ],
)
def test_bad_options_are_rejected(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SimOptions(**kwargs).check()


def test_cli_sim_writes_and_reports_bad_input(tmp_path, capsys):
    assert main(["sim", "--out", str(tmp_path / "x"), "--preset", "cave", "--frames", "2"]) == 2
    assert "unknown preset 'cave'" in capsys.readouterr().err


def test_spin_options_reach_the_trajectory_and_the_manifest(tmp_path):
    sim = Simulator(_small(preset="straight", frames=240, spin_at_s=4.0, spin_deg=-90.0))
    assert sim.trajectory.options.spin_at_s == 4.0
    t = np.linspace(4.0, 10.0, 61)  # the turn: rest at the same place, 90 deg to the right
    T = sim.trajectory.pose(t)
    assert np.abs(T[:, :3, 3] - T[0, :3, 3]).max() < 1e-9
    turned = T[0, :3, :3].T @ T[-1, :3, :3]
    np.testing.assert_allclose(
        turned, [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-9
    )
    # options travel with the sequence; a spin after the last frame is allowed and recorded
    out = tmp_path / "seq"
    Simulator(_small(preset="straight", frames=2, spin_at_s=4.0, lidar=False)).write(
        out, progress=False
    )
    options = json.loads((out / "manifest.json").read_text())["options"]
    assert (options["spin_at_s"], options["spin_deg"], options["spin_duration_s"]) == (
        4.0,
        360.0,
        6.0,
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"spin_at_s": 1.0}, "spin_at_s must be >= 2"),
        ({"spin_at_s": 8.0, "spin_duration_s": 0.0}, "spin_duration_s must be > 0"),
        ({"spin_at_s": 8.0, "spin_deg": float("nan")}, "spin_deg must be finite"),
    ],
)
def test_bad_spin_options_are_rejected(kwargs, message):
    with pytest.raises(InputError, match=message):
        SimOptions(**kwargs).check()


def test_cli_sim_spin_at_reports_bad_input(tmp_path, capsys):
    args = ["sim", "--out", str(tmp_path / "x"), "--frames", "2", "--spin-at", "1"]
    assert main(args) == 2
    assert "spin_at_s must be >= 2 * accel_time_s" in capsys.readouterr().err
    assert not (tmp_path / "x" / "mav0").exists()
