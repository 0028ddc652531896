"""Smooth robot trajectories along a roadway centreline and the matching 6-axis IMU.

Conventions: ``T_world_body`` maps body coordinates to world coordinates; metres, seconds,
timestamps ``t_ns`` in int64 nanoseconds. World frame: z up, gravity ``(0, 0, -9.81)`` m/s^2. Body
frame: x forward, y left, z up (the IMU frame).

The centreline polyline is resampled, lightly smoothed and fitted with a quintic spline that is
parametrised by arc length ``s``. The robot moves along it with ``s(t)``: a quintic smoothstep
ramp from rest to cruise speed, then constant speed. Optionally the robot stops and turns on
the spot: it slows to rest with the mirrored ramp, stands still for ``stop_duration_s``, stays
at ``s`` constant while a yaw offset ``psi(t)`` (quintic smoothstep) turns it about its own up
axis, then ramps back to cruise speed.
Ground-induced vibration (height, roll, pitch) is a sum of sinusoids in ``s``, so it vanishes at
rest and has ``vibration_freq_hz`` at cruise speed. Every quantity (velocity, acceleration,
angular velocity) is analytic: derivatives of the spline and the chain rule, never finite
differences, so the IMU integrates back to the poses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.integrate import cumulative_simpson
from scipy.interpolate import BSpline, make_interp_spline
from scipy.ndimage import gaussian_filter1d

from slslam.errors import InputError

#: Gravity in the world frame [m/s^2].
GRAVITY_WORLD = np.array([0.0, 0.0, -9.81])
#: Spacing of the resampled centreline before the spline fit [m].
RESAMPLE_STEP_M = 0.25
#: Relative frequencies and weights of the vibration components (weights sum to 1).
_VIB_WEIGHTS = np.array([0.6, 0.25, 0.15])
_VIB_FREQ_RANGES = ((1.0, 1.0), (1.3, 1.9), (2.2, 3.0))
#: Largest turn on the spot [deg] (two full turns); larger values are likely unit mistakes.
MAX_SPIN_DEG = 720.0


def _require(ok: bool, source: str, problem: str) -> None:
    if not ok:
        raise InputError(source, problem)


@dataclass(frozen=True)
class ImuNoise:
    """Continuous-time IMU noise model (EuRoC / ADIS16448-like defaults)."""

    gyroscope_noise_density: float = 1.6968e-04  # rad/s/sqrt(Hz)
    gyroscope_random_walk: float = 1.9393e-05  # rad/s^2/sqrt(Hz)
    accelerometer_noise_density: float = 2.0e-3  # m/s^2/sqrt(Hz)
    accelerometer_random_walk: float = 3.0e-3  # m/s^3/sqrt(Hz)

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            _require(np.isfinite(value) and value >= 0, "ImuNoise", f"{name} = {value} < 0")


@dataclass(frozen=True)
class TrajectoryOptions:
    """How the robot drives along the centreline."""

    speed_mps: float = 0.8  # cruise speed [m/s]
    accel_time_s: float = 2.0  # quintic-smoothstep ramp from rest to cruise speed [s]
    body_height_m: float = 0.0  # added to the centreline z [m]
    lateral_offset_m: float = 0.0  # constant offset to the left of the centreline [m]
    vibration_amplitude_m: float = 0.003  # peak vertical track vibration [m]
    vibration_freq_hz: float = 3.0  # main vibration frequency at cruise speed [Hz]
    roll_pitch_amplitude_deg: float = 0.3  # peak roll / pitch vibration [deg]
    seed: int = 0  # picks vibration phases and frequencies
    corner_smoothing_m: float = 0.5  # Gaussian smoothing of the centreline (sigma) [m]; 0 = none
    # Turn on the spot: the robot decelerates over accel_time_s to rest at spin_at_s [s] (None =
    # no turn), turns spin_deg [deg] (> 0 = left) about its up axis in spin_duration_s [s], then
    # accelerates over accel_time_s back to cruise speed. The turn is kept for the rest of the
    # run: a multiple of 360 drives on facing forward; any other angle leaves the body (and the
    # cameras) turned away from the direction of travel, e.g. 180 drives on looking backwards, a
    # purely kinematic motion that a real skid-steer robot would not make.
    spin_at_s: float | None = None
    spin_deg: float = 360.0
    spin_duration_s: float = 6.0
    # With spin_at_s: the robot stands still for stop_duration_s [s] at rest before the turn
    # starts (velocity and angular velocity exactly zero; spin_deg = 0 makes it a plain stop).
    stop_duration_s: float = 0.0

    def __post_init__(self) -> None:
        self.check()

    def check(self) -> None:
        """Raise :class:`slslam.InputError` (a ``ValueError``) naming the first bad value."""
        src = "TrajectoryOptions"
        for name, value in vars(self).items():
            if name == "spin_at_s" and value is None:
                continue
            _require(np.isfinite(value), src, f"{name} must be finite, got {value}")
        _require(self.speed_mps > 0, src, f"speed_mps must be > 0, got {self.speed_mps}")
        for name in (
            "accel_time_s",
            "vibration_amplitude_m",
            "corner_smoothing_m",
            "stop_duration_s",
        ):
            value = getattr(self, name)
            _require(value >= 0, src, f"{name} must be >= 0, got {value}")
        _require(self.vibration_freq_hz > 0, src, "vibration_freq_hz must be > 0")
        _require(
            0 <= self.roll_pitch_amplitude_deg <= 10,
            src,
            f"roll_pitch_amplitude_deg must be in [0, 10], got {self.roll_pitch_amplitude_deg}",
        )
        _require(
            isinstance(self.seed, int | np.integer) and self.seed >= 0,
            src,
            f"seed must be an int >= 0, got {self.seed!r}",
        )
        if self.spin_at_s is not None:
            self._check_spin(src)

    def _check_spin(self, src: str) -> None:
        assert self.spin_at_s is not None  # checked by the caller
        ta = self.accel_time_s
        _require(ta > 0, src, "accel_time_s must be > 0 with spin_at_s (a smooth stop)")
        _require(
            self.spin_at_s >= 2.0 * ta,
            src,
            f"spin_at_s must be >= 2 * accel_time_s = {2.0 * ta} s (ramp up to cruise speed, "
            f"then down to rest), got {self.spin_at_s}",
        )
        _require(
            self.spin_duration_s > 0,
            src,
            f"spin_duration_s must be > 0, got {self.spin_duration_s}",
        )
        _require(
            abs(self.spin_deg) <= MAX_SPIN_DEG,
            src,
            f"spin_deg must be in [-{MAX_SPIN_DEG}, {MAX_SPIN_DEG}], got {self.spin_deg}",
        )


class _Vibration:
    """``f(s) = amplitude * sum_i w_i sin(k_i s + phase_i)``; ``k_i`` in rad/m."""

    def __init__(self, amplitude: float, wavenumber: float, rng: np.random.Generator) -> None:
        ratios = np.array([rng.uniform(lo, hi) for lo, hi in _VIB_FREQ_RANGES])
        self.k = wavenumber * ratios
        self.phase = rng.uniform(0.0, 2.0 * np.pi, size=len(ratios))
        self.w = amplitude * _VIB_WEIGHTS

    def __call__(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value, first and second derivative with respect to ``s``."""
        arg = np.outer(s, self.k) + self.phase
        sin, cos = np.sin(arg), np.cos(arg)
        return sin @ self.w, cos @ (self.w * self.k), -(sin @ (self.w * self.k**2))


class _State(NamedTuple):
    position: np.ndarray  # (N, 3) world [m]
    velocity: np.ndarray  # (N, 3) world [m/s]
    acceleration: np.ndarray  # (N, 3) world [m/s^2]
    rotation: np.ndarray  # (N, 3, 3) R_world_body
    omega_body: np.ndarray  # (N, 3) body [rad/s]


def _clean_centreline(xyz: np.ndarray) -> tuple[np.ndarray, bool]:
    """Validated (M, 3) points without repeated neighbours, and whether the loop is closed."""
    src = "centreline_xyz"
    pts = np.asarray(xyz, dtype=float)
    _require(pts.ndim == 2 and pts.shape[1] == 3, src, f"must be (M, 3), got {pts.shape}")
    _require(len(pts) >= 2, src, f"needs at least 2 points, got {len(pts)}")
    _require(bool(np.all(np.isfinite(pts))), src, "holds NaN or infinite coordinates")
    keep = np.r_[True, np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9]
    pts = pts[keep]
    _require(len(pts) >= 2, src, "all points coincide: the path has zero length")
    closed = len(pts) >= 4 and bool(np.linalg.norm(pts[0] - pts[-1]) < 1e-6)
    if closed:
        pts[-1] = pts[0]
    return pts, closed


def _resample(pts: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points spaced evenly along the polyline, and their chord-length parameter [m]."""
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
    u = np.linspace(0.0, chord[-1], max(int(np.ceil(chord[-1] / step)) + 1, 6))
    return np.column_stack([np.interp(u, chord, pts[:, i]) for i in range(3)]), u


def _smooth(pts: np.ndarray, sigma_samples: float, closed: bool) -> np.ndarray:
    """Gaussian-smooth evenly spaced points; straight ends and closed loops stay exact."""
    if sigma_samples <= 0:
        return pts
    if closed:
        out = gaussian_filter1d(pts[:-1], sigma_samples, axis=0, mode="wrap")
        return np.vstack([out, out[:1]])
    pad = int(4 * sigma_samples) + 1
    ext = np.pad(pts, ((pad, pad), (0, 0)), mode="reflect", reflect_type="odd")
    return gaussian_filter1d(ext, sigma_samples, axis=0, mode="nearest")[pad:-pad]


def _arc_length_spline(pts: np.ndarray, u: np.ndarray, closed: bool) -> tuple[BSpline, float]:
    """Quintic spline q(s) through the points, parametrised by arc length s [m], and its length."""
    bc = "periodic" if closed else None
    curve = make_interp_spline(u, pts, k=5, bc_type=bc)
    fine = np.linspace(u[0], u[-1], 4 * (len(u) - 1) + 1)
    s = cumulative_simpson(np.linalg.norm(curve(fine, 1), axis=1), x=fine, initial=0.0)
    xyz = curve(fine)
    if closed:
        xyz[-1] = xyz[0]
    return make_interp_spline(s, xyz, k=5, bc_type=bc), float(s[-1])


class RobotTrajectory:
    """Body poses ``T_world_body(t)`` along a centreline with analytic derivatives.

    ``t`` arguments are seconds in ``[0, duration_s]`` (scalar or array); every method returns
    arrays with a leading dimension ``N`` of samples.
    """

    def __init__(
        self,
        centreline_xyz: np.ndarray,
        duration_s: float | None = None,
        options: TrajectoryOptions = TrajectoryOptions(),
    ) -> None:
        options.check()
        self.options = options
        pts, self.closed = _clean_centreline(centreline_xyz)
        pts, u = _resample(pts, RESAMPLE_STEP_M)
        step = u[1] - u[0]
        pts = _smooth(pts, options.corner_smoothing_m / step, self.closed)
        self._q, self.length_m = _arc_length_spline(pts, u, self.closed)
        horiz = np.linalg.norm(self._q(np.linspace(0, self.length_m, 2001), 1)[:, :2], axis=1)
        _require(bool(horiz.min() > 0.1), "centreline_xyz", "is (nearly) vertical somewhere")
        self._duration = self._check_duration(duration_s)
        rng = np.random.default_rng(options.seed)
        k = 2.0 * np.pi * options.vibration_freq_hz / options.speed_mps
        rp = np.deg2rad(options.roll_pitch_amplitude_deg)
        self._z_vib = _Vibration(options.vibration_amplitude_m, k, rng)
        self._roll_vib = _Vibration(rp, k, rng)
        self._pitch_vib = _Vibration(rp, k, rng)

    def _check_duration(self, duration_s: float | None) -> float:
        o = self.options
        ramp_m = 0.5 * o.speed_mps * o.accel_time_s
        need = f"the {o.accel_time_s} s ramp to {o.speed_mps} m/s needs {ramp_m:.2f} m"
        _require(ramp_m <= self.length_m, "centreline_xyz", f"is {self.length_m:.2f} m; {need}")
        full = o.accel_time_s + (self.length_m - ramp_m) / o.speed_mps
        if o.spin_at_s is not None:
            # rest at s_stop, then the ramp back to speed must fit on the path
            s_stop = o.speed_mps * (o.spin_at_s - o.accel_time_s)
            _require(
                s_stop + ramp_m <= self.length_m,
                "spin_at_s",
                f"{o.spin_at_s} s stops the robot at {s_stop:.2f} m; with the {ramp_m:.2f} m "
                f"ramp back to speed it needs more than the {self.length_m:.2f} m path",
            )
            # the stop, the turn and the two half-speed ramps
            full += o.stop_duration_s + o.spin_duration_s + o.accel_time_s
        if duration_s is None:
            return full
        _require(bool(np.isfinite(duration_s) and duration_s > 0), "duration_s", "must be > 0")
        # a closed loop can be driven lap after lap: the periodic spline continues past its length
        _require(
            self.closed or duration_s <= full + 1e-9,
            "duration_s",
            f"{duration_s} s needs more than the {self.length_m:.2f} m path "
            f"(at most {full:.2f} s at {o.speed_mps} m/s)",
        )
        return float(duration_s)

    @property
    def duration_s(self) -> float:
        """Length of the trajectory in time [s]; valid times are ``[0, duration_s]``."""
        return self._duration

    def _profile(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arc length s [m], speed ds/dt [m/s] and d2s/dt2 [m/s^2] at times t [s]."""
        v, ta = self.options.speed_mps, self.options.accel_time_s
        if ta == 0:
            return v * t, np.full_like(t, v), np.zeros_like(t)
        x = np.clip(t / ta, 0.0, 1.0)
        ramp_s = v * ta * x**4 * (x * (x - 3.0) + 2.5)  # integral of the smoothstep
        s = np.where(t < ta, ramp_s, 0.5 * v * ta + v * (t - ta))
        sd = v * x**3 * (x * (6.0 * x - 15.0) + 10.0)
        sdd = (v / ta) * 30.0 * x**2 * (x - 1.0) ** 2
        o = self.options
        if o.spin_at_s is not None:
            # speed v * (ramp(t) - ramp(t - t_stop) + ramp(t - t_go)): each ramp is C2 and
            # constant outside its accel_time_s, so the sum is C2, and exactly 0 during the stop
            # and the spin
            t_stop = o.spin_at_s - ta
            t_go = o.spin_at_s + o.stop_duration_s + o.spin_duration_s
            for start, sign in ((t_stop, -v), (t_go, v)):
                g, gd, gdd = _unit_ramp(t - start, ta)
                s, sd, sdd = s + sign * g, sd + sign * gd, sdd + sign * gdd
        return s, sd, sdd

    def _spin_yaw(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Yaw offset psi [rad] of the turn on the spot, psi' [rad/s] and psi'' [rad/s^2]; the
        turn starts ``stop_duration_s`` after the robot comes to rest at ``spin_at_s``.

        The IMU sits at the body origin, so the gyro needs psi' only; psi'' (the angular
        acceleration, zero at both ends of the turn) is there for checks."""
        o = self.options
        x = np.clip((t - o.spin_at_s - o.stop_duration_s) / o.spin_duration_s, 0.0, 1.0)
        turn = np.deg2rad(o.spin_deg)
        psi = turn * x**3 * (x * (6.0 * x - 15.0) + 10.0)
        psi_d = (turn / o.spin_duration_s) * 30.0 * x**2 * (x - 1.0) ** 2
        psi_dd = (turn / o.spin_duration_s**2) * 60.0 * x * (x - 1.0) * (2.0 * x - 1.0)
        return psi, psi_d, psi_dd

    def _times(self, t: np.ndarray | float) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        _require(t.ndim == 1, "t", f"must be a scalar or 1-D array, got shape {t.shape}")
        ok = np.all(np.isfinite(t)) and t.min() >= -1e-9 and t.max() <= self._duration + 1e-9
        _require(bool(ok), "t", f"must lie in [0, {self._duration:.3f}] s")
        return np.clip(t, 0.0, self._duration)

    def _state(self, t: np.ndarray | float) -> _State:
        t = self._times(t)
        s, sd, sdd = self._profile(t)
        q0, q1, q2, q3 = (self._q(s, nu) for nu in range(4))
        cy, sy, yaw_s, yaw_ss = _yaw_terms(q1, q2, q3)
        # position = centreline + lateral offset along the horizontal left normal + height
        z, z_s, z_ss = self._z_vib(s)
        zero, off = np.zeros_like(s), self.options.lateral_offset_m
        n = np.column_stack([-sy, cy, zero])
        tang = np.column_stack([cy, sy, zero])
        up = np.array([0.0, 0.0, 1.0])
        p = q0 + off * n + np.outer(z + self.options.body_height_m, up)
        p_s = q1 - off * yaw_s[:, None] * tang + np.outer(z_s, up)
        p_ss = q2 - off * (yaw_ss[:, None] * tang + yaw_s[:, None] ** 2 * n) + np.outer(z_ss, up)
        vel = p_s * sd[:, None]
        acc = p_ss * (sd**2)[:, None] + p_s * sdd[:, None]
        # attitude: yaw from the tangent, pitch from the slope, plus roll/pitch vibration
        h = np.hypot(q1[:, 0], q1[:, 1])
        pitch_path = np.arctan2(-q1[:, 2], h)
        dh = (q1[:, 0] * q2[:, 0] + q1[:, 1] * q2[:, 1]) / h
        pitch_path_s = (q1[:, 2] * dh - h * q2[:, 2]) / (h**2 + q1[:, 2] ** 2)
        roll, roll_s, _ = self._roll_vib(s)
        dpitch, dpitch_s, _ = self._pitch_vib(s)
        pitch = pitch_path + dpitch
        R = _rotation_zyx(cy, sy, pitch, roll)
        omega = _omega_body_zyx(
            pitch, roll, yaw_s * sd, (pitch_path_s + dpitch_s) * sd, roll_s * sd
        )
        if self.options.spin_at_s is not None:
            psi, psi_d, _ = self._spin_yaw(t)
            R, omega = _turn_about_body_z(R, omega, psi, psi_d)
        return _State(p, vel, acc, R, omega)

    def position(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 3) body origin in the world frame [m]."""
        return self._state(t).position

    def velocity(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 3) body velocity in the world frame [m/s]."""
        return self._state(t).velocity

    def acceleration(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 3) body acceleration in the world frame [m/s^2] (gravity not included)."""
        return self._state(t).acceleration

    def rotation(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 3, 3) rotation ``R_world_body``."""
        return self._state(t).rotation

    def angular_velocity_body(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 3) angular velocity of the body, expressed in the body frame [rad/s]."""
        return self._state(t).omega_body

    def pose(self, t: np.ndarray | float) -> np.ndarray:
        """(N, 4, 4) ``T_world_body``."""
        st = self._state(t)
        T = np.tile(np.eye(4), (len(st.position), 1, 1))
        T[:, :3, :3], T[:, :3, 3] = st.rotation, st.position
        return T

    def imu(
        self, rate_hz: float = 200.0, noise: ImuNoise | None = None, seed: int = 0
    ) -> dict[str, np.ndarray]:
        """IMU samples at ``rate_hz`` over ``[0, duration_s]``.

        Returns ``t_ns`` (N,) int64, ``gyro`` (N, 3) [rad/s], ``acc`` (N, 3) specific force
        ``R^T (a_world - g_world)`` [m/s^2], both in the body frame, and the biases added to them,
        ``gyro_bias`` and ``acc_bias`` (zero without noise). With ``noise``, white noise of
        standard deviation ``density * sqrt(rate_hz)`` and random-walk biases starting at zero
        with steps of ``random_walk / sqrt(rate_hz)`` are added, drawn from ``seed``.
        """
        _require(bool(np.isfinite(rate_hz) and rate_hz > 0), "rate_hz", "must be > 0")
        n = int(np.floor(self._duration * rate_hz + 1e-9)) + 1
        t_ns = np.round(np.arange(n) * (1e9 / rate_hz)).astype(np.int64)
        st = self._state(np.minimum(t_ns * 1e-9, self._duration))
        gyro = st.omega_body
        acc = np.einsum("nji,nj->ni", st.rotation, st.acceleration - GRAVITY_WORLD)
        out = {"t_ns": t_ns, "gyro": gyro, "acc": acc}
        out["gyro_bias"], out["acc_bias"] = np.zeros_like(gyro), np.zeros_like(acc)
        if noise is not None:
            rng = np.random.default_rng(seed)
            for key, density, walk in (
                ("gyro", noise.gyroscope_noise_density, noise.gyroscope_random_walk),
                ("acc", noise.accelerometer_noise_density, noise.accelerometer_random_walk),
            ):
                bias = np.cumsum(rng.standard_normal((n, 3)) * (walk / np.sqrt(rate_hz)), axis=0)
                bias -= bias[0]
                white = rng.standard_normal((n, 3)) * (density * np.sqrt(rate_hz))
                out[key + "_bias"] = bias
                out[key] = out[key] + bias + white
        return out


def _unit_ramp(tau: np.ndarray, ta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance [s], speed [-] and acceleration [1/s] of a unit-speed smoothstep ramp from rest
    that starts at ``tau = 0`` and lasts ``ta`` seconds (``tau`` [s])."""
    x = np.clip(tau / ta, 0.0, 1.0)
    g = np.where(tau < ta, ta * x**4 * (x * (x - 3.0) + 2.5), tau - 0.5 * ta)
    return g, x**3 * (x * (6.0 * x - 15.0) + 10.0), (30.0 / ta) * x**2 * (x - 1.0) ** 2


def _turn_about_body_z(
    R: np.ndarray, omega: np.ndarray, psi: np.ndarray, psi_d: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``R @ Rz(psi)`` and its body angular velocity ``Rz(psi)^T omega + psi_d e_z`` [rad/s].

    The turn is about the body's own up axis, so on a slope the robot stays on the floor plane;
    at rest (omega = 0) the gyro reads ``(0, 0, psi_d)`` exactly.
    """
    c, s = np.cos(psi), np.sin(psi)
    Rz = np.zeros((len(psi), 3, 3))
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
    w = np.column_stack(
        [c * omega[:, 0] + s * omega[:, 1], c * omega[:, 1] - s * omega[:, 0], omega[:, 2] + psi_d]
    )
    return R @ Rz, w


def _yaw_terms(
    q1: np.ndarray, q2: np.ndarray, q3: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """cos and sin of the yaw of the tangent q1 = dq/ds, and d(yaw)/ds [rad/m], d2(yaw)/ds2."""
    h2 = q1[:, 0] ** 2 + q1[:, 1] ** 2
    h = np.sqrt(h2)
    c = q1[:, 0] * q2[:, 1] - q1[:, 1] * q2[:, 0]
    dc = q1[:, 0] * q3[:, 1] - q1[:, 1] * q3[:, 0]
    dh2 = 2.0 * (q1[:, 0] * q2[:, 0] + q1[:, 1] * q2[:, 1])
    return q1[:, 0] / h, q1[:, 1] / h, c / h2, (dc * h2 - c * dh2) / h2**2


def _rotation_zyx(
    cy: np.ndarray, sy: np.ndarray, pitch: np.ndarray, roll: np.ndarray
) -> np.ndarray:
    """(N, 3, 3) ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` from cos/sin of yaw and the angles [rad]."""
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    rows = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _omega_body_zyx(
    pitch: np.ndarray, roll: np.ndarray, yaw_d: np.ndarray, pitch_d: np.ndarray, roll_d: np.ndarray
) -> np.ndarray:
    """(N, 3) body angular velocity [rad/s] from ZYX Euler angles and their rates [rad/s]."""
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    return np.column_stack(
        [
            roll_d - yaw_d * sp,
            pitch_d * cr + yaw_d * sr * cp,
            -pitch_d * sr + yaw_d * cr * cp,
        ]
    )
