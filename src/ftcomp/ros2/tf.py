"""A transform tree from recorded ``/tf`` and ``/tf_static``, looked up at any time stamp.

Each edge is one ``parent -> child`` transform as ROS publishes it (``TransformStamped``:
``header.frame_id`` = parent, ``child_frame_id`` = child, the child's pose in the parent:
``p_parent_child``, ``R_parent_child``). Static edges hold at every time; a dynamic edge is
interpolated between its stamps (position linearly, orientation by spherical linear
interpolation) and is *not* extrapolated: a stamp outside an edge's recorded span has no pose,
as tf2 refuses to extrapolate.

:meth:`TransformTree.lookup` answers tf2's ``lookupTransform(target, source, t)``: the pose of
``source`` in ``target`` (``p_target_source``, ``R_target_source``), composed along the path
between them in the tree. Frame names lose a leading ``/`` (ROS 1 style).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

from ftcomp.errors import InputFileError

__all__ = ["TransformRecord", "TransformTree", "clean_frame"]


def clean_frame(name: str) -> str:
    """A frame id without the leading ``/`` of ROS 1."""
    return name.lstrip("/")


@dataclass(frozen=True)
class TransformRecord:
    """One recorded transform: the child's pose in the parent at ``t_ns``.

    Attributes:
        t_ns: the header stamp [ns].
        parent: ``header.frame_id``.
        child: ``child_frame_id``.
        p_parent_child: translation [m], shape (3,).
        q_parent_child: rotation as a quaternion ``x, y, z, w`` (ROS order), shape (4,).
        static: from ``/tf_static``.
    """

    t_ns: int
    parent: str
    child: str
    p_parent_child: tuple[float, float, float]
    q_parent_child: tuple[float, float, float, float]
    static: bool


@dataclass
class _Edge:
    parent: str
    child: str
    static: bool
    t_ns: NDArray[np.int64] = field(repr=False)
    p: NDArray[np.float64] = field(repr=False)
    rotations: Rotation = field(repr=False)
    slerp: Slerp | None = field(default=None, repr=False)

    def at(
        self, t_ns: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], Rotation, NDArray[np.bool_]]:
        """Pose at each stamp (held at the ends where invalid) and which stamps it covers."""
        n = len(t_ns)
        if self.static or len(self.t_ns) == 1:
            valid = np.ones(n, bool) if self.static else t_ns == self.t_ns[0]
            q = self.rotations[-1].as_quat()
            return np.repeat(self.p[-1:], n, axis=0), Rotation.from_quat(np.tile(q, (n, 1))), valid
        t0 = self.t_ns[0]
        x = (self.t_ns - t0).astype(np.float64)
        tq = np.clip((t_ns - t0).astype(np.float64), x[0], x[-1])
        valid = (t_ns >= self.t_ns[0]) & (t_ns <= self.t_ns[-1])
        p = np.column_stack([np.interp(tq, x, self.p[:, k]) for k in range(3)])
        if self.slerp is None:
            self.slerp = Slerp(x, self.rotations)
        return p, self.slerp(tq), valid


class TransformTree:
    """The frames and transforms of a recording (see the module docstring).

    Args:
        records: every transform read from the bag, in any order.
        source: the bag, for messages.

    Raises:
        InputFileError: a frame with two parents.
    """

    def __init__(self, records: Iterable[TransformRecord], source: str) -> None:
        self.source = source
        grouped: dict[tuple[str, str], list[TransformRecord]] = {}
        parent_of: dict[str, str] = {}
        for rec in records:
            parent, child = clean_frame(rec.parent), clean_frame(rec.child)
            known = parent_of.setdefault(child, parent)
            if known != parent:
                raise InputFileError(
                    f"{source}: frame {child!r} has two parents in /tf, {known!r} and {parent!r}"
                )
            grouped.setdefault((parent, child), []).append(rec)
        self._edges: dict[tuple[str, str], _Edge] = {}
        for (parent, child), recs in grouped.items():
            static = any(r.static for r in recs)
            if static:
                recs = [recs[-1]]
            t = np.array([r.t_ns for r in recs], dtype=np.int64)
            order = np.argsort(t, kind="stable")
            t = t[order]
            # One pose per stamp (the last one recorded at that stamp).
            keep = np.append(t[1:] != t[:-1], True)
            idx = order[keep]
            self._edges[(parent, child)] = _Edge(
                parent,
                child,
                static,
                t[keep],
                np.array([recs[i].p_parent_child for i in idx], dtype=float),
                Rotation.from_quat([recs[i].q_parent_child for i in idx]),
            )
        self._neighbours: dict[str, list[tuple[str, tuple[str, str]]]] = {}
        for parent, child in self._edges:
            self._neighbours.setdefault(parent, []).append((child, (parent, child)))
            self._neighbours.setdefault(child, []).append((parent, (parent, child)))

    @property
    def frames(self) -> tuple[str, ...]:
        """Every frame named in the recording, sorted."""
        return tuple(sorted(self._neighbours))

    def _path(self, target: str, source: str) -> list[tuple[_Edge, bool]]:
        """Edges from ``target`` to ``source``, each with True where walked parent -> child."""
        for frame in (target, source):
            if frame not in self._neighbours:
                known = ", ".join(self.frames) or "none"
                raise InputFileError(
                    f"{self.source}: frame {frame!r} is not in the tf tree; frames: {known}"
                )
        previous: dict[str, tuple[str, tuple[str, str]] | None] = {target: None}
        todo = deque([target])
        while todo and source not in previous:
            frame = todo.popleft()
            for nxt, key in self._neighbours[frame]:
                if nxt not in previous:
                    previous[nxt] = (frame, key)
                    todo.append(nxt)
        if source not in previous:
            raise InputFileError(
                f"{self.source}: frames {target!r} and {source!r} are not connected in the tf tree"
            )
        path: list[tuple[_Edge, bool]] = []
        frame = source
        while (step := previous[frame]) is not None:
            before, key = step
            path.append((self._edges[key], key[0] == before))
            frame = before
        return path[::-1]

    def chain(self, target: str, source: str) -> list[str]:
        """The frames from ``target`` to ``source``, both included."""
        frames = [target]
        for edge, down in self._path(target, source):
            frames.append(edge.child if down else edge.parent)
        return frames

    def is_static(self, target: str, source: str) -> bool:
        """Whether every transform between the two frames is static."""
        return all(edge.static for edge, _ in self._path(target, source))

    def lookup(
        self, target: str, source: str, t_ns: Sequence[int] | NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], Rotation, NDArray[np.bool_]]:
        """``(p_target_source (N, 3) [m], R_target_source (N rotations), valid (N,))``.

        ``valid`` is False at stamps outside the recorded span of a dynamic transform on the
        path (the pose there is held at the nearest end and must not be used).

        Raises:
            InputFileError: a frame not in the tree, or the two not connected.
        """
        t = np.asarray(t_ns, dtype=np.int64)
        n = len(t)
        p = np.zeros((n, 3))
        R = Rotation.identity(n)
        valid = np.ones(n, bool)
        for edge, down in self._path(target, source):
            p_e, R_e, ok = edge.at(t)
            if not down:  # walking child -> parent: the inverse transform
                R_e = R_e.inv()
                p_e = -R_e.apply(p_e)
            p = p + R.apply(p_e)
            R = R * R_e
            valid &= ok
        return p, R, valid
