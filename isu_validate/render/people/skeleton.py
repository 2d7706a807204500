"""One anny body evaluated in a pose: vertices, bone heads and each bone's world rotation delta.

anny's "local-ref" pose parameters (anny.utils.kinematics): the root's 4x4 is its world pose; every other bone's
delta D is a rotation in the world-aligned axes of the reference (rest) pose, applied after its
parent's, so a bone's world rotation delta is G = G_parent @ D. Posing by "rotate this bone by Q in the
world, on top of what its parent does" is then D = G_parent^T Q G_parent (``delta_for``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .phenotype import Phenotype


@dataclass
class Posed:
    vertices: np.ndarray      # (V, 3) float32, world (cabin) frame
    heads: np.ndarray         # (B, 3) bone heads
    G: np.ndarray             # (B, 3, 3) world rotation deltas from the reference orientations
    labels: list

    def head(self, bone: str) -> np.ndarray:
        return self.heads[self.labels.index(bone)]

    def rot(self, bone: str) -> np.ndarray:
        return self.G[self.labels.index(bone)]


class Body:
    """A phenotype (and facial expression) of the anny model, posed on demand."""

    def __init__(self, model, phenotype: Phenotype, facial_actions: dict | None = None):
        self.model, self.phenotype, self.facial = model, phenotype, dict(facial_actions or {})
        self.labels = list(model.bone_labels)
        self.parent = {b: (self.labels[p] if p >= 0 else None) for b, p in zip(self.labels, model.bone_parents)}
        self.U = model.reference_bone_orientations.detach().cpu().numpy().astype(np.float64)

    def evaluate(self, deltas: dict[str, np.ndarray]) -> Posed:
        import torch
        pose = {b: torch.as_tensor(np.asarray(m, np.float32)[None]) for b, m in deltas.items()}
        with torch.no_grad():
            out = self.model(pose_parameters=pose or None, phenotype_kwargs=self.phenotype.kwargs(),
                             facial_actions=self.facial or None)
        W = out["bone_poses"][0].double().numpy()
        G = W[:, :3, :3] @ self.U.transpose(0, 2, 1)
        return Posed(out["vertices"][0].numpy().astype(np.float32), W[:, :3, 3].copy(), G, self.labels)


def rotation(axis, angle_rad: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation
    axis = np.asarray(axis, float)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle_rad).as_matrix()


def rot_x(deg: float) -> np.ndarray:
    return rotation((1, 0, 0), np.radians(deg))


def rot_z(deg: float) -> np.ndarray:
    return rotation((0, 0, 1), np.radians(deg))


def align(a_from, b_from, a_to, b_to) -> np.ndarray:
    """The rotation taking direction a_from to a_to exactly and b_from as close as possible to b_to."""
    from scipy.spatial.transform import Rotation
    a_from, a_to = _unit(a_from), _unit(a_to)
    b_from = _unit(b_from - a_from * (b_from @ a_from))
    b_to = _unit(b_to - a_to * (b_to @ a_to))
    rot, _ = Rotation.align_vectors([a_to, b_to], [a_from, b_from], weights=[np.inf, 1.0])
    return rot.as_matrix()


def swing_to(v_from, v_to) -> np.ndarray:
    """The smallest rotation taking direction v_from to v_to."""
    from scipy.spatial.transform import Rotation
    rot, _ = Rotation.align_vectors([_unit(v_to)], [_unit(v_from)])
    return rot.as_matrix()


def delta_for(G_parent: np.ndarray, Q_world: np.ndarray) -> np.ndarray:
    """The 4x4 pose delta that rotates a bone by Q_world (in the world) on top of its parent."""
    D = np.eye(4)
    D[:3, :3] = G_parent.T @ Q_world @ G_parent
    return D


def rigid(R: np.ndarray, t=(0.0, 0.0, 0.0)) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, t
    return M


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)
