"""Moving objects that cross the view (a walking worker, a mine cart): the dynamic content the
dynamic-cell filter must reject. Meshes are rebuilt per frame from their pose at time t."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slslam.sim.roadway import Material, Mesh, Stations


def box(centre: np.ndarray, size: np.ndarray, yaw: float, material: int) -> Mesh:
    """An axis-aligned box (size = x, y, z extents [m]) rotated by yaw about z."""
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    verts = (corners * size) @ R.T + centre
    faces = np.array(
        [
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ]
    )
    return Mesh(verts, faces.astype(np.int32), np.full(12, material, np.uint8))


@dataclass(frozen=True)
class Mover:
    """An object moving at constant speed between two world points during [t0, t1] seconds."""

    kind: str  # "worker" or "cart"
    start: np.ndarray
    end: np.ndarray
    t0: float
    t1: float

    def mesh(self, t: float) -> Mesh | None:
        if not self.t0 <= t <= self.t1:
            return None
        u = (t - self.t0) / (self.t1 - self.t0)
        p = self.start + u * (self.end - self.start)
        d = self.end - self.start
        yaw = float(np.arctan2(d[1], d[0]))
        if self.kind == "worker":
            legs = box(p + [0, 0, 0.42], np.array([0.25, 0.35, 0.84]), yaw, Material.WORKER)
            torso = box(p + [0, 0, 1.2], np.array([0.3, 0.5, 0.72]), yaw, Material.WORKER)
            head = box(p + [0, 0, 1.66], np.array([0.22, 0.2, 0.22]), yaw, Material.WORKER)
            return Mesh.concat([legs, torso, head])
        return box(p + [0, 0, 0.65], np.array([1.6, 1.0, 1.1]), yaw, Material.CART)


def default_movers(
    path: np.ndarray, robot_s: np.ndarray, robot_t: np.ndarray, width_m: float
) -> list[Mover]:
    """A worker crossing 7 m ahead of the robot at 30 % of the path and a cart coming towards
    it at 60 %. ``robot_s``/``robot_t``: the robot's arc length over time."""
    st = Stations.from_centreline(path)
    movers = []
    for fraction, kind in ((0.3, "worker"), (0.6, "cart")):
        s_event = fraction * robot_s[-1]
        t_event = float(np.interp(s_event, robot_s, robot_t))
        if kind == "worker":
            s_at = s_event + 7.0
            i = int(np.clip(np.searchsorted(st.s, s_at), 0, len(st.s) - 1))
            half = width_m / 2 - 0.4
            start = st.position[i] - half * st.left[i]
            end = st.position[i] + half * st.left[i]
            movers.append(Mover(kind, start, end, t_event, t_event + 2 * half / 1.2))
        else:
            i0 = int(np.clip(np.searchsorted(st.s, s_event + 14.0), 0, len(st.s) - 1))
            i1 = int(np.clip(np.searchsorted(st.s, s_event + 4.0), 0, len(st.s) - 1))
            off = -(width_m / 2 - 0.8)
            start = st.position[i0] + off * st.left[i0]
            end = st.position[i1] + off * st.left[i1]
            movers.append(Mover(kind, start, end, t_event, t_event + 10.0 / 1.0))
    return movers
