"""Robot trajectories of the roadway simulator and their IMU (slslam.sim.trajectory)."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from slslam.errors import InputError
from slslam.sim.trajectory import (
    GRAVITY_WORLD,
    ImuNoise,
    RobotTrajectory,
    TrajectoryOptions,
)

QUIET = TrajectoryOptions(vibration_amplitude_m=0.0, roll_pitch_amplitude_deg=0.0)


def rounded_rectangle(width: float = 30.0, height: float = 16.0, radius: float = 4.0) -> np.ndarray:
    """Closed centreline (first == last), counter-clockwise, 0.25 m spacing, z = 0."""
    w, h, r = width / 2 - radius, height / 2 - radius, radius
    corners = [(w, h), (-w, h), (-w, -h), (w, -h)]
    parts = []
    for i, (cx, cy) in enumerate(corners):
        a = np.linspace(i * np.pi / 2, (i + 1) * np.pi / 2, 26)
        parts.append(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))
    ring = np.vstack([*parts, parts[0][:1]])
    dense = [ring[:1]]
    for a, b in itertools.pairwise(ring):
        n = max(int(np.linalg.norm(b - a) / 0.25), 1)
        dense.append(a + (b - a) * np.linspace(0.0, 1.0, n + 1)[1:, None])
    xy = np.vstack(dense)
    return np.column_stack([xy, np.zeros(len(xy))])


def straight(length: float = 40.0) -> np.ndarray:
    return np.array([[0.0, 0.0, 0.0], [length, 0.0, 0.0]])


def sloped_s_curve() -> np.ndarray:
    """An open S-shaped roadway climbing at 5 %."""
    x = np.linspace(0.0, 40.0, 161)
    return np.column_stack([x, 3.0 * np.sin(x / 8.0), 0.05 * x])


CASES = {
    "loop": (rounded_rectangle, TrajectoryOptions()),
    "straight": (straight, TrajectoryOptions(speed_mps=1.2)),
    "sloped_offset": (
        sloped_s_curve,
        TrajectoryOptions(lateral_offset_m=0.5, body_height_m=0.3, seed=3),
    ),
}


def integrate_imu(
    imu: dict[str, np.ndarray], i0: int, n: int, p, v, R, gravity=GRAVITY_WORLD
) -> tuple[np.ndarray, np.ndarray]:
    """Strapdown integration from sample i0 over n steps: rotation by the exp map of the mid-point
    gyro, velocity by the trapezoid rule, position exact for linearly varying acceleration."""
    t = imu["t_ns"] * 1e-9
    gyro, acc = imu["gyro"], imu["acc"]
    p, v, R = p.copy(), v.copy(), R.copy()
    for k in range(i0, i0 + n):
        dt = t[k + 1] - t[k]
        R1 = R @ Rotation.from_rotvec(0.5 * (gyro[k] + gyro[k + 1]) * dt).as_matrix()
        a0, a1 = R @ acc[k] + gravity, R1 @ acc[k + 1] + gravity
        p = p + v * dt + (2.0 * a0 + a1) / 6.0 * dt**2
        v = v + 0.5 * (a0 + a1) * dt
        R = R1
    return p, R


def imu_errors(traj: RobotTrajectory, gravity=GRAVITY_WORLD) -> tuple[float, float]:
    """Max position [m] and rotation [deg] error of 1 s integrations from several start times."""
    imu = traj.imu(rate_hz=200.0)
    t = imu["t_ns"] * 1e-9
    starts = np.linspace(0.0, traj.duration_s - 1.1, 9)
    pos_err, rot_err = 0.0, 0.0
    for t0 in starts:
        i0 = int(np.searchsorted(t, t0))
        p0, v0, R0 = traj.position(t[i0])[0], traj.velocity(t[i0])[0], traj.rotation(t[i0])[0]
        p, R = integrate_imu(imu, i0, 200, p0, v0, R0, gravity)
        p_true, R_true = traj.position(t[i0 + 200])[0], traj.rotation(t[i0 + 200])[0]
        pos_err = max(pos_err, float(np.linalg.norm(p - p_true)))
        angle = np.linalg.norm(Rotation.from_matrix(R_true.T @ R).as_rotvec())
        rot_err = max(rot_err, float(np.rad2deg(angle)))
    return pos_err, rot_err


@pytest.mark.parametrize("name", list(CASES))
def test_imu_integrates_back_to_the_poses(name: str) -> None:
    make, options = CASES[name]
    traj = RobotTrajectory(make(), options=options)
    pos_err, rot_err = imu_errors(traj)
    print(f"{name}: max position error {pos_err:.2e} m, rotation error {rot_err:.2e} deg")
    assert pos_err < 0.01
    assert rot_err < 0.1


def test_imu_integration_without_gravity_fails() -> None:
    traj = RobotTrajectory(rounded_rectangle())
    pos_err, _ = imu_errors(traj, gravity=np.zeros(3))
    assert pos_err > 1.0  # 0.5 * 9.81 m/s^2 * (1 s)^2 ~ 4.9 m


def test_imu_at_rest_measures_gravity_only() -> None:
    imu = RobotTrajectory(straight(), options=QUIET).imu()
    np.testing.assert_allclose(imu["acc"][0], [0.0, 0.0, 9.81], atol=1e-9)
    np.testing.assert_allclose(imu["gyro"][0], 0.0, atol=1e-12)
    assert imu["t_ns"].dtype == np.int64
    assert np.all(np.diff(imu["t_ns"]) == 5_000_000)


@pytest.mark.parametrize("make", [rounded_rectangle, straight])
def test_speed_is_cruise_speed_after_the_ramp(make) -> None:
    traj = RobotTrajectory(make(), options=QUIET)
    t = np.linspace(0.0, traj.duration_s, 5001)
    speed = np.linalg.norm(traj.velocity(t), axis=1)
    assert speed[0] == 0.0
    assert np.all(np.diff(speed[t <= QUIET.accel_time_s]) >= -1e-9)
    np.testing.assert_allclose(speed[t >= QUIET.accel_time_s], QUIET.speed_mps, atol=1e-3)
    # with vibration the along-track (horizontal) speed on a flat roadway is still the cruise speed
    vib = RobotTrajectory(make(), options=TrajectoryOptions())
    horizontal = np.linalg.norm(vib.velocity(t)[:, :2], axis=1)
    np.testing.assert_allclose(horizontal[t >= 2.0], 0.8, atol=1e-3)


def test_closed_loop_is_driven_once() -> None:
    traj = RobotTrajectory(rounded_rectangle(), options=QUIET)
    assert traj.closed
    p = traj.position([0.0, traj.duration_s])
    np.testing.assert_allclose(p[0], p[1], atol=1e-6)


@pytest.mark.parametrize("options", [QUIET, TrajectoryOptions()])
def test_acceleration_is_continuous(options: TrajectoryOptions) -> None:
    traj = RobotTrajectory(rounded_rectangle(), options=options)
    acc = traj.acceleration(np.arange(0.0, traj.duration_s, 1e-3))
    if options.vibration_amplitude_m == 0:
        # jerk below 10 m/s^3: a curvature jump of 1/4 m^-1 at 0.8 m/s would jump by 0.16 m/s^2
        assert np.abs(np.diff(acc, axis=0)).max() < 0.01
    else:  # vibration makes the jerk large but smooth: second differences stay small
        assert np.abs(np.diff(acc, n=2, axis=0)).max() < 0.02


def assert_derivatives_match_finite_differences(traj: RobotTrajectory, t: np.ndarray) -> None:
    """Analytic velocity, acceleration and body angular velocity at times ``t`` against central
    (and, for rotation, forward) differences of position, velocity and rotation."""
    dt = 1e-4
    dp = (traj.position(t + dt) - traj.position(t - dt)) / (2 * dt)
    np.testing.assert_allclose(traj.velocity(t), dp, atol=1e-5)
    dv = (traj.velocity(t + dt) - traj.velocity(t - dt)) / (2 * dt)
    np.testing.assert_allclose(traj.acceleration(t), dv, atol=1e-4)
    R0, R1 = traj.rotation(t), traj.rotation(t + dt)
    w_num = Rotation.from_matrix(np.einsum("nji,njk->nik", R0, R1)).as_rotvec() / dt
    np.testing.assert_allclose(traj.angular_velocity_body(t + dt / 2), w_num, atol=1e-6)


@pytest.mark.parametrize("name", list(CASES))
def test_derivatives_match_finite_differences(name: str) -> None:
    make, options = CASES[name]
    traj = RobotTrajectory(make(), options=options)
    t = np.linspace(0.01, traj.duration_s - 0.01, 1501)
    assert_derivatives_match_finite_differences(traj, t)


def test_pose_is_rigid_and_follows_the_path() -> None:
    traj = RobotTrajectory(rounded_rectangle(), options=QUIET)
    t = np.linspace(3.0, traj.duration_s, 400)
    T = traj.pose(t)
    R = T[:, :3, :3]
    np.testing.assert_allclose(
        np.einsum("nji,njk->nik", R, R), np.tile(np.eye(3), (400, 1, 1)), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    np.testing.assert_allclose(T[:, :3, 3], traj.position(t))
    np.testing.assert_allclose(T[:, 3], np.tile([0.0, 0, 0, 1], (400, 1)))
    forward = traj.velocity(t) / np.linalg.norm(traj.velocity(t), axis=1, keepdims=True)
    np.testing.assert_allclose(R[:, :, 0], forward, atol=1e-6)  # body x along the motion
    np.testing.assert_allclose(R[:, :, 2], np.tile([0.0, 0, 1], (400, 1)), atol=1e-9)


@pytest.mark.parametrize(
    ("centreline", "duration", "message"),
    [
        (np.zeros((1, 3)), None, "at least 2 points"),
        (np.array([[0.0, 0, 0], [np.nan, 1, 0]]), None, "NaN"),
        (np.zeros((4, 2)), None, r"\(M, 3\)"),
        (np.zeros((3, 3)), None, "zero length"),
        (straight(10.0), 20.0, "more than the 10.00 m path"),
        (straight(0.5), None, "ramp"),
        (straight(10.0), -1.0, "must be > 0"),
    ],
)
def test_bad_centreline_or_duration_raises(centreline, duration, message) -> None:
    with pytest.raises(ValueError, match=message):
        RobotTrajectory(centreline, duration_s=duration)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed_mps": -0.8}, "speed_mps must be > 0"),
        ({"speed_mps": float("nan")}, "speed_mps must be finite"),
        ({"accel_time_s": -1.0}, "accel_time_s must be >= 0"),
        ({"vibration_freq_hz": 0.0}, "vibration_freq_hz"),
        ({"seed": -1}, "seed"),
    ],
)
def test_bad_options_raise(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        TrajectoryOptions(**kwargs)


def test_times_outside_the_trajectory_raise() -> None:
    traj = RobotTrajectory(straight(10.0))
    with pytest.raises(ValueError, match="must lie in"):
        traj.pose([traj.duration_s + 0.1])


def test_same_seed_gives_identical_arrays() -> None:
    t = np.linspace(0.0, 20.0, 300)
    a = RobotTrajectory(rounded_rectangle(), options=TrajectoryOptions(seed=7))
    b = RobotTrajectory(rounded_rectangle(), options=TrajectoryOptions(seed=7))
    c = RobotTrajectory(rounded_rectangle(), options=TrajectoryOptions(seed=8))
    np.testing.assert_array_equal(a.pose(t), b.pose(t))
    assert not np.array_equal(a.pose(t), c.pose(t))
    noise = ImuNoise()
    imu_a, imu_b = a.imu(noise=noise, seed=1), b.imu(noise=noise, seed=1)
    for key in imu_a:
        np.testing.assert_array_equal(imu_a[key], imu_b[key])
    assert not np.array_equal(imu_a["gyro"], a.imu(noise=noise, seed=2)["gyro"])


def test_imu_noise_statistics_match_the_densities() -> None:
    traj = RobotTrajectory(rounded_rectangle())
    rate = 200.0
    noise = ImuNoise()
    exact, noisy = traj.imu(rate), traj.imu(rate, noise=noise, seed=5)
    np.testing.assert_array_equal(exact["t_ns"], noisy["t_ns"])
    for key, density, walk in (
        ("gyro", noise.gyroscope_noise_density, noise.gyroscope_random_walk),
        ("acc", noise.accelerometer_noise_density, noise.accelerometer_random_walk),
    ):
        bias = noisy[key + "_bias"]
        white = noisy[key] - exact[key] - bias
        np.testing.assert_allclose(white.std(axis=0), density * np.sqrt(rate), rtol=0.1)
        np.testing.assert_allclose(
            np.diff(bias, axis=0).std(axis=0), walk / np.sqrt(rate), rtol=0.1
        )
        assert np.all(bias[0] == 0.0)


# --- turn on the spot ----------------------------------------------------------------------------

SPIN_AT, SPIN_S, RAMP_S = 10.0, 6.0, 2.0


def spin_options(spin_deg: float = 360.0, **kwargs) -> TrajectoryOptions:
    return TrajectoryOptions(spin_at_s=SPIN_AT, spin_deg=spin_deg, spin_duration_s=SPIN_S, **kwargs)


def spin_junctions() -> np.ndarray:
    """Times [s] where the speed profile changes piece: stop ramp, rest, go ramp, cruise."""
    return np.array([SPIN_AT - RAMP_S, SPIN_AT, SPIN_AT + SPIN_S, SPIN_AT + SPIN_S + RAMP_S])


SPIN_CASES = {
    "loop_360": (rounded_rectangle, spin_options()),
    "straight_left_90": (straight, spin_options(90.0, speed_mps=1.2)),
    "sloped_offset_right_180": (
        sloped_s_curve,
        spin_options(-180.0, lateral_offset_m=0.5, body_height_m=0.3, seed=3),
    ),
}


@pytest.mark.parametrize("name", list(SPIN_CASES))
def test_spin_holds_position_and_turns_about_body_z(name: str) -> None:
    make, options = SPIN_CASES[name]
    traj = RobotTrajectory(make(), options=options)
    t = np.linspace(SPIN_AT, SPIN_AT + SPIN_S, 3001)
    p = traj.position(t)
    assert np.abs(p - p[0]).max() < 1e-9  # at rest: no motion, and vibration is frozen in s
    np.testing.assert_array_equal(traj.velocity(t), 0.0)
    # body angular velocity: about body z only, with the smoothstep rate of the turn
    turn = np.deg2rad(options.spin_deg)
    x = (t - SPIN_AT) / SPIN_S
    w = traj.angular_velocity_body(t)
    np.testing.assert_allclose(w[:, :2], 0.0, atol=1e-12)
    np.testing.assert_allclose(w[:, 2], turn / SPIN_S * 30.0 * x**2 * (1.0 - x) ** 2, atol=1e-12)
    assert w[1500, 2] == pytest.approx(1.875 * turn / SPIN_S)  # peak rate, half-way
    # the attitude turns about the body's own z axis by the yaw integrated so far
    R = traj.rotation(t)
    rel = Rotation.from_matrix(np.einsum("ji,njk->nik", R[0], R)).as_rotvec()
    psi = turn * x**3 * (x * (6.0 * x - 15.0) + 10.0)
    wrapped = np.angle(np.exp(1j * psi))
    np.testing.assert_allclose(rel[:, :2], 0.0, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (rel[:, 2] - wrapped))), 0.0, atol=1e-9)
    # the gyro integrates to the full turn (a 360 deg turn is not the identity here)
    yaw_turned = np.trapezoid(w[:, 2], t)
    assert np.rad2deg(yaw_turned) == pytest.approx(options.spin_deg, abs=1e-4)


def test_spin_yaw_offset_is_kept_for_the_rest_of_the_run() -> None:
    make, options = SPIN_CASES["straight_left_90"]
    traj = RobotTrajectory(make(), options=options)
    t = np.linspace(SPIN_AT + SPIN_S + RAMP_S, traj.duration_s, 50)
    v_xy = traj.velocity(t)[:, :2]
    forward = np.column_stack([v_xy / np.linalg.norm(v_xy, axis=1, keepdims=True), np.zeros(50)])
    R = traj.rotation(t)
    np.testing.assert_allclose(forward[:, :2], np.tile([1.0, 0.0], (50, 1)), atol=1e-9)
    # turned 90 deg left: body y (left) points backwards along the motion, body x to the left
    np.testing.assert_allclose(np.einsum("ni,ni->n", R[:, :, 1], forward), -1.0, atol=0.01)
    assert np.all(R[:, 1, 0] > 0.99)


def test_spin_before_and_after_matches_the_run_without_it() -> None:
    """Before the stop ramp the run is the plain one; the pause costs spin + ramp time."""
    plain = RobotTrajectory(straight(), options=QUIET)
    spin = RobotTrajectory(
        straight(),
        options=dataclasses.replace(QUIET, spin_at_s=SPIN_AT, spin_duration_s=SPIN_S),
    )
    assert spin.duration_s == pytest.approx(plain.duration_s + SPIN_S + RAMP_S)
    t = np.linspace(0.0, SPIN_AT - RAMP_S, 200)
    np.testing.assert_allclose(spin.pose(t), plain.pose(t), atol=1e-12)
    np.testing.assert_allclose(spin.position(spin.duration_s), plain.position(plain.duration_s))
    t_after = np.linspace(SPIN_AT + SPIN_S + RAMP_S, spin.duration_s, 200)
    np.testing.assert_allclose(np.linalg.norm(spin.velocity(t_after), axis=1), 0.8, atol=1e-9)
    # the stop: speed falls monotonically to exactly zero at spin_at_s
    t_stop = np.linspace(SPIN_AT - RAMP_S, SPIN_AT, 400)
    speed = np.linalg.norm(spin.velocity(t_stop), axis=1)
    assert np.all(np.diff(speed) <= 1e-12) and speed[-1] == 0.0


@pytest.mark.parametrize("name", list(SPIN_CASES))
def test_spin_profile_is_continuous_at_its_junctions(name: str) -> None:
    make, options = SPIN_CASES[name]
    traj = RobotTrajectory(make(), options=options)
    h = 1e-7
    for tj in spin_junctions():
        before, after = tj - h, tj + h
        v0, v1 = traj.velocity(before)[0], traj.velocity(after)[0]
        a0, a1 = traj.acceleration(before)[0], traj.acceleration(after)[0]
        w0, w1 = traj.angular_velocity_body(before)[0], traj.angular_velocity_body(after)[0]
        assert np.abs(v1 - v0).max() < 1e-5, f"velocity jumps at {tj} s"
        assert np.abs(a1 - a0).max() < 1e-4, f"acceleration jumps at {tj} s"
        assert np.abs(w1 - w0).max() < 1e-5, f"angular velocity jumps at {tj} s"
    # analytic derivatives across the whole spin agree with finite differences
    t = np.linspace(SPIN_AT - RAMP_S - 0.5, SPIN_AT + SPIN_S + RAMP_S + 0.5, 1201)
    assert_derivatives_match_finite_differences(traj, t)
    dt = 1e-4
    # the yaw offset's second derivative matches its first (smooth angular acceleration)
    psi, psi_d, psi_dd = traj._spin_yaw(t)
    num_dd = (traj._spin_yaw(t + dt)[1] - traj._spin_yaw(t - dt)[1]) / (2 * dt)
    np.testing.assert_allclose(psi_dd, num_dd, atol=1e-6)
    np.testing.assert_allclose(psi_d, np.gradient(psi, t), atol=2e-3)


@pytest.mark.parametrize("name", list(SPIN_CASES))
def test_imu_integrates_back_to_the_poses_across_the_spin(name: str) -> None:
    make, options = SPIN_CASES[name]
    traj = RobotTrajectory(make(), options=options)
    pos_err, rot_err = imu_errors(traj)  # 1 s windows over the whole run, as without a spin
    imu = traj.imu(rate_hz=200.0)
    t = imu["t_ns"] * 1e-9
    # one integration from cruise before the stop to cruise after the restart
    i0 = int(np.searchsorted(t, SPIN_AT - RAMP_S - 0.5))
    i1 = int(np.searchsorted(t, SPIN_AT + SPIN_S + RAMP_S + 0.5))
    p0, v0, R0 = traj.position(t[i0])[0], traj.velocity(t[i0])[0], traj.rotation(t[i0])[0]
    p, R = integrate_imu(imu, i0, i1 - i0, p0, v0, R0)
    p_true, R_true = traj.position(t[i1])[0], traj.rotation(t[i1])[0]
    pos_err = max(pos_err, float(np.linalg.norm(p - p_true)))
    angle = np.linalg.norm(Rotation.from_matrix(R_true.T @ R).as_rotvec())
    rot_err = max(rot_err, float(np.rad2deg(angle)))
    print(f"{name}: max position error {pos_err:.2e} m, rotation error {rot_err:.2e} deg")
    assert pos_err < 0.01
    assert rot_err < 0.1


def test_spin_off_is_the_run_without_spin_options() -> None:
    """spin_deg / spin_duration_s do nothing without spin_at_s: identical arrays."""
    t = np.linspace(0.0, 20.0, 300)
    a = RobotTrajectory(rounded_rectangle(), options=TrajectoryOptions(seed=7))
    b = RobotTrajectory(
        rounded_rectangle(), options=TrajectoryOptions(seed=7, spin_deg=90.0, spin_duration_s=3.0)
    )
    np.testing.assert_array_equal(a.pose(t), b.pose(t))
    np.testing.assert_array_equal(a.imu()["gyro"], b.imu()["gyro"])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"spin_at_s": float("nan")}, "spin_at_s must be finite"),
        ({"spin_at_s": 3.0}, r"spin_at_s must be >= 2 \* accel_time_s = 4.0 s"),
        ({"spin_at_s": 10.0, "spin_duration_s": 0.0}, "spin_duration_s must be > 0"),
        ({"spin_at_s": 10.0, "spin_duration_s": -2.0}, "spin_duration_s must be > 0"),
        ({"spin_at_s": 10.0, "spin_deg": float("inf")}, "spin_deg must be finite"),
        ({"spin_at_s": 10.0, "spin_deg": 1000.0}, "spin_deg must be in"),
        ({"spin_at_s": 10.0, "accel_time_s": 0.0}, "accel_time_s must be > 0 with spin_at_s"),
    ],
)
def test_bad_spin_options_raise(kwargs, message) -> None:
    with pytest.raises(InputError, match=message):
        TrajectoryOptions(**kwargs)


def test_spin_beyond_the_path_raises() -> None:
    # stops at 0.8 * (20 - 2) = 14.4 m of a 10 m path
    with pytest.raises(InputError, match=r"spin_at_s: 20.0 s stops the robot at 14.40 m"):
        RobotTrajectory(straight(10.0), options=TrajectoryOptions(spin_at_s=20.0))
    # and a duration longer than the path allows, pause included, is refused as before
    traj = RobotTrajectory(straight(), options=spin_options())
    with pytest.raises(InputError, match=r"more than the 40\.00 m path"):
        RobotTrajectory(straight(), duration_s=traj.duration_s + 0.1, options=spin_options())


def test_stop_before_the_spin_is_exact_rest_and_the_imu_integrates_across_it() -> None:
    """stop_duration_s: at rest (velocity, angular velocity zero; the accelerometer reads
    gravity only) from spin_at_s for that long, then the turn; C2 at every junction, and the
    IMU integrates from cruise before the stop to cruise after the restart."""
    stop = 3.0
    options = dataclasses.replace(spin_options(90.0), stop_duration_s=stop)
    traj = RobotTrajectory(rounded_rectangle(), options=options)
    plain = RobotTrajectory(rounded_rectangle(), options=spin_options(90.0))
    assert traj.duration_s == pytest.approx(plain.duration_s + stop)
    t = np.linspace(SPIN_AT, SPIN_AT + stop, 601)
    np.testing.assert_array_equal(traj.velocity(t), 0.0)
    np.testing.assert_array_equal(traj.angular_velocity_body(t), 0.0)
    assert np.abs(traj.position(t) - traj.position(SPIN_AT)).max() < 1e-12
    imu = traj.imu(rate_hz=200.0)
    at_rest = (imu["t_ns"] >= SPIN_AT * 1e9) & (imu["t_ns"] <= (SPIN_AT + stop) * 1e9)
    assert np.count_nonzero(at_rest) == 601
    np.testing.assert_allclose(imu["gyro"][at_rest], 0.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(imu["acc"][at_rest], axis=1), 9.81, atol=1e-12)
    # the turn is the plain spin's, shifted by the stop
    t_turn = np.linspace(SPIN_AT, SPIN_AT + SPIN_S, 301)
    np.testing.assert_allclose(
        traj.angular_velocity_body(t_turn + stop), plain.angular_velocity_body(t_turn), atol=1e-12
    )
    h = 1e-7
    for tj in (
        *spin_junctions()[:2],
        SPIN_AT + stop,
        SPIN_AT + stop + SPIN_S,
        SPIN_AT + stop + SPIN_S + RAMP_S,
    ):
        for f, tol in (
            (traj.velocity, 1e-5),
            (traj.acceleration, 1e-4),
            (traj.angular_velocity_body, 1e-5),
        ):
            assert np.abs(f(tj + h)[0] - f(tj - h)[0]).max() < tol, f"{f.__name__} jumps at {tj} s"
    t = imu["t_ns"] * 1e-9
    i0 = int(np.searchsorted(t, SPIN_AT - RAMP_S - 0.5))
    i1 = int(np.searchsorted(t, SPIN_AT + stop + SPIN_S + RAMP_S + 0.5))
    p0, v0, R0 = traj.position(t[i0])[0], traj.velocity(t[i0])[0], traj.rotation(t[i0])[0]
    p, R = integrate_imu(imu, i0, i1 - i0, p0, v0, R0)
    assert np.linalg.norm(p - traj.position(t[i1])[0]) < 0.01
    angle = np.linalg.norm(Rotation.from_matrix(traj.rotation(t[i1])[0].T @ R).as_rotvec())
    assert np.rad2deg(angle) < 0.1
