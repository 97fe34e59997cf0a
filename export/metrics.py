"""Pose metrics as pure numpy functions: joints, vertices and orientations in, errors out.

    e = mpjpe(pred_joints_m, true_joints_m)            # (N,) metres, pelvis-aligned
    p = pa_mpjpe(pred_joints_m, true_joints_m)         # (N,) metres after Procrustes
    h = heading_error_rad(pred_pose_aa[:, :3], true_pose_aa[:, :3])   # (N,) signed, radians

Everything is in metres and radians (SI); callers convert to cm or degrees when they print.
Frames: the carpet frame is z up; the SMPL canonical body is Y up and ``pose_aa[0:3]`` rotates
it into the carpet frame, so an upright person has a global orientation of +90° about x
(see /work/shared/design.md). Joint 0 is the pelvis.

- ``mpjpe``: mean over joints of the joint error after moving both pelvises to the origin.
- ``pa_mpjpe``: the same after the best similarity transform (scale, rotation, translation;
  Umeyama/Procrustes) of the prediction onto the truth, per frame.
- ``local_mpjpe``: the local pose alone: the prediction's joints re-posed with the TRUE global
  orientation, then pelvis-aligned; a heading or tilt error does not count here.
- ``heading_error_rad``: the rotation about the vertical (carpet z) between the predicted and
  the true global orientation: the twist about z of R_pred · R_trueᵀ (swing–twist
  decomposition), in (-π, π]. Defined for every pose, lying ones included; a tilt error alone
  gives 0.
- ``heading_rad``: one body's heading, the same twist against the upright orientation.
- ``pve``: mean over vertices of the pelvis-aligned vertex error.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

UP = np.array([0.0, 0.0, 1.0])  # carpet z
UPRIGHT_AA = np.array([np.pi / 2, 0.0, 0.0])  # the canonical Y-up body standing on the carpet


def joint_errors(pred: np.ndarray, true: np.ndarray, root: int | None = 0) -> np.ndarray:
    """(…,J,3), (…,J,3) → (…,J) metres; ``root`` is the joint both are moved onto (None: no alignment)."""
    pred, true = np.asarray(pred, np.float64), np.asarray(true, np.float64)
    if pred.shape != true.shape or pred.shape[-1] != 3:
        raise ValueError(f"joint arrays must have the same (…,J,3) shape; got {pred.shape} and {true.shape}")
    if root is not None:
        pred = pred - pred[..., root:root + 1, :]
        true = true - true[..., root:root + 1, :]
    return np.linalg.norm(pred - true, axis=-1)


def mpjpe(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(…,J,3), (…,J,3) → (…) metres: mean pelvis-aligned joint error per frame."""
    return joint_errors(pred, true).mean(-1)


def procrustes_align(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(…,J,3), (…,J,3) → (…,J,3): ``pred`` moved by the similarity transform (s, R, t) that
    minimises Σ‖s·R·pred_j + t − true_j‖² (Umeyama 1991; det R = +1)."""
    pred, true = np.asarray(pred, np.float64), np.asarray(true, np.float64)
    mp, mt = pred.mean(-2, keepdims=True), true.mean(-2, keepdims=True)
    p0, t0 = pred - mp, true - mt
    # cov[..., a, b] = Σ_j t0[j, a] · p0[j, b]
    cov = np.einsum("...ja,...jb->...ab", t0, p0)
    u, s, vt = np.linalg.svd(cov)
    d = np.sign(np.linalg.det(u @ vt))
    fix = np.ones(s.shape)
    fix[..., -1] = d
    rot = u @ (fix[..., :, None] * vt)  # u · diag(1,1,d) · vᵀ
    var = (p0 ** 2).sum((-2, -1))
    scale = (s * fix).sum(-1) / np.maximum(var, 1e-12)
    return scale[..., None, None] * np.einsum("...ab,...jb->...ja", rot, p0) + mt


def pa_mpjpe(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(…,J,3), (…,J,3) → (…) metres: mean joint error after Procrustes alignment per frame."""
    aligned = procrustes_align(pred, true)
    return np.linalg.norm(aligned - np.asarray(true, np.float64), axis=-1).mean(-1)


def with_true_orientation(pred_pose_aa: np.ndarray, true_pose_aa: np.ndarray) -> np.ndarray:
    """(N,72), (N,72) → (N,72): the predicted local pose under the true global orientation."""
    out = np.array(pred_pose_aa, np.float64, copy=True)
    out[..., 0:3] = np.asarray(true_pose_aa, np.float64)[..., 0:3]
    return out


def local_mpjpe(body, pred_pose_aa: np.ndarray, pred_betas: np.ndarray, true_joints: np.ndarray,
                true_pose_aa: np.ndarray) -> np.ndarray:
    """(N,72), (N,10), (N,J,3), (N,72) → (N,) metres: MPJPE of the predicted local pose and shape
    re-posed with the true global orientation. ``body`` is an ``edge.body.BodyModel``."""
    joints = body.forward(with_true_orientation(pred_pose_aa, true_pose_aa), pred_betas)["joints"]
    return mpjpe(joints, true_joints)


def heading_rad(orient_aa: np.ndarray) -> np.ndarray:
    """(…,3) global orientation (axis-angle) → (…) the body's heading about carpet z, radians in (-π, π]:
    the twist about z of R · R_uprightᵀ (R_upright = +90° about x), so Rz(ψ)·R_upright has heading ψ."""
    o = np.asarray(orient_aa, np.float64)
    return heading_error_rad(o, np.broadcast_to(UPRIGHT_AA, o.shape))


def heading_error_rad(pred_orient_aa: np.ndarray, true_orient_aa: np.ndarray) -> np.ndarray:
    """(…,3), (…,3) global orientations (axis-angle) → (…) signed rotation about carpet z, radians,
    in (-π, π]: the twist about z of R_pred · R_trueᵀ."""
    pred, true = np.asarray(pred_orient_aa, np.float64), np.asarray(true_orient_aa, np.float64)
    shape = np.broadcast_shapes(pred.shape, true.shape)[:-1]
    rp = Rotation.from_rotvec(np.broadcast_to(pred, shape + (3,)).reshape(-1, 3).copy())
    rt = Rotation.from_rotvec(np.broadcast_to(true, shape + (3,)).reshape(-1, 3).copy())
    q = (rp * rt.inv()).as_quat()  # (x, y, z, w)
    angle = 2 * np.arctan2(q[:, :3] @ UP, q[:, 3])  # twist about UP
    return (np.mod(angle + np.pi, 2 * np.pi) - np.pi).reshape(shape)


def pve(pred_vertices: np.ndarray, true_vertices: np.ndarray, pred_pelvis: np.ndarray,
        true_pelvis: np.ndarray) -> np.ndarray:
    """(…,V,3), (…,V,3), (…,3), (…,3) → (…) metres: mean vertex error, each mesh moved by its pelvis."""
    pv = np.asarray(pred_vertices, np.float64) - np.asarray(pred_pelvis, np.float64)[..., None, :]
    tv = np.asarray(true_vertices, np.float64) - np.asarray(true_pelvis, np.float64)[..., None, :]
    return np.linalg.norm(pv - tv, axis=-1).mean(-1)
