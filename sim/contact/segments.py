"""A segment mass model: the body's centre of mass from segment masses and centres that
move rigidly with their joints, so it does not change with pose (the posed mesh's
volume does: deep flexion folds it into itself, the deep squat loses ~10 %).

Masses are de Leva's (1996, J Biomech 29:1223) fractions of body mass, adjusted from
Zatsiorsky–Seluyanov; each segment's centre lies at a fixed fraction of the way from its
proximal to its distal SMPL joint. The trunk is de Leva's three trunk segments along the
SMPL spine. SMPL joints sit near the skeleton, not at the segments' volume centres, so
one offset per subject, carried by the trunk segments in their own frames, makes the
zero-pose centre of mass equal the zero-pose mesh's volume centroid (where the mesh is
right).

    model = SegmentMassModel(body, betas)
    model.com_m(pose_aa, transl_m)        # (T,3) centre of mass in the carpet frame
"""

from __future__ import annotations

import numpy as np

from edge.body import SMPL_PARENTS, lbs
from edge.body.rotations import axis_angle_to_matrix
from sim.contact.mesh import mesh_centroid_m

# (segment, proximal joint, distal joint, mass fraction, centre as a fraction proximal → distal)
DE_LEVA = (
    ("head", "neck", "head", 0.0694, 1.4),  # SMPL's head joint is at the skull base; the head's centre ~1.4 neck→head
    ("upper_trunk", "spine3", "neck", 0.1596, 0.50),
    ("middle_trunk", "spine1", "spine3", 0.1633, 0.50),
    ("lower_trunk", "pelvis", "spine1", 0.1117, 0.50),
    ("left_upper_arm", "left_shoulder", "left_elbow", 0.0271, 0.5772),
    ("right_upper_arm", "right_shoulder", "right_elbow", 0.0271, 0.5772),
    ("left_forearm", "left_elbow", "left_wrist", 0.0162, 0.4574),
    ("right_forearm", "right_elbow", "right_wrist", 0.0162, 0.4574),
    ("left_hand", "left_wrist", "left_hand", 0.0061, 0.60),
    ("right_hand", "right_wrist", "right_hand", 0.0061, 0.60),
    ("left_thigh", "left_hip", "left_knee", 0.1416, 0.4095),
    ("right_thigh", "right_hip", "right_knee", 0.1416, 0.4095),
    ("left_shank", "left_knee", "left_ankle", 0.0433, 0.4459),
    ("right_shank", "right_knee", "right_ankle", 0.0433, 0.4459),
    ("left_foot", "left_ankle", "left_foot", 0.0137, 0.50),
    ("right_foot", "right_ankle", "right_foot", 0.0137, 0.50),
)
_TRUNK = ("upper_trunk", "middle_trunk", "lower_trunk")


class SegmentMassModel:
    """Pose-independent centre of mass of one subject (``body``: an edge.body.BodyModel)."""

    def __init__(self, body, betas):
        names = list(body.joint_names)
        self.prox = np.array([names.index(s[1]) for s in DE_LEVA])
        dist = np.array([names.index(s[2]) for s in DE_LEVA])
        self.frac = np.array([s[3] for s in DE_LEVA])
        self.frac = self.frac / self.frac.sum()
        betas = np.asarray(betas, np.float64).reshape(1, -1)
        zero = np.zeros((1, 3 * body.num_joints))
        fw = body.forward(zero, betas, np.zeros((1, 3)), vertices=True)
        self.rest = fw["joints"][0] - fw["joints"][0, 0]  # (J,3) canonical, pelvis at the origin
        self.levels = lbs.kinematic_levels(np.asarray(SMPL_PARENTS))
        # Segment centres in the proximal joint's frame (at rest all frames are the identity).
        along = np.array([s[4] for s in DE_LEVA])[:, None]
        self.local = along * (self.rest[dist] - self.rest[self.prox])
        rest_com = self.frac @ (self.rest[self.prox] + self.local)
        delta = mesh_centroid_m(fw["vertices"][0], body.faces) - fw["joints"][0, 0] - rest_com
        trunk = np.array([s[0] in _TRUNK for s in DE_LEVA])
        self.local[trunk] += delta / self.frac[trunk].sum()

    def com_m(self, pose_aa, transl_m) -> np.ndarray:
        """(T,3) centre of mass for poses (T,72) and pelvis positions (T,3)."""
        pose = np.asarray(pose_aa, np.float64).reshape(len(pose_aa), -1, 3)
        rot = axis_angle_to_matrix(pose)
        rest = np.broadcast_to(self.rest, (len(pose),) + self.rest.shape)
        return self.com_from_fk(*lbs.forward_kinematics(rot, rest, self.levels)) + np.asarray(transl_m, np.float64)

    def com_from_fk(self, g_rot, g_t) -> np.ndarray:
        """(T,3) centre of mass relative to the pelvis from global joint rotations (T,J,3,3) and
        positions (T,J,3) of a pelvis-relative forward kinematics of this shape."""
        seg = g_t[:, self.prox] + np.einsum("tsij,sj->tsi", g_rot[:, self.prox], self.local)
        return np.einsum("s,tsi->ti", self.frac, seg)

    @property
    def rest_com_m(self) -> np.ndarray:
        """(3,) centre of mass at rest, pelvis at the origin, canonical frame."""
        return self.frac @ (self.rest[self.prox] + self.local)
