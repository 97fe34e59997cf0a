"""``BodyModel``: the SMPL function in numpy, as the runtime and outside checks call it.

    model = BodyModel.load("lite")              # or "full", or a path to any SMPL-layout file
    out = model.forward(pose_aa, betas, transl_m, vertices=False)
    out["joints"]      # (B, J, 3) float64, metres, J = 24 for SMPL
    out["vertices"]    # (B, V, 3), only when vertices=True

Conventions (see docs/body-model.md):

* ``pose_aa`` (B, 3·J): axis-angle per joint in SMPL order; ``pose_aa[:, 0:3]`` is the
  global orientation, which rotates the canonical body (Y up, facing +Z) into the
  world (the carpet frame, Z up): a person standing upright has +90° about x.
* ``transl_m`` (B, 3) is where the pelvis joint (joint 0) lands. The pelvis is always
  computed (official SMPL's rest pelvis is not at the origin and moves with the betas),
  so ``out["joints"][:, 0] == transl_m`` for every file. (smplx's ``transl`` instead
  adds to the rest pelvis: ours = theirs + J_0(betas).)
* ``betas`` (B, ≤NB): missing trailing betas are zero. Values beyond ±``betas_limit``
  (default 5, the range training shapes stay in) are clamped with a warning: far
  outside it the body turns inside out (±100 gives 8–12 m bodies).
* Non-finite input raises ``ValueError`` naming the argument; with
  ``nonfinite="zero"`` the offending values are replaced by 0 and a warning is issued.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from importlib import resources
from pathlib import Path

import numpy as np

from edge.body import lbs
from edge.body.files import BodyArrays, read_body_file
from edge.body.rotations import axis_angle_to_matrix

# The models shipped as package data (edge/body/data/), by name.
SHIPPED_MODELS = {
    "full": "cavatar_body_full.npz",  # ~13k vertices: evaluation and rendering
    "lite": "cavatar_body_lite.npz",  # ~1.2k vertices: the board
}

SMPL_JOINT_NAMES = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand", "right_hand",
)
SMPL_PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21)


class BodyModelWarning(UserWarning):
    """Input was changed to keep the body sane (clamped betas, zeroed non-finite values)."""


def shipped_model_path(name: str) -> Path:
    """Path of a model shipped with the package: 'full' or 'lite'."""
    if name not in SHIPPED_MODELS:
        raise ValueError(f"unknown shipped body model {name!r}; expected one of {sorted(SHIPPED_MODELS)} or a file path")
    return Path(str(resources.files("edge.body").joinpath("data", SHIPPED_MODELS[name])))


class BodyModel:
    """A loaded SMPL-layout body model; ``forward`` evaluates it in numpy.

    vertex_dtype: dtype of the vertex products (float32 on the board; float64 for
    parity and evaluation). Rotations and the kinematic chain are always float64.
    """

    def __init__(self, arrays: BodyArrays, vertex_dtype=np.float32, betas_limit: float = 5.0):
        self.arrays = arrays
        self.vertex_dtype = np.dtype(vertex_dtype)
        self.betas_limit = float(betas_limit)
        self.parents = arrays.parents
        self.num_joints = arrays.num_joints
        self.num_betas = arrays.num_betas
        self.num_vertices = arrays.num_vertices
        self.faces = arrays.faces
        self.joint_names = tuple(arrays.joint_names) or (
            SMPL_JOINT_NAMES if self.num_joints == 24 else tuple(f"joint{i}" for i in range(self.num_joints))
        )
        self._levels = lbs.kinematic_levels(self.parents)
        # Joint regression folded into the shape space: the joints-only path is O(J·NB).
        self._j_template = arrays.J_regressor @ arrays.v_template  # (J,3)
        self._j_shapedirs = np.einsum("jv,vkl->jkl", arrays.J_regressor, arrays.shapedirs)  # (J,3,NB)
        vt = self.vertex_dtype
        self._v_template = arrays.v_template.astype(vt)
        self._shapedirs_flat = arrays.shapedirs.reshape(-1, self.num_betas).astype(vt)  # (3V,NB)
        self._posedirs_flat = (
            None if arrays.posedirs is None else arrays.posedirs.reshape(-1, arrays.posedirs.shape[2]).T.astype(vt).copy()
        )  # (9(J-1), 3V)
        self._weights = arrays.weights.astype(vt)

    @classmethod
    def load(cls, path: str | Path = "lite", vertex_dtype=np.float32, betas_limit: float = 5.0) -> "BodyModel":
        """Load a shipped model by name ('full', 'lite') or any SMPL-layout .npz/.pkl file."""
        if isinstance(path, str) and path in SHIPPED_MODELS:
            path = shipped_model_path(path)
        return cls(read_body_file(path), vertex_dtype=vertex_dtype, betas_limit=betas_limit)

    @property
    def sha256(self) -> str:
        """SHA-256 of the file this model was read from (model bundles record it)."""
        return self.arrays.sha256

    @property
    def has_posedirs(self) -> bool:
        return self._posedirs_flat is not None

    def __repr__(self) -> str:
        return (
            f"BodyModel({self.arrays.source!r}, V={self.num_vertices}, J={self.num_joints}, "
            f"NB={self.num_betas}, posedirs={self.has_posedirs})"
        )

    # ------------------------------------------------------------------ inputs

    def _finite(self, name: str, value: np.ndarray, nonfinite: str) -> np.ndarray:
        bad = ~np.isfinite(value)
        if not bad.any():
            return value
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        if nonfinite == "zero":
            warnings.warn(f"{name}: {int(bad.sum())} non-finite value(s) replaced by 0 (first at {where})", BodyModelWarning, stacklevel=4)
            return np.where(bad, 0.0, value)
        raise ValueError(f"{name} contains {int(bad.sum())} non-finite value(s) (first at index {where}); "
                         "pass nonfinite='zero' to zero them")

    def prepare_inputs(self, pose_aa, betas=None, transl_m=None, nonfinite: str = "raise"):
        """Check, broadcast and sanitise inputs → (pose (B,J,3), betas (B,NB), transl (B,3)), float64."""
        if nonfinite not in ("raise", "zero"):
            raise ValueError(f"nonfinite must be 'raise' or 'zero', not {nonfinite!r}")
        n_j = self.num_joints
        pose = np.asarray(pose_aa, dtype=np.float64)
        if pose.shape == (n_j, 3) or pose.shape == (3 * n_j,):
            pose = pose.reshape(1, n_j, 3)
        elif pose.ndim == 2 and pose.shape[1] == 3 * n_j:
            pose = pose.reshape(-1, n_j, 3)
        elif not (pose.ndim == 3 and pose.shape[1:] == (n_j, 3)):
            raise ValueError(f"pose_aa has shape {pose.shape}; expected (B, {3 * n_j}), (B, {n_j}, 3) or ({3 * n_j},)")
        betas = np.zeros((1, self.num_betas)) if betas is None else np.asarray(betas, dtype=np.float64)
        if betas.ndim == 1:
            betas = betas[None]
        if betas.ndim != 2 or betas.shape[1] > self.num_betas:
            raise ValueError(f"betas has shape {betas.shape}; expected (B, n) with n <= {self.num_betas}")
        if betas.shape[1] < self.num_betas:
            betas = np.concatenate([betas, np.zeros((betas.shape[0], self.num_betas - betas.shape[1]))], axis=1)
        transl = np.zeros((1, 3)) if transl_m is None else np.asarray(transl_m, dtype=np.float64)
        if transl.ndim == 1:
            transl = transl[None]
        if transl.ndim != 2 or transl.shape[1] != 3:
            raise ValueError(f"transl_m has shape {transl.shape}; expected (B, 3) or (3,)")
        sizes = {len(pose), len(betas), len(transl)} - {1}
        if len(sizes) > 1:
            raise ValueError(f"batch sizes differ: pose_aa {len(pose)}, betas {len(betas)}, transl_m {len(transl)}")
        batch = sizes.pop() if sizes else 1
        pose = self._finite("pose_aa", pose, nonfinite)
        betas = self._finite("betas", betas, nonfinite)
        transl = self._finite("transl_m", transl, nonfinite)
        limit = self.betas_limit
        over = np.abs(betas) > limit
        if over.any():
            warnings.warn(
                f"betas: {int(over.sum())} value(s) beyond ±{limit:g} clamped (max |beta| {np.abs(betas).max():.3g}); "
                "shapes that far from training are not plausible bodies",
                BodyModelWarning,
                stacklevel=3,
            )
            betas = np.clip(betas, -limit, limit)
        return (
            np.broadcast_to(pose, (batch, n_j, 3)),
            np.broadcast_to(betas, (batch, self.num_betas)),
            np.broadcast_to(transl, (batch, 3)),
        )

    # ------------------------------------------------------------------ the SMPL function

    def forward(self, pose_aa, betas=None, transl_m=None, vertices: bool = False, nonfinite: str = "raise") -> Mapping[str, np.ndarray]:
        """Evaluate bodies.

        pose_aa: (B, 3J) | (B, J, 3) | (3J,) radians; betas: (B, ≤NB) | (≤NB,) | None;
        transl_m: (B, 3) | (3,) | None, the pelvis position in metres. A batch of 1 in
        any argument broadcasts against the others.
        vertices: also skin the mesh (the joints-only path never touches vertex arrays).
        nonfinite: 'raise' (ValueError) or 'zero' (replace by 0, with a warning).
        Returns {'joints': (B,J,3) float64} plus 'vertices': (B,V,3) in ``vertex_dtype``.
        """
        pose, betas, transl = self.prepare_inputs(pose_aa, betas, transl_m, nonfinite)
        rotations = axis_angle_to_matrix(pose)  # (B,J,3,3) float64
        rest_joints = lbs.shape_joints(self._j_template, self._j_shapedirs, betas)  # (B,J,3)
        g_rot, g_t = lbs.forward_kinematics(rotations, rest_joints, self._levels)
        offset = transl - rest_joints[:, 0]  # moves the pelvis onto transl_m
        out = {"joints": g_t + offset[:, None]}
        if vertices:
            v = lbs.shape_vertices(self._v_template, self._shapedirs_flat, betas)
            if self._posedirs_flat is not None:
                feature = lbs.pose_feature(rotations).astype(self.vertex_dtype)
                v = v + (feature @ self._posedirs_flat).reshape(v.shape)
            v = lbs.skin(v, self._weights, g_rot, g_t, rest_joints)
            out["vertices"] = v + offset[:, None].astype(self.vertex_dtype)
        return out

    __call__ = forward
