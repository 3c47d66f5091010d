"""What the stand-ins serve: a known tool model carried through known poses on a timeline.

The timeline starts at ``t0`` on the host's monotonic clock (shared by every process on the
machine). The first pose is held for ``first_hold_s``, every other for ``hold_s``; after each,
the wrist turns to the next in ``move_s`` (as a person guiding the arm would); the last pose is
held until the end. Both
stand-ins compute the same TCP pose at the same time; the fake Net F/T serves
``model.predict(R_base_sensor)`` plus seeded noise, quantised to its counts.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ftcomp.hardware.protocols import Mount
from ftcomp.model import GravityModel

__all__ = ["FORCE_UNIT_N", "TORQUE_UNIT_NM", "Scenario"]

_LBF_N = 0.45359237 * 9.80665  # the pound-force, by definition
_INCH_M = 0.0254
#: Newtons per force unit, by the label the configuration page shows (from the definitions).
FORCE_UNIT_N = {"N": 1.0, "kN": 1e3, "lbf": _LBF_N, "klbf": 1e3 * _LBF_N, "kgf": 9.80665}
#: Newton-metres per torque unit (``Nmm`` is how ATI's page spells N-mm).
TORQUE_UNIT_NM = {
    "Nmm": 1e-3,
    "N-mm": 1e-3,
    "N-m": 1.0,
    "Nm": 1.0,
    "lbf-in": _LBF_N * _INCH_M,
    "lbf-ft": _LBF_N * 12 * _INCH_M,
    "kgf-cm": 9.80665e-2,
}


@dataclass
class Scenario:
    """A stand-in's script (JSON-serialisable; see the module docstring).

    Attributes:
        t0: start of the timeline [s], host monotonic clock.
        rotvecs_base_tcp: TCP orientations in the base frame (rotation vectors [rad]).
        p_base_tcp_m: the TCP position [m], base frame (constant).
        hold_s, move_s: time at each pose and between poses [s].
        first_hold_s: time at the first pose [s] (a client may still be connecting).
        mount_xyz_m, mount_rpy_deg: the sensor frame on the TCP (``Mount.from_xyz_rpy``).
        model: the tool model (``GravityModel`` fields).
        noise: Gaussian noise std of one reading, force [N] and torque [N*m].
        seed: noise seed.
        rate_hz: the sensor's packet rate [Hz].
        counts_per_force, counts_per_torque: counts per force and per torque unit.
        force_unit, torque_unit: the unit labels the configuration page reports.
        lose_every: drop RDT packets whose sequence number is a multiple of this (0: none).
        fault_after_s: this long after streaming first started, begin reporting a serious
            device status (None: never).
        silent_after_s: this long after streaming first started, stop sending (None: never).
        max_s: the stand-in exits after this long, whatever happens [s].
        t0_file: if given, ``t0`` is read from this file once it exists; until then the first
            pose is held. The fake Net F/T writes it when a client first starts streaming
            (``t0`` = then + ``lead_s``): the timeline starts once the client is recording.
        lead_s: see ``t0_file`` [s].
    """

    t0: float
    rotvecs_base_tcp: list[list[float]]
    p_base_tcp_m: list[float] = field(default_factory=lambda: [0.4, 0.1, 0.3])
    hold_s: float = 1.0
    move_s: float = 0.3
    first_hold_s: float = 1.0
    mount_xyz_m: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    mount_rpy_deg: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    model: dict[str, object] = field(default_factory=dict)
    noise: list[float] = field(default_factory=lambda: [0.0, 0.0])
    seed: int = 0
    rate_hz: float = 1000.0
    counts_per_force: float = 1_000_000.0
    counts_per_torque: float = 1000.0
    force_unit: str = "N"
    torque_unit: str = "Nmm"
    lose_every: int = 0
    fault_after_s: float | None = None
    silent_after_s: float | None = None
    max_s: float = 30.0
    t0_file: str | None = None
    lead_s: float = 0.3
    _cache: dict[str, object] = field(default_factory=dict, repr=False, compare=False)

    def to_json(self) -> str:
        """The scenario as one line of JSON (a command-line argument)."""
        return json.dumps({k: v for k, v in asdict(self).items() if not k.startswith("_")})

    @classmethod
    def from_json(cls, text: str) -> Scenario:
        """Back from :meth:`to_json`."""
        return cls(**json.loads(text))

    @staticmethod
    def model_fields(model: GravityModel) -> dict[str, object]:
        """A ``GravityModel`` as the ``model`` field."""
        return {
            "weight_N": model.weight_N,
            "center_of_gravity_m": model.center_of_gravity_m.tolist(),
            "force_bias_N": model.force_bias_N.tolist(),
            "torque_bias_Nm": model.torque_bias_Nm.tolist(),
            "tilt_U_rad": model.tilt_U_rad,
            "tilt_V_rad": model.tilt_V_rad,
        }

    def gravity_model(self) -> GravityModel:
        """The tool model served."""
        m = self.model
        return GravityModel(
            float(m["weight_N"]),  # type: ignore[arg-type]
            np.array(m["center_of_gravity_m"]),
            np.array(m["force_bias_N"]),
            np.array(m["torque_bias_Nm"]),
            tilt_U_rad=float(m["tilt_U_rad"]),  # type: ignore[arg-type]
            tilt_V_rad=float(m["tilt_V_rad"]),  # type: ignore[arg-type]
        )

    def mount(self) -> Mount:
        """The sensor frame on the TCP."""
        return Mount.from_xyz_rpy(self.mount_xyz_m, self.mount_rpy_deg)

    def _cached(self, key: str, make: object) -> object:
        if key not in self._cache:
            self._cache[key] = make()  # type: ignore[operator]
        return self._cache[key]

    def start_timeline(self) -> None:
        """Write ``t0_file`` (once): the timeline starts ``lead_s`` from now."""
        if self.t0_file is None or Path(self.t0_file).exists():
            return
        tmp = Path(self.t0_file + ".tmp")
        tmp.write_text(repr(time.monotonic() + self.lead_s))
        tmp.replace(self.t0_file)

    def elapsed(self) -> float:
        """Time since ``t0`` now [s] (negative before the start)."""
        if self.t0_file is not None and "t0" not in self._cache:
            try:
                text = Path(self.t0_file).read_text()
            except OSError:
                return -1.0
            if not text.strip():
                return -1.0
            self._cache["t0"] = float(text)
        t0 = float(self._cache.get("t0", self.t0))  # type: ignore[arg-type]
        return time.monotonic() - t0

    def tcp_pose(self, t: float) -> tuple[np.ndarray, Rotation, bool]:
        """``(p_base_tcp, R_base_tcp, moving)`` at ``t`` [s] since ``t0``."""
        rotations: Rotation = self._cached(
            "rotations", lambda: Rotation.from_rotvec(self.rotvecs_base_tcp)
        )  # type: ignore[assignment]
        n = len(rotations)
        segment = self.hold_s + self.move_s
        t = t - (self.first_hold_s - self.hold_s)  # the first pose is held longer
        k = max(0, math.floor(t / segment)) if t > 0 else 0
        p = np.array(self.p_base_tcp_m)
        if k >= n - 1:
            return p, rotations[n - 1], False
        phase = t - k * segment
        if phase < self.hold_s:
            return p, rotations[k], False
        s = (phase - self.hold_s) / self.move_s
        s = s * s * (3.0 - 2.0 * s)  # smooth start and stop
        return p, Slerp([0.0, 1.0], rotations[[k, k + 1]])([s])[0], True

    def wrench_counts(self, t: float, rng: np.random.Generator) -> tuple[list[int], bool]:
        """The six counts a reading at ``t`` carries (model + noise, quantised), and whether the
        arm is moving."""
        p, R_tcp, moving = self.tcp_pose(t)
        mount: Mount = self._cached("mount", self.mount)  # type: ignore[assignment]
        model: GravityModel = self._cached("model", self.gravity_model)  # type: ignore[assignment]
        R_base_sensor = mount.sensor_pose(p, R_tcp.as_matrix())[1]
        w = model.predict(R_base_sensor)
        w = w + rng.normal(size=6) * np.repeat(self.noise, 3)
        return self.counts(w), moving

    def _per_unit(self) -> tuple[float, float]:
        """Counts per N and per N*m (unknown units: as N and N*mm)."""
        force = FORCE_UNIT_N.get(self.force_unit, 1.0)
        torque = TORQUE_UNIT_NM.get(self.torque_unit, 1e-3)
        return self.counts_per_force / force, self.counts_per_torque / torque

    def counts(self, wrench: np.ndarray) -> list[int]:
        """Counts for wrenches [N, N*m], shape (6,) (or (n, 6) as an array)."""
        f, t = self._per_unit()
        scaled = np.round(np.asarray(wrench) * np.repeat([f, t], 3))
        return [int(v) for v in scaled] if scaled.ndim == 1 else scaled

    def wrench_from_counts(self, counts: object) -> np.ndarray:
        """The reading [N, N*m] a client should make of ``counts``, (6,) or (n, 6)."""
        f, t = self._per_unit()
        return np.asarray(counts, dtype=float) / np.repeat([f, t], 3)


#: The tool the stand-ins carry: a 5 N gripper on a base tilted by 1.2 and -0.8 degrees.
TOOL_MODEL = GravityModel(
    5.0,
    np.array([0.002, -0.001, 0.06]),
    np.array([0.4, -0.3, 0.2]),
    np.array([0.012, -0.02, 0.005]),
    tilt_U_rad=math.radians(1.2),
    tilt_V_rad=math.radians(-0.8),
)

#: TCP orientations a person might guide the arm through, as the paper's angles
#: ``Rz(alpha) Ry(beta) Rx(gamma)`` [deg]: tool down and tilted up to 60 degrees every way.
HAND_GUIDED_DEG = [
    (0, 0, 180),
    (0, 40, 180),
    (0, -40, 180),
    (90, 0, 140),
    (90, 0, -140),
    (45, 60, 180),
    (-45, -60, 180),
    (135, 30, 150),
    (-135, 30, -150),
    (60, -30, 130),
    (-60, 20, -130),
    (180, 50, 160),
]


def rotvecs(angles_deg: list[tuple[float, float, float]]) -> list[list[float]]:
    """Rotation vectors of paper-angle triples (for ``Scenario.rotvecs_base_tcp``)."""
    return Rotation.from_euler("ZYX", angles_deg, degrees=True).as_rotvec().tolist()
