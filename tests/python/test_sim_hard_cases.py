"""Issue 62's hard simulated cases: a smooth shotcrete lining that really has no texture, a stop
in which ground truth and the IMU are exactly at rest, a blackout of the configured length, a
dead end with a face, and the benchmark's case definitions."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import ndimage

from slslam.cli import main
from slslam.errors import InputError
from slslam.features.orb import Orb
from slslam.sim import SimOptions, Simulator
from slslam.sim.roadway import Material
from slslam.sim.sensors import StereoCamera

from conftest import load_benchmark

SMALL = StereoCamera(width=320, height=240, fx=200.0)
#: The straight roadway lined with shotcrete from 10 to 30 m along the path (x = 11 ... 31 m:
#: the straight preset's path starts 1 m into the roadway). Its own pattern has an older,
#: bolted SHOTCRETE section at x = 18 ... 28 m and rock with arches at x = 40 ... 58 m.
LINED = {"preset": "straight", "shotcrete_start_m": 10.0, "shotcrete_length_m": 20.0}


def _small(**kwargs) -> SimOptions:
    return SimOptions(camera=SMALL, **{"frames": 5, "lidar": False, **kwargs})


#: Camera orientations R_world_cam (camera x right, y down, z forward) at 1.2 m on the straight:
#: facing the left wall (z = world +y) and looking along the roadway (z = world +x).
FACING_WALL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
ALONG_ROADWAY = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def _view(
    sim: Simulator, x: float, R_world_cam: np.ndarray, level: float
) -> tuple[np.ndarray, np.ndarray]:
    """Left camera image and hit materials, the robot at x [m] on the straight, the camera
    turned to R_world_cam at 1.2 m, at light ``level``."""
    T_world_cam = np.eye(4)
    T_world_cam[:3, :3] = R_world_cam
    T_world_cam[:3, 3] = [x, 0.0, 1.2]
    T_world_body = T_world_cam @ np.linalg.inv(sim.camera.T_body_cam0)
    hits = sim.cast_cameras([T_world_cam], 0.0)[0]
    image = sim.shade(hits, T_world_cam, sim._headlamp(T_world_body), level, 0)
    return image, hits.material.reshape(image.shape)


def _wall_view(sim: Simulator, x: float, level: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """Facing the left wall from 2.2 m (light 0.15: brighter saturates there)."""
    return _view(sim, x, FACING_WALL, level)


def _gradient_energy(image: np.ndarray) -> float:
    """Mean squared Sobel gradient [gray levels^2] away from the image border."""
    img = image.astype(np.float64)
    g = ndimage.sobel(img, axis=0) ** 2 + ndimage.sobel(img, axis=1) ** 2
    return float(g[8:-8, 8:-8].mean())


@pytest.fixture(scope="module")
def lined() -> Simulator:
    return Simulator(_small(noise=False, **LINED))


def test_shotcrete_lining_replaces_shell_and_removes_arches_and_services(lined):
    mesh = lined.mesh
    centroid_x = mesh.vertices[mesh.triangles].mean(axis=1)[:, 0]
    inside = (centroid_x > 11.5) & (centroid_x < 30.5)
    assert lined.shotcrete_triangles > 1000
    assert set(np.unique(mesh.material[inside])) == {Material.SMOOTH_SHOTCRETE}
    outside = (centroid_x > 40.0) & (centroid_x < 58.0)
    for kind in (Material.STEEL, Material.PIPE, Material.CABLE, Material.FLOOR):
        assert np.any(mesh.material[outside] == kind)


def test_shotcrete_lining_has_no_corners_and_little_gradient(lined):
    """Facing the wall from 2.2 m: the lining against rock with arches and against the older,
    bolted shotcrete section (same renderer, same light, no sensor noise)."""
    plain = Simulator(_small(preset="straight", noise=False))
    views = {
        "lined": _wall_view(lined, 21.0),
        "rock": _wall_view(lined, 50.0),
        "bolted": _wall_view(plain, 23.0),
    }
    assert np.mean(views["lined"][1] == Material.SMOOTH_SHOTCRETE) > 0.95
    assert np.mean(views["bolted"][1] == Material.SHOTCRETE) > 0.5
    assert np.any(views["rock"][1] == Material.STEEL)
    lined_image = views["lined"][0]
    assert 60 < np.median(lined_image) < 200  # lit, not black: the light is there
    orb = Orb()
    corners = {k: len(orb.detect(image).uv) for k, (image, _) in views.items()}
    energy = {k: _gradient_energy(image) for k, (image, _) in views.items()}
    assert corners["rock"] > 100 and corners["bolted"] > 10, corners
    assert corners["lined"] <= 0.05 * corners["rock"], corners
    assert corners["lined"] < corners["bolted"], corners
    assert energy["lined"] < 0.05 * energy["rock"], energy
    assert energy["lined"] < 0.1 * energy["bolted"], energy


def _along_view(sim: Simulator, x: float) -> tuple[np.ndarray, np.ndarray]:
    """Looking along the roadway (+x) at light 1.0: walls and floor seen at grazing angles."""
    return _view(sim, x, ALONG_ROADWAY, 1.0)


def test_shotcrete_relief_shades_a_faint_texture_along_the_roadway(lined):
    """The lining's relief (shotcrete_relief_m) is seen where the headlamp grazes walls and
    floor: more gradient and corners than the flat lining, far fewer than rock with arches; the
    relief is a property of the world point (two renders agree exactly)."""
    relief = Simulator(_small(noise=False, shotcrete_relief_m=0.006, **LINED))
    flat_image, material = _along_view(lined, 12.0)
    relief_image, _ = _along_view(relief, 12.0)
    rock_image, _ = _along_view(lined, 41.0)
    near = material == Material.SMOOTH_SHOTCRETE
    assert near.mean() > 0.7
    np.testing.assert_array_equal(relief_image, _along_view(relief, 12.0)[0])

    def energy(image: np.ndarray) -> float:
        """Mean squared detail [gray levels^2]: the image less its 3-pixel blur (the headlamp's
        smooth falloff removed), on the lining's pixels away from the border."""
        img = image.astype(np.float64)
        detail = (img - ndimage.gaussian_filter(img, 3.0)) ** 2
        return float(detail[8:-8, 8:-8][near[8:-8, 8:-8]].mean())

    orb = Orb()
    corners = {
        k: len(orb.detect(v).uv)
        for k, v in (("flat", flat_image), ("relief", relief_image), ("rock", rock_image))
    }
    assert energy(relief_image) > 2.0 * energy(flat_image)
    assert energy(relief_image) < 0.2 * energy(rock_image)
    assert corners["relief"] > corners["flat"], corners


def test_stop_is_at_rest_in_ground_truth_and_imu(tmp_path):
    """3 s standing still, then a 90 degree turn on the spot: velocity exactly zero, the
    noiseless IMU reads gravity only (no rotation) during the stop, and the turn's rate after."""
    options = _small(
        preset="straight",
        frames=300,  # 15 s of ground truth and IMU; no images
        cameras=False,
        noise=False,
        spin_at_s=6.0,
        stop_duration_s=3.0,
        spin_deg=90.0,
        spin_duration_s=4.0,
    )
    out = tmp_path / "seq"
    Simulator(options).write(out, progress=False)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["options"]["stop_duration_s"] == 3.0
    gt = np.loadtxt(out / "mav0/state_groundtruth_estimate0/data.csv", delimiter=",")
    imu = np.loadtxt(out / "mav0/imu0/data.csv", delimiter=",")
    t_gt = (gt[:, 0] - gt[0, 0]) * 1e-9
    t_imu = (imu[:, 0] - imu[0, 0]) * 1e-9
    stop_gt = (t_gt >= 6.0) & (t_gt <= 9.0)
    stop_imu = (t_imu >= 6.0) & (t_imu <= 9.0)
    assert np.count_nonzero(stop_imu) == 601  # 3 s at 200 Hz, both ends
    assert np.abs(gt[stop_gt, 8:11]).max() < 1e-9  # velocity
    assert np.ptp(gt[stop_gt, 1:8], axis=0).max() < 1e-9  # position and orientation
    assert np.abs(imu[stop_imu, 1:4]).max() < 1e-9  # no rotation
    np.testing.assert_allclose(np.linalg.norm(imu[stop_imu, 4:7], axis=1), 9.81, atol=1e-8)
    turning = (t_imu > 9.5) & (t_imu < 12.5)
    assert np.abs(imu[turning, 1:3]).max() < 1e-9 and imu[turning, 3].min() > 0.05
    moving = t_gt < 3.5
    assert np.linalg.norm(gt[moving, 8:11], axis=1)[-1] > 0.7  # driving before the stop


def test_blackout_lasts_the_configured_time():
    sim = Simulator(
        _small(frames=200, blackout=True, blackout_s=4.0, blackout_at_s=2.5, noise=False)
    )
    dark = np.flatnonzero([sim.light_level(i) == 0.0 for i in range(200)])
    assert len(dark) == 80 and dark[0] == 50 and dark[-1] == 129  # 4 s at 20 Hz from 2.5 s
    assert np.all(np.diff(dark) == 1)
    assert sim.render_stereo(90)[0].max() == 0 < sim.render_stereo(40)[0].mean()
    # without a start time the blackout stays centred mid-run, as before
    centred = Simulator(_small(frames=200, blackout=True, blackout_s=4.0))
    dark = np.flatnonzero([centred.light_level(i) == 0.0 for i in range(200)])
    assert len(dark) == 79 and dark[0] == 61 and dark[-1] == 139  # |t - 5 s| < 2 s


def test_dead_end_branch_ends_in_a_face():
    sim = Simulator(_small(preset="dead_end", frames=2))
    hits = sim.scene.cast(np.array([10.0, 28.0, 1.0]), np.array([[0.0, 1.0, 0.0]]))
    assert hits.t[0] == pytest.approx(2.0, abs=1e-3)  # the face 2 m beyond the path's end


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"shotcrete_length_m": -1.0}, "shotcrete_length_m"),
        ({"shotcrete_start_m": float("nan"), "shotcrete_length_m": 5.0}, "shotcrete_start_m"),
        ({"blackout": True, "blackout_s": 0.0}, "blackout_s"),
        ({"blackout": True, "blackout_at_s": 30.0, "frames": 100}, "blackout_at_s"),
        ({"spin_at_s": 8.0, "stop_duration_s": -1.0}, "stop_duration_s"),
        ({"shotcrete_relief_m": 0.2}, "shotcrete_relief_m"),
        ({"shotcrete_relief_m": float("nan")}, "shotcrete_relief_m"),
    ],
)
def test_bad_hard_case_options_name_the_key(kwargs, key):
    with pytest.raises(InputError, match=key):
        SimOptions(**kwargs).check()


def test_shotcrete_past_the_path_end_is_refused():
    with pytest.raises(InputError, match=r"shotcrete_start_m: 500\.0 m is past the end"):
        Simulator(_small(preset="junction", shotcrete_start_m=500.0, shotcrete_length_m=20.0))


def test_cli_sim_shotcrete_reaches_the_manifest(tmp_path, capsys):
    out = tmp_path / "x"
    args = ["sim", "--out", str(out), "--preset", "dead_end", "--frames", "2", "--no-lidar"]
    assert main([*args, "--shotcrete-start", "11", "--shotcrete-length", "26"]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["options"]["shotcrete_start_m"] == 11.0
    assert manifest["options"]["shotcrete_length_m"] == 26.0
    assert manifest["shotcrete_triangles"] > 1000
    bad = ["sim", "--out", str(tmp_path / "y"), "--frames", "2", "--shotcrete-length", "-3"]
    assert main(bad) == 2
    assert "shotcrete_length_m: must be a distance >= 0" in capsys.readouterr().err
    assert not (tmp_path / "y" / "mav0").exists()


@pytest.fixture(scope="module")
def hard_cases():
    yield from load_benchmark("hard_cases.py")


def test_hard_cases_are_valid_and_their_hard_parts_are_where_intended(hard_cases):
    for name, frames in hard_cases.CASE_FRAMES.items():
        options = SimOptions(frames=frames, **hard_cases.SEQUENCES[name])
        options.check()
        assert options.shotcrete_length_m >= 15.0 or options.blackout_s > 2.0
    hard = hard_cases.hard_frames("shotcrete_branch", hard_cases.CASE_FRAMES["shotcrete_branch"])
    spin = hard_cases.SEQUENCES["shotcrete_branch"]["spin_at_s"] * 20
    # the stop and the whole turn (24.5 ... 33.5 s) lie inside the lining, which runs to the end
    assert np.all(np.isin(np.arange(round(spin), round(spin) + 9 * 20), hard))
    assert hard[-1] == hard_cases.CASE_FRAMES["shotcrete_branch"] - 1
    hard = hard_cases.hard_frames("blackout_long", hard_cases.CASE_FRAMES["blackout_long"])
    assert len(hard) == 80 and hard[0] == 160
    hard = hard_cases.hard_frames("shotcrete_l100", hard_cases.CASE_FRAMES["shotcrete_l100"])
    assert len(hard) == pytest.approx(16.0 / 0.8 * 20, abs=3)  # 16 m at 0.8 m/s
