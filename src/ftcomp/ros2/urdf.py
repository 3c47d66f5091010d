"""The sensor's pose from joint states and the robot description (URDF).

The URDF is parsed by pytransform3d (:func:`pytransform3d.urdf.parse_urdf`): maintained, pure
Python on numpy, no ROS needed, and explicit about its conventions (a joint's ``<origin>`` is the
child-to-parent transform with fixed-axis roll-pitch-yaw; the ``<axis>`` is in the joint frame),
the same parser its :class:`~pytransform3d.urdf.UrdfTransformManager` uses. That manager computes
one configuration at a time (about 0.3 ms for a six-joint arm); a bag holds tens of thousands of
readings, so :class:`UrdfChain` walks the chain for every reading at once with the same formula
(``T_parent_child = child2parent @ joint_motion(q)``, fixed joints merged, Rodrigues for the
motion); the tests check it against ``UrdfTransformManager.get_transform``. The same walk gives
:meth:`UrdfChain.pose_and_jacobian` (one configuration and its geometric Jacobian, for inverse
kinematics: :mod:`ftcomp.chain_ik`).

Joint positions are interpolated linearly to each reading's stamp (per joint, over the messages
that name it); a stamp outside the recorded span has no pose.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.extras import require_extra

if TYPE_CHECKING:
    from pytransform3d.urdf import Joint, Link

    from ftcomp.ros2.bag import JointStates

__all__ = ["UrdfChain", "read_urdf"]

_MOVABLE = ("revolute", "continuous", "prismatic")
#: A movable joint prepared for one configuration: the fixed rotation and translation before
#: it, its unit axis, ``[axis]x`` and its square, and whether it is prismatic (the last step:
#: the fixed rest of the chain).
_Step: TypeAlias = tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    bool,
]
_I3 = np.eye(3)


def read_urdf(path: str | Path) -> tuple[list[Link], list[Joint]]:
    """The links and joints of a URDF file, as pytransform3d parses them (a link's inertial:
    ``mass``, ``inertial_frame`` and ``inertia``; a joint's ``child2parent``, ``joint_axis``,
    ``limits`` and ``joint_type``).

    Raises:
        MissingExtraError: pytransform3d (the extra ``urdf``) is not installed.
        InputFileError: unreadable, a xacro file, or not a valid URDF.
    """
    require_extra("urdf", "reading a URDF")
    from pytransform3d.urdf import parse_urdf

    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise InputFileError(f"{path}: cannot read the URDF ({why})") from None
    if _is_xacro(path, text):
        raise InputFileError(
            f"{path}: a xacro file (macros, not a URDF); expand it first: "
            f"xacro {path} > robot.urdf (ros2 run xacro xacro, or pip install xacro), with the "
            "arguments your launch file passes, then give robot.urdf"
        )
    try:
        _name, links, joints = parse_urdf(text, strict_check=False)
    except Exception as exc:  # UrdfException, and the XML parser's errors
        raise InputFileError(f"{path}: not a valid URDF ({exc})") from None
    return list(links), list(joints)


def _is_xacro(path: str | Path, text: str) -> bool:
    """A xacro file: named ``*.xacro``, or using the xacro namespace or its elements."""
    return str(path).endswith(".xacro") or "xmlns:xacro" in text or "<xacro:" in text


class UrdfChain:
    """The kinematic chain from ``base`` to ``sensor`` in a URDF.

    Args:
        path: the URDF file (meshes are not loaded).
        base: the link the poses are given in (the robot's base frame); None: the URDF's root.
        sensor: the link whose pose is wanted (the sensor frame); None: the one leaf link of
            the tree that a movable joint leads to.

    Raises:
        InputFileError: unreadable or invalid URDF, a link not in it, links not connected, no
            single default link, or a joint whose lower limit exceeds its upper.
    """

    def __init__(self, path: str | Path, base: str | None = None, sensor: str | None = None):
        self.source = str(path)
        links, joints = read_urdf(path)
        link_names = {str(link.name) for link in links}
        self._parent_joint: dict[str, Joint] = {str(j.child): j for j in joints}
        if base is None:
            roots = sorted(n for n in link_names if n not in self._parent_joint)
            if len(roots) != 1:
                raise InputFileError(f"{path}: {len(roots)} root links ({', '.join(roots)})")
            base = roots[0]
        self._check_link(base, link_names)
        if sensor is None:
            sensor = self._single_leaf(self._ancestry(base)[-1], joints)
        self._check_link(sensor, link_names)
        #: The base and tip (sensor) links.
        self.base_link, self.tip_link = base, sensor
        up_base = self._ancestry(base)
        up_sensor = self._ancestry(sensor)
        common = next((f for f in up_sensor if f in up_base), None)
        if common is None:
            raise InputFileError(f"{path}: links {base!r} and {sensor!r} are not connected")
        #: Joints from the common ancestor down to the base, and down to the sensor.
        self._down_to_base = self._joints_below(common, up_base)
        self._down_to_sensor = self._joints_below(common, up_sensor)
        movable = [
            j for j in (*self._down_to_base, *self._down_to_sensor) if j.joint_type != "fixed"
        ]
        #: The movable joints on the chain (the joint states must name each of them).
        self.joint_names: tuple[str, ...] = tuple(str(j.joint_name) for j in movable)
        #: Each movable joint's ``[lower, upper]`` [rad or m], shape (n, 2); continuous joints
        #: and limits the URDF does not give are infinite.
        self.joint_limits: NDArray[np.float64] = np.array(
            [(-np.inf, np.inf) if j.joint_type == "continuous" else j.limits for j in movable],
            dtype=float,
        ).reshape(-1, 2)
        for j, (lo, hi) in zip(movable, self.joint_limits, strict=True):
            if not lo <= hi:
                raise InputFileError(
                    f"{path}: joint {j.joint_name!r} has lower limit {lo:g} above upper {hi:g}"
                )
        for j in movable:
            if not np.linalg.norm(np.asarray(j.joint_axis, dtype=float)) > 0:
                raise InputFileError(f"{path}: joint {j.joint_name!r} has no axis direction")
        self.joint_limits.setflags(write=False)
        #: True for each revolute or continuous joint, False for a prismatic one.
        self.joint_revolute: tuple[bool, ...] = tuple(j.joint_type != "prismatic" for j in movable)
        self._n_base = sum(j.joint_type != "fixed" for j in self._down_to_base)
        self._prismatic = ~np.array(self.joint_revolute, dtype=bool)
        self._steps_base = self._steps(self._down_to_base)
        self._steps_sensor = self._steps(self._down_to_sensor)

    def _check_link(self, link: str, link_names: set[str]) -> None:
        if link not in link_names:
            raise InputFileError(
                f"{self.source}: link {link!r} is not in the URDF; links: "
                + ", ".join(sorted(link_names))
            )

    def _single_leaf(self, root: str, joints: list[Joint]) -> str:
        """The one leaf link below ``root`` with a movable joint on the way to it."""
        children: dict[str, list[Joint]] = {}
        for j in joints:
            children.setdefault(str(j.parent), []).append(j)
        leaves, stack, seen = [], [(root, False)], set()
        while stack:
            link, moved = stack.pop()
            if link in seen:
                continue
            seen.add(link)
            below = children.get(link, [])
            if not below and moved:
                leaves.append(link)
            stack += [(str(j.child), moved or j.joint_type != "fixed") for j in below]
        if len(leaves) != 1:
            found = ", ".join(sorted(leaves)) or "none"
            raise InputFileError(
                f"{self.source}: no single tip link below {root!r} to default to (leaf links "
                f"after a movable joint: {found}); name the sensor link"
            )
        return leaves[0]

    def _ancestry(self, link: str) -> list[str]:
        """The link and its ancestors up to the root."""
        out = [link]
        while out[-1] in self._parent_joint:
            out.append(str(self._parent_joint[out[-1]].parent))
            if out[-1] in out[:-1]:
                raise InputFileError(f"{self.source}: the joints form a loop through {link!r}")
        return out

    def _joints_below(self, ancestor: str, ancestry: list[str]) -> list[Joint]:
        """Joints from ``ancestor`` down the given ancestry, top first."""
        frames = ancestry[: ancestry.index(ancestor)]
        return [self._parent_joint[f] for f in reversed(frames)]

    @staticmethod
    def _steps(joints: list[Joint]) -> list[_Step]:
        """The chain prepared for :meth:`_walk`: fixed transforms merged into the next joint's."""
        steps: list[_Step] = []
        fixed = np.eye(4)
        for joint in joints:
            fixed = fixed @ np.asarray(joint.child2parent, dtype=float)
            if joint.joint_type not in _MOVABLE:
                continue
            axis = np.asarray(joint.joint_axis, dtype=float)
            axis = axis / np.linalg.norm(axis)
            K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            prismatic = joint.joint_type == "prismatic"
            steps.append((fixed[:3, :3].copy(), fixed[:3, 3].copy(), axis, K, K @ K, prismatic))
            fixed = np.eye(4)
        zero = np.zeros((3, 3))
        steps.append((fixed[:3, :3].copy(), fixed[:3, 3].copy(), np.zeros(3), zero, zero, True))
        return steps

    @staticmethod
    def _walk(
        steps: list[_Step], q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Configurations ``q`` (n, k) down a chain: the end frames (n, 4, 4), and each movable
        joint's unit axis and origin (n, k, 3), all in the top frame."""
        n = len(q)
        R = np.broadcast_to(_I3, (n, 3, 3))
        p = np.zeros((n, 3))
        axes = np.empty((n, len(steps) - 1, 3))
        origins = np.empty((n, len(steps) - 1, 3))
        for k, (fixed_R, fixed_p, axis, K, K2, prismatic) in enumerate(steps[:-1]):
            p = p + R @ fixed_p
            R = R @ fixed_R
            axes[:, k] = R @ axis
            origins[:, k] = p
            if prismatic:
                p = p + q[:, k, None] * axes[:, k]
            else:  # Rodrigues: exp(q [axis]x)
                sin, cos = np.sin(q[:, k])[:, None, None], np.cos(q[:, k])[:, None, None]
                R = R @ (_I3 + sin * K + (1.0 - cos) * K2)
        T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        T[:, :3, 3] = p + R @ steps[-1][1]
        T[:, :3, :3] = R @ steps[-1][0]
        return T, axes, origins

    def _kinematics(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """For configurations ``q`` (n, joints): ``T_base_sensor`` (n, 4, 4), and each movable
        joint's axis (n, 3, joints) and origin (n, 3, joints) in the base frame, the base's
        joints' axes reversed (moving one moves the base)."""
        T_top_base, axes_b, origins_b = self._walk(self._steps_base, q[:, : self._n_base])
        T_top_tip, axes_t, origins_t = self._walk(self._steps_sensor, q[:, self._n_base :])
        R_base_top = np.swapaxes(T_top_base[:, :3, :3], 1, 2)
        p_top_base = T_top_base[:, :3, 3, None]
        T = np.broadcast_to(np.eye(4), T_top_tip.shape).copy()
        T[:, :3, :3] = R_base_top @ T_top_tip[:, :3, :3]
        T[:, :3, 3] = (R_base_top @ (T_top_tip[:, :3, 3, None] - p_top_base))[:, :, 0]
        a = R_base_top @ np.concatenate([-axes_b, axes_t], axis=1).transpose(0, 2, 1)
        o = np.concatenate([origins_b, origins_t], axis=1).transpose(0, 2, 1)
        return T, a, R_base_top @ (o - p_top_base)

    def forward(self, q: dict[str, NDArray[np.float64]], n: int) -> NDArray[np.float64]:
        """``T_base_sensor`` (n, 4, 4) for joint positions ``q[name]`` (n,) [rad or m]."""
        x = np.zeros((n, len(self.joint_names)))
        for k, name in enumerate(self.joint_names):
            x[:, k] = q[name]
        return self._kinematics(x)[0]

    def pose(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """``T_base_sensor`` (4, 4) at one configuration ``q`` (n,) in :attr:`joint_names`
        order [rad or m]."""
        return self._kinematics(np.asarray(q, dtype=float).reshape(1, -1))[0][0]

    def pose_and_jacobian(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``T_base_sensor`` (4, 4) and the geometric Jacobian (6, n) at one configuration.

        Args:
            q: joint positions in :attr:`joint_names` order [rad or m], shape (n,).

        Returns:
            The pose, and ``J`` with ``[v; w] = J @ dq``: the velocity of the sensor origin and
            the angular velocity, both in the base frame. A joint between the common ancestor and
            the base moves the base, so it enters with the opposite sign.
        """
        T, a, o = self._kinematics(np.asarray(q, dtype=float).reshape(1, -1))
        T, a, o = T[0], a[0], o[0]
        r = T[:3, 3, None] - o
        J = np.empty((6, len(self.joint_names)))
        J[0] = a[1] * r[2] - a[2] * r[1]  # a x r: a revolute joint's velocity at the tip
        J[1] = a[2] * r[0] - a[0] * r[2]
        J[2] = a[0] * r[1] - a[1] * r[0]
        J[3:] = a
        if self._prismatic.any():
            J[:3, self._prismatic] = a[:, self._prismatic]
            J[3:, self._prismatic] = 0.0
        return T, J

    def joint_origins(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each movable joint's origin in the base frame [m] at configuration ``q``, (n, 3)."""
        return self._kinematics(np.asarray(q, dtype=float).reshape(1, -1))[2][0].T

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
