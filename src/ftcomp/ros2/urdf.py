"""The sensor's pose from joint states and the robot description (URDF).

The URDF is parsed by pytransform3d (:func:`pytransform3d.urdf.parse_urdf`): maintained, pure
Python on numpy, no ROS needed, and explicit about its conventions (a joint's ``<origin>`` is the
child-to-parent transform with fixed-axis roll-pitch-yaw; the ``<axis>`` is in the joint frame),
the same parser its :class:`~pytransform3d.urdf.UrdfTransformManager` uses. That manager computes
one configuration at a time (about 0.3 ms for a six-joint arm); a bag holds tens of thousands of
readings, so :class:`UrdfChain` composes the parsed joints of the chain for every reading at once
with the same formula (``T_parent_child = child2parent @ joint_motion(q)``); the tests check it
against ``UrdfTransformManager.get_transform``.

Joint positions are interpolated linearly to each reading's stamp (per joint, over the messages
that name it); a stamp outside the recorded span has no pose.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from pytransform3d.urdf import Joint, parse_urdf
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.ros2.bag import JointStates

__all__ = ["UrdfChain"]


class UrdfChain:
    """The kinematic chain from ``base`` to ``sensor`` in a URDF.

    Args:
        path: the URDF file (meshes are not loaded).
        base: the link the poses are given in (the robot's base frame).
        sensor: the link whose pose is wanted (the sensor frame).

    Raises:
        InputFileError: unreadable or invalid URDF, or a link not in it.
    """

    def __init__(self, path: str | Path, base: str, sensor: str) -> None:
        self.source = str(path)
        try:
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise InputFileError(f"{path}: cannot read the URDF ({exc.strerror})") from None
        try:
            _name, links, joints = parse_urdf(text, strict_check=False)
        except Exception as exc:  # UrdfException, and the XML parser's errors
            raise InputFileError(f"{path}: not a valid URDF ({exc})") from None
        link_names = {link.name for link in links}
        for frame in (base, sensor):
            if frame not in link_names:
                raise InputFileError(
                    f"{path}: link {frame!r} is not in the URDF; links: "
                    + ", ".join(sorted(str(n) for n in link_names))
                )
        self._parent_joint: dict[str, Joint] = {str(j.child): j for j in joints}
        up_base = self._ancestry(base)
        up_sensor = self._ancestry(sensor)
        common = next(f for f in up_sensor if f in up_base)
        #: Joints from the common ancestor down to the base, and down to the sensor.
        self._down_to_base = self._joints_below(common, up_base)
        self._down_to_sensor = self._joints_below(common, up_sensor)
        movable = [
            str(j.joint_name)
            for j in (*self._down_to_base, *self._down_to_sensor)
            if j.joint_type != "fixed"
        ]
        #: The movable joints on the chain (the joint states must name each of them).
        self.joint_names: tuple[str, ...] = tuple(movable)

    def _ancestry(self, link: str) -> list[str]:
        """The link and its ancestors up to the root."""
        out = [link]
        while out[-1] in self._parent_joint:
            out.append(str(self._parent_joint[out[-1]].parent))
        return out

    def _joints_below(self, ancestor: str, ancestry: list[str]) -> list[Joint]:
        """Joints from ``ancestor`` down the given ancestry, top first."""
        frames = ancestry[: ancestry.index(ancestor)]
        return [self._parent_joint[f] for f in reversed(frames)]

    def _compose(
        self, joints: list[Joint], q: dict[str, NDArray[np.float64]], n: int
    ) -> NDArray[np.float64]:
        T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        for joint in joints:
            motion = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
            if joint.joint_type in ("revolute", "continuous"):
                axis = np.asarray(joint.joint_axis, dtype=float)
                axis = axis / np.linalg.norm(axis)
                rotvec = q[str(joint.joint_name)][:, None] * axis
                motion[:, :3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
            elif joint.joint_type == "prismatic":
                axis = np.asarray(joint.joint_axis, dtype=float)
                motion[:, :3, 3] = q[str(joint.joint_name)][:, None] * (axis / np.linalg.norm(axis))
            T = T @ (np.asarray(joint.child2parent, dtype=float) @ motion)
        return T

    def forward(self, q: dict[str, NDArray[np.float64]], n: int) -> NDArray[np.float64]:
        """``T_base_sensor`` (n, 4, 4) for joint positions ``q[name]`` (n,) [rad or m]."""
        T_top_base = self._compose(self._down_to_base, q, n)
        T_top_sensor = self._compose(self._down_to_sensor, q, n)
        R_tb = T_top_base[:, :3, :3]
        T = np.empty_like(T_top_sensor)
        T[:, :3, :3] = np.swapaxes(R_tb, 1, 2) @ T_top_sensor[:, :3, :3]
        delta = T_top_sensor[:, :3, 3] - T_top_base[:, :3, 3]
        T[:, :3, 3] = np.einsum("nji,nj->ni", R_tb, delta)
        T[:, 3] = (0.0, 0.0, 0.0, 1.0)
        return T

    def sensor_poses(
        self, states: JointStates, t_ns: NDArray[np.int64], source: str
    ) -> tuple[NDArray[np.float64], Rotation, NDArray[np.bool_]]:
        """``(p_base_sensor (N, 3), R_base_sensor, valid (N,))`` at each stamp.

        Raises:
            InputFileError: a joint of the chain missing from the joint states.
        """
        index = {name: k for k, name in enumerate(states.names)}
        valid = np.ones(len(t_ns), bool)
        q: dict[str, NDArray[np.float64]] = {}
        x = (t_ns - states.t_ns[0]).astype(np.float64)
        for name in self.joint_names:
            k = index.get(name)
            column = states.positions[:, k] if k is not None else np.empty(0)
            have = np.isfinite(column)
            if k is None or not have.any():
                raise InputFileError(
                    f"{source}: joint {name!r} of the chain in {self.source} is not in "
                    f"{states.topic}; joints there: {', '.join(states.names) or 'none'}"
                )
            t = states.t_ns[have]
            xp = (t - states.t_ns[0]).astype(np.float64)
            q[name] = np.interp(x, xp, column[have])
            valid &= (t_ns >= t[0]) & (t_ns <= t[-1])
        T = self.forward(q, len(t_ns))
        if not np.isfinite(T).all():
            raise InputFileError(f"{source}: non-finite joint positions in {states.topic}")
        return T[:, :3, 3], Rotation.from_matrix(T[:, :3, :3]), valid
