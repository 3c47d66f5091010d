"""A one-dimensional stand-in for the MuJoCo cell: fast, exact, for loop and fault tests.

The sensor hangs pointing down (R_base_sensor = diag(1, -1, -1)); the robot tracks the commanded
twist with a first-order servo lag; the surface is a spring-damper under the load.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ftcomp.hardware.protocols import PoseSample, WrenchSample
from ftcomp.model import GravityModel

R_DOWN = np.diag([1.0, -1.0, -1.0])
PAPER_MODEL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=0.0,
    tilt_V_rad=0.0,
)


class FakeCell:
    clock_name = "simulation"
    pose_known = True

    def __init__(
        self,
        stiffness_N_per_m: float,
        damping_N_s_per_m: float = 10.0,
        weight_N: float = 4.903,
        noise_N: float = 0.0,
        seed: int = 0,
    ) -> None:
        self.k, self.c, self.weight = stiffness_N_per_m, damping_N_s_per_m, weight_N
        self.noise = noise_N
        self.rng = np.random.default_rng(seed)
        self.t = 0.0
        self.z = 0.1  # sensor height [m]; the load's bottom is 0.1 m below, the surface at 0.
        self.v = 0.0
        self.v_cmd = 0.0
        self.grasped = True
        self.control_period_s = 1e-3
        self._tau = 0.005

    # Robot
    @property
    def robot(self) -> FakeCell:
        return self

    @property
    def sensor(self) -> FakeCell:
        return self

    def __enter__(self) -> FakeCell:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def time(self) -> float:
        return self.t

    def now_ns(self) -> int:
        return round(self.t * 1e9)

    def pose(self) -> PoseSample:
        return PoseSample(self.now_ns(), np.array([0.4, 0.0, self.z]), R_DOWN)

    def settle(self, max_duration_s: float) -> float:
        self.v = 0.0
        return 0.0

    def move_pose(self, p: NDArray[np.float64], R: NDArray[np.float64], duration_s: float) -> None:
        self.z, self.v, self.v_cmd = float(p[2]), 0.0, 0.0
        self.t += duration_s

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        self.v_cmd = float(twist_base[2])

    def stop(self) -> None:
        self.v_cmd = 0.0

    def wait_cycle(self) -> None:
        dt = self.control_period_s
        self.v += (self.v_cmd - self.v) * dt / self._tau
        self.z += self.v * dt
        self.t += dt

    # Sensor
    def read(self) -> WrenchSample:
        load = (
            np.array([0.0, 0.0, -self.weight + self.true_contact_force_N()])
            if self.grasped
            else np.zeros(3)
        )
        f_sensor = (
            R_DOWN.T @ load + self.rng.normal(scale=self.noise, size=3)
            if self.noise
            else R_DOWN.T @ load
        )
        w = PAPER_MODEL.predict(R_DOWN) + np.concatenate([f_sensor, np.zeros(3)])
        return WrenchSample(self.now_ns(), w)

    def read_new(self) -> list[WrenchSample]:
        return [self.read()]

    # Cell
    def load_clearance_m(self) -> float:
        return self.z - 0.1

    def move_to_clearance(self, clearance_m: float) -> None:
        self.z, self.v, self.v_cmd = 0.1 + clearance_m, 0.0, 0.0

    def true_contact_force_N(self) -> float:
        gap = self.load_clearance_m()
        if gap >= 0.0 or not self.grasped:
            return 0.0
        return max(0.0, -self.k * gap - self.c * self.v)

    def load_weight_N(self) -> float:
        return self.weight

    def release(self) -> None:
        self.grasped = False
