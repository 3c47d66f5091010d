"""The simulated robot cell: arm, F/T sensor, gripper, load and surfaces, stepped at 1 kHz.

:class:`SimCell` implements :class:`ftcomp.hardware.protocols.Robot`; its
:attr:`SimCell.sensor` implements :class:`ftcomp.hardware.protocols.WrenchSensor`. Frames follow
the protocols (the simulated TCP is the sensor frame, an identity mount): poses of the
sensor frame in the (tilted) robot *base* frame, twists of the sensor frame's origin in the base
frame, wrenches in the sensor frame. Only :meth:`SimCell.true_contact_force_N` and the
placement helpers speak of the *world* (z up, level; gravity along -z).

One control cycle (:meth:`SimCell.wait_cycle`) = one differential-IK update of the joint command
from the commanded twist, then ``control_period_s / timestep_s`` MuJoCo steps. The joint servos
are MuJoCo position actuators plus a gravity/Coriolis feedforward (``qfrc_bias``) and a
velocity feedforward, as an industrial controller's servo loop would do.
"""

from __future__ import annotations

import math
from types import TracebackType
from typing import Final

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import ParameterError, SimulationError
from ftcomp.hardware.protocols import ClockName, PoseSample
from ftcomp.sim.gripper import SURFACE_GEOMS, GripperAndSurfaces
from ftcomp.sim.ik import DifferentialIK
from ftcomp.sim.motion import HOME_Q_RAD, ArmMotion
from ftcomp.sim.scene import NAMES, SceneConfig, build_mjcf
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor

__all__ = ["COLLECTION_POSITION_BASE_M", "HOME_Q_RAD", "SimCell"]

#: Where the sensor origin is held for static calibration readings, base frame [m]: in front of
#: the robot, high enough above the table for every orientation of the paper's poses.
COLLECTION_POSITION_BASE_M: Final = (0.45, 0.0, 0.42)
#: Damping of the control-cycle differential IK [m or rad]: negligible away from singularities.
_DLS_DAMPING: Final = 1e-3
#: The control-cycle IK reuses its Jacobian until a joint has moved this far [rad].
_JACOBIAN_REFRESH_RAD: Final = 1e-3
#: Joint speed limit of the velocity interface [rad/s] (the C4's slowest axes reach ~7 rad/s).
_MAX_JOINT_SPEED: Final = 3.0

#: Seeds the random starts of the cell's inverse kinematics (:meth:`SimCell.solve_ik`), drawn
#: once per cell: every solve, a move's or a reachability check's, tries the same starts.
_IK_STARTS_SEED: Final = 20200301
#: Random starts of the inverse kinematics, uniform within the joint ranges.
_RANDOM_IK_STARTS: Final = 30

#: Consecutive still cycles that make :meth:`SimCell.settle` call the cell at rest.
_STILL_CYCLES: Final = 20
_BADQACC: Final = int(mujoco.mjtWarning.mjWARN_BADQACC)


class SimCell(ArmMotion, GripperAndSurfaces):
    """A MuJoCo robot cell implementing the :class:`~ftcomp.hardware.protocols.Robot` protocol,
    with the capability :class:`~ftcomp.hardware.protocols.ChecksReachability` (the cell's IK).

    Args:
        config: the scene (tilt, gripper, load, surface...). Default: level base, gripper,
            no load, no surface.
        sensor_spec: the F/T sensor model. Default: the paper's sensor.
        seed: seeds the sensor noise; the same seed and calls give the same readings.
        control_period_s: control cycle [s] (1 ms); a whole multiple of the physics step.
        q_start_rad: initial joint positions [rad], shape (N,) (the arm's N joints); default:
            the arm's ``home_q_rad`` (:data:`HOME_Q_RAD` for the C4-like arm).
    """

    def __init__(
        self,
        config: SceneConfig | None = None,
        sensor_spec: SensorSpec | None = None,
        *,
        seed: int | None = 0,
        control_period_s: float = 0.001,
        q_start_rad: ArrayLike | None = None,
    ) -> None:
        self._config = config if config is not None else SceneConfig()
        self._model = mujoco.MjModel.from_xml_string(build_mjcf(self._config))
        self._data = mujoco.MjData(self._model)
        self._scratch = mujoco.MjData(self._model)
        m = self._model
        ratio = control_period_s / m.opt.timestep
        if not math.isfinite(ratio) or ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
            raise ParameterError(
                f"control_period_s={control_period_s} must be a whole multiple of the physics "
                f"step {m.opt.timestep} s"
            )
        self._substeps = round(ratio)
        self._period = control_period_s
        self._rate = 1.0 / control_period_s

        self._joint_names = self._config.arm.joint_names
        n = self._n = len(self._joint_names)
        joint_ids = [m.joint(name).id for name in self._joint_names]
        self._qpos_adr = np.array([m.jnt_qposadr[j] for j in joint_ids], dtype=np.intp)
        self._dof_adr = np.array([m.jnt_dofadr[j] for j in joint_ids], dtype=np.intp)
        if np.any(self._dof_adr != np.arange(n)) or np.any(self._qpos_adr != np.arange(n)):
            raise SimulationError(
                f"the arm's {n} joints must be MuJoCo's first {n} degrees of freedom"
            )
        self._qs = slice(int(self._qpos_adr[0]), int(self._qpos_adr[0]) + n)
        self._ds = slice(int(self._dof_adr[0]), int(self._dof_adr[0]) + n)
        self._lower = m.jnt_range[joint_ids, 0].copy()
        self._upper = m.jnt_range[joint_ids, 1].copy()
        self._limits = (self._lower.tolist(), self._upper.tolist())
        self._kv = self._config.arm.kv.copy()
        self._site = m.site(NAMES["ft_site"]).id
        self._sensing_end = m.body(NAMES["sensing_end"]).id
        self._gripper = m.body(NAMES["gripper"]).id if self._config.gripper else -1
        self._load = m.body(NAMES["load"]).id if self._config.load is not None else -1
        self._load_geom = m.geom(NAMES["load_geom"]).id if self._config.load is not None else -1
        self._weld = m.equality(NAMES["grasp_weld"]).id if self._config.load is not None else -1
        self._load_qadr = int(m.jnt_qposadr[m.body_jntadr[self._load]]) if self._load >= 0 else -1
        self._load_dadr = int(m.jnt_dofadr[m.body_jntadr[self._load]]) if self._load >= 0 else -1
        self._surface_set = frozenset(
            gid
            for name in SURFACE_GEOMS
            if (gid := mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)) >= 0
        )
        self._contact_buffer = np.zeros(6)
        sponge = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, NAMES["sponge_joint"])
        self._sponge_qadr = int(m.jnt_qposadr[sponge]) if sponge >= 0 else -1
        self._R_world_base = self._config.R_world_base
        self._R_base_world = np.ascontiguousarray(self._R_world_base.T)
        self._R6_world_base = np.kron(np.eye(2), self._R_world_base)
        self._gravity = float(np.linalg.norm(m.opt.gravity))

        q0 = np.array(
            self._config.arm.home_q_rad if q_start_rad is None else q_start_rad, dtype=float
        )
        self._check_joints(q0, "q_start_rad")
        self._q_cmd = q0.copy()
        self._qd_cmd = np.zeros(n)
        self._twist_world = np.zeros(6)
        self._twist_active = False
        self._dik = DifferentialIK(
            m, self._site, _DLS_DAMPING, refresh_rad=_JACOBIAN_REFRESH_RAD, chain=self._qs
        )
        span = self._upper - self._lower
        random_starts = self._lower + span * np.random.default_rng(_IK_STARTS_SEED).random(
            (_RANDOM_IK_STARTS, n)
        )
        self._ik_starts = np.vstack([self._config.arm.home_q_rad, random_starts])
        self._ik_starts.setflags(write=False)
        d = self._data
        d.qpos[self._qs] = q0
        d.ctrl[:] = q0
        mujoco.mj_forward(m, d)
        # With the servo's gravity feedforward in place, as every physics step has it: the
        # sensor then reads the tool at rest from t = 0, not the arm starting to sag.
        d.qfrc_applied[self._ds] = d.qfrc_bias[self._ds]
        mujoco.mj_forward(m, d)
        self._sensor_spec = sensor_spec if sensor_spec is not None else SensorSpec()
        self._sensor = SimWrenchSensor(
            self._sensor_spec, self.ideal_wrench_sensor, self.time, seed=seed
        )

    # ----------------------------------------------------------------- properties
    @property
    def config(self) -> SceneConfig:
        """The scene this cell was built from."""
        return self._config

    @property
    def model(self) -> mujoco.MjModel:
        """The MuJoCo model (for viewers and inspection; changing it is at your own risk)."""
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        """The MuJoCo data (state)."""
        return self._data

    @property
    def sensor(self) -> SimWrenchSensor:
        """The wrist F/T sensor (implements :class:`~ftcomp.hardware.protocols.WrenchSensor`)."""
        return self._sensor

    @property
    def control_period_s(self) -> float:
        """Control cycle [s]."""
        return self._period

    @property
    def R_world_base(self) -> NDArray[np.float64]:
        """The base's mounting rotation ``Rx(U) @ Ry(V)``, shape (3, 3)."""
        return self._R_world_base.copy()

    @property
    def n_joints(self) -> int:
        """The arm's number of joints, N: MuJoCo's degrees of freedom ``0 .. N-1``
        (``data.qpos[:N]``, ``data.qvel[:N]``)."""
        return self._n

    @property
    def joint_names(self) -> tuple[str, ...]:
        """MJCF names of the arm's joints, base to flange, N."""
        return self._joint_names

    @property
    def q_rad(self) -> NDArray[np.float64]:
        """Measured joint positions [rad], shape (N,)."""
        return np.array(self._data.qpos[self._qs])

    @property
    def qd_rad_per_s(self) -> NDArray[np.float64]:
        """Measured joint velocities [rad/s], shape (N,)."""
        return np.array(self._data.qvel[self._ds])

    @property
    def q_command_rad(self) -> NDArray[np.float64]:
        """Commanded joint positions [rad], shape (N,)."""
        return self._q_cmd.copy()

    @property
    def joint_range_rad(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The joints' ranges ``(lower, upper)`` [rad], each shape (N,): the commanded joints
        stop there."""
        return self._lower.copy(), self._upper.copy()

    # ----------------------------------------------------------------- Robot protocol
    #: Every stamp is simulation time; the pose is the simulated sensor frame's.
    clock_name: ClockName = "simulation"
    pose_known = True

    def __enter__(self) -> SimCell:
        """Nothing to connect: the cell is built."""
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop motion (the joints hold their commanded position)."""
        self.stop()

    def time(self) -> float:
        """Simulation time [s]."""
        return float(self._data.time)

    def now_ns(self) -> int:
        """Simulation time [ns]: the clock of every time stamp of this cell."""
        return round(self._data.time * 1e9)

    def pose(self) -> PoseSample:
        """The TCP pose, stamped: the simulated TCP *is* the sensor frame (identity mount)."""
        d = self._data
        RwbT = self._R_base_world
        p = RwbT @ d.site_xpos[self._site]
        R = RwbT @ d.site_xmat[self._site].reshape(3, 3)
        return PoseSample.owning(round(d.time * 1e9), p, R)

    def sensor_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(p_base_sensor [m] (3,), R_base_sensor (3, 3))`` of the latest physics state."""
        d = self._data
        Rwb = self._R_world_base
        return Rwb.T @ d.site_xpos[self._site], Rwb.T @ d.site_xmat[self._site].reshape(3, 3)

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Set the sensor origin's velocity ``[v (m/s), w (rad/s)]``, base frame, shape (6,).

        Executed from the next :meth:`wait_cycle` on by damped-least-squares differential IK,
        until changed or :meth:`stop`.

        Raises:
            ParameterError: wrong shape or not finite.
        """
        tw = np.asarray(twist_base, dtype=float)
        # The sum is NaN or infinite as soon as one component is (cheaper than isfinite().all()).
        if tw.shape != (6,) or not math.isfinite(tw.sum()):
            raise ParameterError(f"twist_base must be 6 finite numbers, got {twist_base!r}")
        self._twist_world = self._R6_world_base @ tw
        self._twist_active = bool(tw.any())
        if not self._twist_active:
            self._qd_cmd[:] = 0.0

    def command_joints(self, q_rad: NDArray[np.float64], qd_rad_per_s: NDArray[np.float64]) -> None:
        """Set the joint servos' target ``q_rad`` [rad] and its rate ``qd_rad_per_s`` [rad/s]
        (the velocity feedforward), each shape (N,), for the next :meth:`wait_cycle`; a
        commanded twist stops. A target beyond a joint's range is held at the range's end.

        For a controller that plans in joint space (a Franka's joint and Cartesian motion
        generators resolve to joints): a redundant arm's null space then follows the
        controller, not the twist's differential inverse kinematics.

        Raises:
            ParameterError: wrong shapes or not finite.
        """
        q = np.asarray(q_rad, dtype=float)
        qd = np.asarray(qd_rad_per_s, dtype=float)
        n = self._n
        if q.shape != (n,) or qd.shape != (n,) or not math.isfinite(q.sum() + qd.sum()):
            raise ParameterError(
                f"q_rad and qd_rad_per_s must be {n} finite numbers each, got {q_rad!r}, "
                f"{qd_rad_per_s!r}"
            )
        self._twist_world[:] = 0.0
        self._twist_active = False
        self._q_cmd = np.clip(q, self._lower, self._upper)
        self._qd_cmd = qd.copy()

    def stop(self) -> None:
        """Zero the commanded velocity at once (the joints hold the commanded position)."""
        self._twist_world[:] = 0.0
        self._twist_active = False
        self._qd_cmd[:] = 0.0

    def wait_cycle(self) -> None:
        """Advance one control period: differential IK of the commanded twist, then physics."""
        if self._twist_active:  # on floats: a few joints, where numpy calls cost the most
            qd = self._dik.joint_velocity(self._data, self._twist_world)[: self._n].tolist()
            peak = max(map(abs, qd))
            if peak > _MAX_JOINT_SPEED:
                qd = [v * (_MAX_JOINT_SPEED / peak) for v in qd]
            dt, rate = self._period, self._rate
            q_old = self._q_cmd.tolist()
            q = [
                min(max(a + v * dt, lo), hi)
                for a, v, lo, hi in zip(q_old, qd, *self._limits, strict=True)
            ]
            self._qd_cmd = np.array([(b - a) * rate for a, b in zip(q_old, q, strict=True)])
            self._q_cmd = np.array(q)
        self._physics()

    # ----------------------------------------------------------------- physics and sensing
    def _check_joints(self, q: NDArray[np.float64], name: str) -> None:
        if q.shape != (self._n,) or not np.isfinite(q).all():
            raise ParameterError(f"{name} must be {self._n} finite joint angles [rad], got {q!r}")
        bad = np.flatnonzero((q < self._lower - 1e-9) | (q > self._upper + 1e-9))
        if bad.size:
            j = int(bad[0])
            raise ParameterError(
                f"{name}: joint {self._joint_names[j]}={math.degrees(q[j]):.2f} deg is outside "
                f"[{math.degrees(self._lower[j]):.1f}, {math.degrees(self._upper[j]):.1f}] deg"
            )

    def _physics(self) -> None:
        m, d = self._model, self._data
        d.ctrl[:] = self._q_cmd
        ff = self._kv * self._qd_cmd
        for _ in range(self._substeps):
            d.qfrc_applied[self._ds] = d.qfrc_bias[self._ds] + ff
            mujoco.mj_step(m, d)
        # MuJoCo resets the state when the accelerations blow up; never go on silently.
        if d.warning[_BADQACC].number:
            raise SimulationError(f"the simulation became unstable at t={d.time:.4f} s")

    def step(self, n_cycles: int = 1) -> None:
        """Run ``n_cycles`` control cycles with the current command (:meth:`wait_cycle`)."""
        for _ in range(n_cycles):
            self.wait_cycle()

    def is_still(self, velocity_tol: float = 1e-6) -> bool:
        """Whether every degree of freedom moves slower than ``velocity_tol`` [rad/s or m/s]."""
        return float(np.max(np.abs(self._data.qvel))) < velocity_tol

    def settle(
        self, max_duration_s: float = 3.0, velocity_tol: float = 1e-6, *, label: str = ""
    ) -> float:
        """Hold the command until the cell is still; returns the time it took [s].

        Still: every degree of freedom slower than ``velocity_tol`` [rad/s or m/s] for
        :data:`_STILL_CYCLES` cycles in a row (a body released at rest is not yet still).

        Raises:
            SimulationError: still moving after ``max_duration_s``.
        """
        self.stop()
        t0 = self.time()
        n = max(1, round(max_duration_s / self._period))
        still = 0
        for _ in range(n):
            self._physics()
            still = still + 1 if self.is_still(velocity_tol) else 0
            if still >= _STILL_CYCLES:
                return self.time() - t0
        raise SimulationError(
            f"{label or 'the cell'} did not come to rest within {max_duration_s} s "
            f"(max |qvel| = {float(np.max(np.abs(self._data.qvel))):.3g})"
        )

    def ideal_wrench_sensor(self) -> NDArray[np.float64]:
        """The load on the sensor [N, N*m], sensor frame, shape (6,), straight from MuJoCo.

        MuJoCo's force/torque sensors give the wrench the housing exerts on the sensing end;
        the sensor feels the opposite. No bias, noise, quantisation or saturation.
        """
        return np.negative(self._data.sensordata[0:6])
