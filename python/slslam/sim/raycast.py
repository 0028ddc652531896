"""Ray casting against the roadway with Open3D's RaycastingScene (Embree).

The static roadway is put into one scene once; moving objects go into a small second scene per
frame, and the nearer hit wins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from slslam.sim.roadway import Material, Mesh


@dataclass
class Hits:
    """Per ray: distance ``t`` along the unit direction [m] (inf: no hit), unit ``normal``
    (world), ``material`` id (255: no hit) and hit ``point`` (world)."""

    t: np.ndarray
    normal: np.ndarray
    material: np.ndarray
    point: np.ndarray


def _scene(mesh: Mesh) -> o3d.t.geometry.RaycastingScene:
    scene = o3d.t.geometry.RaycastingScene()
    if len(mesh.triangles):
        scene.add_triangles(
            o3d.core.Tensor(mesh.vertices.astype(np.float32)),
            o3d.core.Tensor(mesh.triangles.astype(np.uint32)),
        )
    return scene


class RaycastScene:
    """A static mesh prepared for repeated ray casting."""

    def __init__(self, mesh: Mesh):
        if len(mesh.triangles) == 0:
            raise ValueError("the scene mesh has no triangles")
        self.mesh = mesh
        self._scene = _scene(mesh)
        self._lookup = np.append(mesh.material, Material.NONE).astype(np.uint8)

    @staticmethod
    def _cast(scene, material_lookup: np.ndarray, rays: o3d.core.Tensor):
        result = scene.cast_rays(rays)
        t = result["t_hit"].numpy()
        # Misses carry an invalid primitive id; the lookup table's last entry (NONE) catches them.
        ids = np.minimum(result["primitive_ids"].numpy(), len(material_lookup) - 1)
        return t, result["primitive_normals"].numpy(), material_lookup[ids]

    def cast_rays(self, rays: np.ndarray, movers: Mesh | None = None) -> Hits:
        """Cast rays given as an (N, 6) float32 array of origin and unit direction (world)."""
        rays = np.ascontiguousarray(rays, dtype=np.float32)
        tensor = o3d.core.Tensor.from_numpy(rays)
        t, normal, mat = self._cast(self._scene, self._lookup, tensor)
        if movers is not None and len(movers.triangles):
            t2, n2, m2 = self._cast(
                _scene(movers), np.append(movers.material, Material.NONE).astype(np.uint8), tensor
            )
            nearer = t2 < t
            t, mat = np.where(nearer, t2, t), np.where(nearer, m2, mat)
            normal = np.where(nearer[:, None], n2, normal)
        point = np.multiply(rays[:, 3:], np.nan_to_num(t, posinf=0.0)[:, None])
        point += rays[:, :3]
        return Hits(t=t, normal=normal, material=mat, point=point)

    def cast(self, origins: np.ndarray, directions: np.ndarray, movers: Mesh | None = None) -> Hits:
        """Cast rays from origins (N x 3 or one 3-vector) along unit directions (N x 3)."""
        rays = np.empty((len(directions), 6), dtype=np.float32)
        rays[:, :3] = origins
        rays[:, 3:] = directions
        return self.cast_rays(rays, movers)
