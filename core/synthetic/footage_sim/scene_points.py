"""Static scene points for the generator: floor marks around the person and features on a wall beyond.

An animator who films a moving shot tracks a few such features (Blender's Movie Clip
Editor); they are what pins the camera down (:mod:`core.scene_camera`).  Half the points
lie on the floor within :data:`FLOOR_RADIUS_M` of places the person passes, half on a
wall behind the person, facing the camera, :data:`WALL_BEYOND_M` further than the
person's farthest point, at heights up to :data:`WALL_HEIGHT_M`.  Each point is seen only
in the frames where it lies inside the picture, with the joints' noise.
"""

from __future__ import annotations

import math

import numpy as np

from ...skeleton import JOINT_INDEX

FLOOR_RADIUS_M = (0.5, 4.0)
WALL_BEYOND_M = (2.0, 6.0)
WALL_HEIGHT_M = (0.1, 3.0)
#: Bearing spread (degrees) of wall points about the bearing of a frame's pelvis.
WALL_SPREAD_DEG = 15.0


def scene_points_world(joints_world: np.ndarray, camera_position: np.ndarray, n_points: int, seed: int) -> np.ndarray:
    """(n_points, 3) static points in the motion's world (Y up), drawn as the module docstring says."""
    rng = np.random.default_rng([int(seed), 5])
    joints_world = np.asarray(joints_world, dtype=float)
    pelvis = joints_world[:, JOINT_INDEX["pelvis"]]
    ankles = joints_world[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].min(axis=1)
    floor_y = float(np.percentile(ankles, 5)) - 0.07
    n_floor = (n_points + 1) // 2
    pts = []
    for _ in range(n_floor):
        p = pelvis[int(rng.integers(len(pelvis)))]
        r = math.sqrt(rng.uniform(FLOOR_RADIUS_M[0] ** 2, FLOOR_RADIUS_M[1] ** 2))
        a = rng.uniform(0.0, 2.0 * math.pi)
        pts.append([p[0] + r * math.cos(a), floor_y, p[2] + r * math.sin(a)])
    cam = np.asarray(camera_position, dtype=float)
    rel = pelvis[:, [0, 2]] - cam[[0, 2]]
    view = rel.mean(axis=0)
    view /= max(float(np.linalg.norm(view)), 1e-9)
    far = float((rel @ view).max()) + rng.uniform(*WALL_BEYOND_M)
    for _ in range(n_points - n_floor):
        d = rel[int(rng.integers(len(rel)))]
        bearing = math.atan2(d[1], d[0]) + math.radians(rng.uniform(-WALL_SPREAD_DEG, WALL_SPREAD_DEG))
        ray = np.array([math.cos(bearing), math.sin(bearing)])
        t = far / max(float(ray @ view), 0.2)
        x, z = cam[[0, 2]] + t * ray
        pts.append([x, floor_y + rng.uniform(*WALL_HEIGHT_M), z])
    return np.array(pts, dtype=float).reshape(-1, 3)
