"""The differentiable PyTorch twin of ``edge.body.BodyModel`` (training losses).

Same file, same conventions, same numbers (parity ≤ 1e-6 m in float64, tested):
``pose_aa[:, 0:3]`` rotates the canonical body (Y up, facing +Z) into the world and
``transl_m`` is where the pelvis joint lands. Differences, on purpose: no input
checks (they would synchronise the device), betas are not clamped (that would cut
gradients; keep training shapes within ±5), and Rodrigues has finite gradients at
angle 0 (Taylor branch in θ², the other branch fed a safe value).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from edge.body.files import BodyArrays, read_body_file
from edge.body.lbs import kinematic_levels
from edge.body.model import SHIPPED_MODELS, shipped_model_path

_TAYLOR_BELOW_RAD2 = 1e-8  # θ² below which sinc uses its series (θ < 1e-4)


def _sinc_of_square(x2: torch.Tensor) -> torch.Tensor:
    """sin(x)/x as a function of x², finite with finite gradients everywhere."""
    small = x2 < _TAYLOR_BELOW_RAD2
    safe = torch.where(small, torch.ones_like(x2), x2)
    x = torch.sqrt(safe)
    return torch.where(small, 1.0 - x2 / 6.0 + x2 * x2 / 120.0, torch.sin(x) / x)


def axis_angle_to_matrix(rotvec: torch.Tensor) -> torch.Tensor:
    """Rodrigues: (..., 3) → (..., 3, 3); R = I + sinc(θ)·K + ½·sinc(θ/2)²·K²."""
    theta2 = (rotvec * rotvec).sum(-1)
    a = _sinc_of_square(theta2)[..., None, None]
    half = _sinc_of_square(0.25 * theta2)[..., None, None]
    x, y, z = rotvec.unbind(-1)
    zero = torch.zeros_like(x)
    k = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], -1).reshape(rotvec.shape + (3,))
    eye = torch.eye(3, dtype=rotvec.dtype, device=rotvec.device)
    return eye + a * k + 0.5 * half * half * (k @ k)


class TorchBodyModel(torch.nn.Module):
    """SMPL-layout body model as a torch module; buffers follow ``.to(dtype/device)``."""

    def __init__(self, arrays: BodyArrays, dtype: torch.dtype = torch.float32):
        super().__init__()
        self.parents = [int(p) for p in arrays.parents]
        self.levels = [(torch.as_tensor(c), torch.as_tensor(p)) for c, p in kinematic_levels(arrays.parents)]
        self.num_joints = arrays.num_joints
        self.num_betas = arrays.num_betas

        def buf(name, value):
            self.register_buffer(name, torch.as_tensor(np.ascontiguousarray(value), dtype=dtype))

        buf("v_template", arrays.v_template)
        buf("shapedirs", arrays.shapedirs.reshape(-1, arrays.num_betas))  # (3V,NB)
        buf("J_regressor", arrays.J_regressor)
        buf("j_template", arrays.J_regressor @ arrays.v_template)
        buf("j_shapedirs", np.einsum("jv,vkl->jkl", arrays.J_regressor, arrays.shapedirs))
        buf("weights", arrays.weights)
        self.has_posedirs = arrays.posedirs is not None
        if self.has_posedirs:
            buf("posedirs", arrays.posedirs.reshape(-1, arrays.posedirs.shape[2]).T)  # (P,3V)
        self.register_buffer("faces", torch.as_tensor(arrays.faces), persistent=False)

    @classmethod
    def load(cls, path: str | Path = "full", dtype: torch.dtype = torch.float32) -> "TorchBodyModel":
        if isinstance(path, str) and path in SHIPPED_MODELS:
            path = shipped_model_path(path)
        return cls(read_body_file(path), dtype=dtype)

    def forward(self, pose_aa, betas=None, transl_m=None, vertices: bool = False) -> dict[str, torch.Tensor]:
        """pose_aa (B,3J) or (B,J,3); betas (B,≤NB) or None; transl_m (B,3) or None.

        Returns {'joints': (B,J,3)} and, when asked, 'vertices': (B,V,3).
        """
        dtype = self.v_template.dtype
        batch = pose_aa.shape[0]
        pose = pose_aa.reshape(batch, self.num_joints, 3).to(dtype)
        if betas is None:
            betas = pose.new_zeros(batch, self.num_betas)
        elif betas.shape[-1] < self.num_betas:
            betas = torch.nn.functional.pad(betas, (0, self.num_betas - betas.shape[-1]))
        betas = betas.to(dtype).expand(batch, -1)
        transl = pose.new_zeros(batch, 3) if transl_m is None else transl_m.to(dtype).expand(batch, 3)
        return self.forward_matrices(axis_angle_to_matrix(pose), betas, transl, vertices)

    def forward_matrices(self, rot: torch.Tensor, betas: torch.Tensor, transl: torch.Tensor,
                         vertices: bool = False) -> dict[str, torch.Tensor]:
        """The forward from rotation matrices rot (B,J,3,3), betas (B,NB), transl (B,3) of this
        model's dtype (training feeds the network's 6D rotations as matrices)."""
        dtype = self.v_template.dtype
        batch = rot.shape[0]
        # J[b,j,k] = Jt[j,k] + sum_l JS[j,k,l] betas[b,l]
        rest_joints = self.j_template + torch.einsum("jkl,bl->bjk", self.j_shapedirs, betas)
        g_rot = [None] * self.num_joints
        g_t = [None] * self.num_joints
        g_rot[0], g_t[0] = rot[:, 0], rest_joints[:, 0]
        for i in range(1, self.num_joints):  # lists, not in-place writes: autograd-friendly
            p = self.parents[i]
            g_rot[i] = g_rot[p] @ rot[:, i]
            g_t[i] = (g_rot[p] @ (rest_joints[:, i] - rest_joints[:, p])[..., None])[..., 0] + g_t[p]
        g_rot = torch.stack(g_rot, 1)
        g_t = torch.stack(g_t, 1)
        offset = transl - rest_joints[:, 0]
        out = {"joints": g_t + offset[:, None]}
        if vertices:
            v = self.v_template + (betas @ self.shapedirs.T).reshape(batch, -1, 3)
            if self.has_posedirs:
                eye = torch.eye(3, dtype=dtype, device=rot.device)
                feature = (rot[:, 1:] - eye).reshape(batch, -1)
                v = v + (feature @ self.posedirs).reshape(batch, -1, 3)
            t = g_t - (g_rot @ rest_joints[..., None])[..., 0]
            a = torch.cat([g_rot, t[..., None]], -1).reshape(batch, self.num_joints, 12)
            per_vertex = (self.weights @ a).reshape(batch, -1, 3, 4)
            # v'[b,n,i] = sum_k T[b,n,i,k] v[b,n,k] + T[b,n,i,3]
            v = (per_vertex[..., :3] @ v[..., None])[..., 0] + per_vertex[..., 3]
            out["vertices"] = v + offset[:, None]
        return out
