"""Triangle meshes of mine roadways: an arched or trapezoidal cross-section swept along a
centreline, with steel arches, a pipe and cables along the walls, and per-triangle materials.

Frames: world z up, floor at z = 0 under the centreline. Material ids match the C++ shading
kernel (``slslam._core`` ``Material``): see :class:`Material`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import Literal

import numpy as np
from scipy.spatial import cKDTree


class Material(IntEnum):
    """Surface kinds; the values are the ids the shading kernel knows."""

    ROCK = 0
    COAL = 1
    SHOTCRETE = 2
    STEEL = 3
    ROOF_MESH = 4
    FLOOR = 5
    PIPE = 6
    CABLE = 7
    WORKER = 8
    CART = 9
    #: Smooth shotcrete lining (no bolt plates, services or arches): an id of the Python side
    #: only; the simulator shades it as SHOTCRETE with that texture cancelled and a faint
    #: sub-centimetre grain instead (``sequence.smooth_shotcrete_shading``).
    SMOOTH_SHOTCRETE = 10
    NONE = 255


@dataclass(frozen=True)
class CrossSection:
    """Roadway cross-section [m]. ``arched``: vertical walls and a segmental arch roof;
    ``trapezoidal``: walls leaning in by ``wall_lean_m`` and a flat roof."""

    shape: Literal["arched", "trapezoidal"] = "arched"
    width_m: float = 4.4
    wall_height_m: float = 2.1
    arch_rise_m: float = 1.2  # arched: roof crown above the wall top
    wall_lean_m: float = 0.4  # trapezoidal: each wall's top is this much closer to the centre
    segments: int = 24  # profile vertices on the arch

    @property
    def height_m(self) -> float:
        return self.wall_height_m + (self.arch_rise_m if self.shape == "arched" else 0.0)

    def check(self) -> None:
        if not (3.0 <= self.width_m <= 8.0 and 1.5 <= self.height_m <= 6.0):
            raise ValueError(f"cross-section {self.width_m} m x {self.height_m} m is not a roadway")

    def profile(self) -> tuple[np.ndarray, np.ndarray]:
        """Profile points (lateral y to the left, height z), right floor corner -> left floor
        corner over the roof, and the surface kind of each segment (0 floor, 1 wall, 2 roof)."""
        a = self.width_m / 2
        if self.shape == "arched":
            rise = self.arch_rise_m
            radius = (a * a + rise * rise) / (2 * rise)
            zc = self.wall_height_m + rise - radius
            half = np.arcsin(a / radius)
            angles = np.linspace(-half, half, self.segments)
            roof = np.column_stack([radius * np.sin(angles), zc + radius * np.cos(angles)])
            top_r, top_l = roof[0], roof[-1]
        else:
            top = a - self.wall_lean_m
            roof = np.array([[-top, self.wall_height_m], [top, self.wall_height_m]])
            top_r, top_l = roof[0], roof[-1]
        walls_r = np.linspace([-a, 0.0], top_r, 6)
        walls_l = np.linspace(top_l, [a, 0.0], 6)
        floor = np.linspace([a, 0.0], [-a, 0.0], 9)
        points = np.concatenate([walls_r, roof[1:], walls_l[1:], floor[1:]])
        kinds = np.concatenate([np.ones(5), np.full(len(roof) - 1, 2), np.ones(5), np.zeros(8)])
        return points, kinds.astype(np.int32)

    def roof_height(self, lateral: np.ndarray) -> np.ndarray:
        """Height of the roof (or wall) above the floor at a lateral offset [m]."""
        a = self.width_m / 2
        y = np.abs(lateral)
        if self.shape == "arched":
            rise = self.arch_rise_m
            radius = (a * a + rise * rise) / (2 * rise)
            zc = self.wall_height_m + rise - radius
            return zc + np.sqrt(np.maximum(radius * radius - y * y, 0.0))
        top = a - self.wall_lean_m
        wall = self.wall_height_m * np.clip((a - y) / max(a - top, 1e-9), 0.0, None)
        return np.where(y <= top, self.wall_height_m, np.minimum(wall, self.wall_height_m))


@dataclass(frozen=True)
class RoadwayStyle:
    """What lines the roadway: wall sections, arches, services."""

    section_pattern: tuple[tuple[int, float], ...] = (
        (Material.ROCK, 18.0),
        (Material.SHOTCRETE, 10.0),
        (Material.COAL, 12.0),
    )
    arch_spacing_m: float = 1.0  # steel arches in rock and coal sections [m]
    arch_width_m: float = 0.14  # along the roadway [m]
    arch_depth_m: float = 0.12  # how far the arch stands off the rock [m]
    pipe_radius_m: float = 0.1
    pipe_height_m: float = 1.6
    cable_radius_m: float = 0.025
    cable_heights_m: tuple[float, ...] = (1.85, 1.95)


@dataclass
class Mesh:
    """Triangles with one material per triangle."""

    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int32))
    material: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.uint8))

    @staticmethod
    def concat(meshes: list[Mesh]) -> Mesh:
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return Mesh(
            np.concatenate([m.vertices for m in meshes]),
            np.concatenate([m.triangles + o for m, o in zip(meshes, offsets, strict=True)]).astype(
                np.int32
            ),
            np.concatenate([m.material for m in meshes]).astype(np.uint8),
        )

    def select(self, keep: np.ndarray) -> Mesh:
        return Mesh(self.vertices, self.triangles[keep], self.material[keep])


@dataclass(frozen=True)
class Stations:
    """Points along a centreline with their unit tangent and horizontal left vector."""

    position: np.ndarray
    tangent: np.ndarray
    left: np.ndarray
    s: np.ndarray  # arc length [m]

    @classmethod
    def from_centreline(cls, centreline: np.ndarray) -> Stations:
        p = np.asarray(centreline, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2 or not np.all(np.isfinite(p)):
            raise ValueError("a centreline must be a finite (M >= 2, 3) array")
        tangent = np.gradient(p, axis=0)
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        left = np.cross([0.0, 0.0, 1.0], tangent)
        left /= np.linalg.norm(left, axis=1, keepdims=True)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        return cls(p, tangent, left, s)


def sweep(
    stations: Stations, profile: np.ndarray, closed: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (M*K, 3) and triangles of a profile (K, 2: lateral, height) swept along stations.

    Triangle ``2*(m*(K-1)+k) + {0,1}`` joins profile segment k between stations m and m+1.
    ``closed`` joins the last profile point back to the first (tubes such as pipes).
    """
    M, K = len(stations.position), len(profile)
    up = np.array([0.0, 0.0, 1.0])
    verts = (
        stations.position[:, None, :]
        + profile[None, :, 0, None] * stations.left[:, None, :]
        + profile[None, :, 1, None] * up
    )
    idx = np.arange(M * K).reshape(M, K)
    if closed:
        idx = np.concatenate([idx, idx[:, :1]], axis=1)
    a, b = idx[:-1, :-1], idx[:-1, 1:]
    c, d = idx[1:, :-1], idx[1:, 1:]
    tris = np.stack([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], axis=2)
    return verts.reshape(-1, 3), tris.reshape(-1, 3).astype(np.int32)


def _section_material(s: np.ndarray, style: RoadwayStyle) -> np.ndarray:
    kinds = np.array([m for m, _ in style.section_pattern], dtype=np.uint8)
    lengths = np.array([length for _, length in style.section_pattern])
    edges = np.concatenate([[0.0], np.cumsum(lengths)])
    return kinds[np.searchsorted(edges, np.mod(s, edges[-1]), side="right") - 1]


def _shell(stations: Stations, section: CrossSection, style: RoadwayStyle) -> Mesh:
    profile, kinds = section.profile()
    verts, tris = sweep(stations, profile)
    K = len(profile) - 1
    s_mid = 0.5 * (stations.s[:-1] + stations.s[1:])
    wall = np.repeat(_section_material(s_mid, style), K * 2)
    kind = np.tile(np.repeat(kinds, 2), len(s_mid))
    material = np.where(kind == 0, Material.FLOOR, wall)
    # Rock roofs carry a wire mesh; shotcrete and coal sections do not.
    material = np.where((kind == 2) & (wall == Material.ROCK), Material.ROOF_MESH, material)
    return Mesh(verts, tris, material.astype(np.uint8))


def _arches(stations: Stations, section: CrossSection, style: RoadwayStyle) -> list[Mesh]:
    profile, kinds = section.profile()
    wall_roof = profile[: int(np.flatnonzero(kinds == 0)[0]) + 1]  # right floor .. left floor
    centre = np.array([0.0, section.height_m / 2])
    inward = centre - wall_roof
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    inner = wall_roof + style.arch_depth_m * inward
    meshes = []
    targets = np.arange(style.arch_spacing_m / 2, stations.s[-1], style.arch_spacing_m)
    sections = _section_material(targets, style)
    for s_k in targets[sections != Material.SHOTCRETE]:
        i = int(np.clip(np.searchsorted(stations.s, s_k), 1, len(stations.s) - 1))
        p, t, left = stations.position[i], stations.tangent[i], stations.left[i]
        half = style.arch_width_m / 2
        local = Stations(
            np.stack([p - half * t, p + half * t]),
            np.stack([t, t]),
            np.stack([left, left]),
            np.array([s_k - half, s_k + half]),
        )
        for prof in (inner, np.concatenate([wall_roof[:1], inner[:1]])):  # face, foot
            v, f = sweep(local, prof)
            meshes.append(Mesh(v, f, np.full(len(f), Material.STEEL, np.uint8)))
        for offset in (-half, half):  # the two sides facing along the roadway
            ring = np.concatenate([wall_roof, inner[::-1]])
            v = p + offset * t + ring[:, :1] * left + ring[:, 1:] * np.array([0.0, 0.0, 1.0])
            n = len(wall_roof)
            a, b = np.arange(n - 1), np.arange(1, n)
            c, d = 2 * n - 1 - a, 2 * n - 1 - b
            f = np.concatenate([np.stack([a, b, c], 1), np.stack([b, d, c], 1)])
            meshes.append(Mesh(v, f.astype(np.int32), np.full(len(f), Material.STEEL, np.uint8)))
    return meshes


def _tube(
    stations: Stations,
    lateral: float,
    height: float,
    radius: float,
    material: int,
    segments: int = 10,
) -> Mesh:
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    profile = np.column_stack([lateral + radius * np.cos(a), height + radius * np.sin(a)])
    v, f = sweep(stations, profile, closed=True)
    return Mesh(v, f, np.full(len(f), material, np.uint8))


def roadway_mesh(
    centreline: np.ndarray,
    section: CrossSection = CrossSection(),
    style: RoadwayStyle = RoadwayStyle(),
) -> Mesh:
    """Shell, steel arches, a pipe on the left wall and cables on the right wall."""
    section.check()
    stations = Stations.from_centreline(centreline)
    a = section.width_m / 2
    wall_inset = (
        section.wall_lean_m * style.pipe_height_m / section.wall_height_m
        if section.shape == "trapezoidal"
        else 0.0
    )
    parts = [
        _shell(stations, section, style),
        *_arches(stations, section, style),
        _tube(
            stations, a - wall_inset - 0.3, style.pipe_height_m, style.pipe_radius_m, Material.PIPE
        ),
    ]
    for h in style.cable_heights_m:
        parts.append(
            _tube(
                stations,
                -(a - wall_inset - 0.2),
                h,
                style.cable_radius_m,
                Material.CABLE,
                segments=6,
            )
        )
    return Mesh.concat(parts)


def end_cap(
    centreline: np.ndarray, section: CrossSection = CrossSection(), material: int = Material.ROCK
) -> Mesh:
    """A flat face closing a roadway at its last centreline point (a dead end): the
    cross-section polygon, perpendicular to the last tangent, as a fan of triangles."""
    section.check()
    st = Stations.from_centreline(centreline)
    profile, _ = section.profile()  # closed: the last floor point is the first wall point
    centre = np.array([0.0, section.height_m / 2])
    ring = np.concatenate([centre[None], profile[:-1]])
    left, end = st.left[-1], st.position[-1]
    verts = end + ring[:, :1] * left + ring[:, 1:] * np.array([0.0, 0.0, 1.0])
    k = np.arange(1, len(ring))
    tris = np.column_stack([np.zeros_like(k), k, np.where(k + 1 < len(ring), k + 1, 1)])
    return Mesh(verts, tris.astype(np.int32), np.full(len(tris), material, np.uint8))


#: Materials of the roadway shell (walls, roof, floor, faces) that a shotcrete lining covers;
#: arches, pipes and cables (STEEL, PIPE, CABLE) inside the lined stretch are removed.
_SHELL = (Material.ROCK, Material.COAL, Material.SHOTCRETE, Material.ROOF_MESH, Material.FLOOR)


def line_with_shotcrete(
    mesh: Mesh, path: np.ndarray, start_m: float, length_m: float, section: CrossSection
) -> tuple[Mesh, np.ndarray]:
    """Line the stretch ``[start_m, start_m + length_m]`` of a roadway with smooth shotcrete.

    The stretch is measured along ``path`` (the robot's path, (M, 3) [m], from its start). A
    triangle belongs to it when the path point nearest to its centroid (horizontally, within
    the roadway's width) lies in the stretch. Its shell triangles become
    ``Material.SMOOTH_SHOTCRETE`` and its arches, pipe and cables go, so that walls, roof and
    floor carry no corner at all. Returns the new mesh and the mask of lined triangles in it.
    """
    st = Stations.from_centreline(path)
    centroids = mesh.vertices[mesh.triangles].mean(axis=1)
    dist, idx = cKDTree(st.position[:, :2]).query(centroids[:, :2])
    s = st.s[idx]
    inside = (s >= start_m) & (s <= start_m + length_m) & (dist <= section.width_m)
    shell = np.isin(mesh.material, np.array(_SHELL, dtype=np.uint8))
    keep = ~inside | shell
    material = np.where(inside & shell, Material.SMOOTH_SHOTCRETE, mesh.material)
    lined = Mesh(mesh.vertices, mesh.triangles[keep], material[keep].astype(np.uint8))
    return lined, (inside & shell)[keep]


def inside_roadway(
    points: np.ndarray, centreline: np.ndarray, section: CrossSection, margin_m: float = 0.03
) -> np.ndarray:
    """True for points strictly inside the open space of a roadway (used to cut junctions)."""
    st = Stations.from_centreline(centreline)
    _, i = cKDTree(st.position[:, :2]).query(points[:, :2])
    d = points - st.position[i]
    along = np.einsum("ij,ij->i", d, st.tangent[i])
    lateral = np.einsum("ij,ij->i", d, st.left[i])
    step = np.max(np.linalg.norm(np.diff(st.position, axis=0), axis=1))
    within_ends = np.abs(along) <= step
    return (
        within_ends
        & (np.abs(lateral) < section.width_m / 2 - margin_m)
        & (points[:, 2] > margin_m)
        & (points[:, 2] < section.roof_height(lateral) - margin_m)
    )


def network_mesh(
    centrelines: list[np.ndarray],
    section: CrossSection = CrossSection(),
    style: RoadwayStyle = RoadwayStyle(),
) -> Mesh:
    """Several roadways; where one opens into another, the surfaces inside the other are cut."""
    meshes = []
    for i, line in enumerate(centrelines):
        mesh = roadway_mesh(line, section, style)
        centroids = mesh.vertices[mesh.triangles].mean(axis=1)
        keep = np.ones(len(mesh.triangles), dtype=bool)
        for j, other in enumerate(centrelines):
            if j != i:
                keep &= ~inside_roadway(centroids, other, section)
        meshes.append(mesh.select(keep))
    return Mesh.concat(meshes)
