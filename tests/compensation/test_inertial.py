"""Inertial compensation: the static model plus the Newton-Euler wrench, and the simulator."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from tests.compensation.test_kinematics import analytic_path

from ftcomp.calibration.identify import calibrate
from ftcomp.calibration_record import MountRotation
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.inertial import InertialCompensator
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.huang2020.beyond_inertial import excitation_moves, record_moves
from ftcomp.kinematics import SensorMotion, imu_motion, inertial_wrench, sensor_motion
from ftcomp.model import GravityModel
from ftcomp.sim.cell import HOME_Q_RAD, SimCell
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec

from conftest import synthetic_samples

TOOL = GravityModel(
    3.2,
    np.array([0.001, -0.002, 0.05]),
    np.array([0.3, -0.2, 0.1]),
    np.array([0.01, 0.02, -0.01]),
    tilt_U_rad=0.003,
    tilt_V_rad=-0.002,
)
INERTIA = np.array([[8e-4, 1e-5, 0.0], [1e-5, 8e-4, 2e-5], [0.0, 2e-5, 4e-4]])


def test_noise_free_moving_readings_compensate_to_zero() -> None:
    _t, _p, R, motion = analytic_path()
    mass = TOOL.weight_N / STANDARD_GRAVITY_MPS2
    readings = TOOL.predict(R) + inertial_wrench(mass, TOOL.center_of_gravity_m, INERTIA, motion)
    out = InertialCompensator(TOOL, INERTIA).compensate(readings, R, motion)
    np.testing.assert_allclose(out, 0.0, atol=1e-12)


def test_compensator_rejects_a_bad_inertia() -> None:
    with pytest.raises(ParameterError, match="inertia_cog_kgm2"):
        InertialCompensator(TOOL, np.eye(2))


def test_kinematics_from_simulated_poses_match_the_simulators_truth() -> None:
    cell = SimCell(SceneConfig(integrator="Euler"), SensorSpec(), seed=1)
    moves = excitation_moves(0.7)
    moves.append((np.array(HOME_Q_RAD) + np.array([0.5, 0.3, -0.3, 0.0, 0.0, 0.0]), 0.8))
    rec = record_moves(cell, moves)
    motion = sensor_motion(rec.t, rec.p, rec.R)
    inner = slice(20, -20)
    peak_a = np.abs(rec.truth[:, 0:3]).max()
    peak_alpha = np.abs(rec.truth[:, 6:9]).max()

    # RMS within 1 % of the peaks: the filter smooths the servos' transients at the moves' ends.
    def rms(x: np.ndarray) -> float:
        return float(np.sqrt(np.mean(x**2)))

    assert rms(motion.accel_sensor_mps2[inner] - rec.truth[inner, 0:3]) < 0.01 * peak_a
    peak_w = np.abs(rec.truth[:, 3:6]).max()
    assert rms(motion.omega_sensor_rad_s[inner] - rec.truth[inner, 3:6]) < 0.01 * peak_w
    assert rms(motion.alpha_sensor_rad_s2[inner] - rec.truth[inner, 6:9]) < 0.01 * peak_alpha


def _moving_tool() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, SensorMotion]:
    """Noise-free readings of TOOL moving along the analytic path (its whole Newton-Euler
    wrench), the orientations, what an accelerometer in the sensor reads, the motion."""
    t, _p, R, motion = analytic_path()
    mass = TOOL.weight_N / STANDARD_GRAVITY_MPS2
    readings = TOOL.predict(R) + inertial_wrench(mass, TOOL.center_of_gravity_m, INERTIA, motion)
    g_sensor = np.einsum("nji,j->ni", R, TOOL.gravity_base_N) / mass
    return t, readings, R, motion.accel_sensor_mps2 - g_sensor, motion


def test_an_accelerometer_compensates_a_moving_tools_linear_inertia() -> None:
    _t, _readings, R, f, motion = _moving_tool()
    # A tool moving without turning (no rotational terms): the accelerometer's apparent
    # gravity is all the static model needs.
    linear = SensorMotion(motion.accel_sensor_mps2, 0 * f, 0 * f)
    mass = TOOL.weight_N / STANDARD_GRAVITY_MPS2
    readings = TOOL.predict(R) + inertial_wrench(mass, TOOL.center_of_gravity_m, INERTIA, linear)
    compensator = GravityCompensator(TOOL)
    np.testing.assert_allclose(
        compensator.compensate(readings, R, specific_force_mps2=f), 0.0, atol=1e-12
    )
    one = compensator.compensate(readings[7], R[7], specific_force_mps2=f[7])
    np.testing.assert_allclose(one, 0.0, atol=1e-12)
    # Held at its pose's gravity instead, the move's m a is left in the force.
    still = compensator.compensate(readings, R)
    np.testing.assert_allclose(still[:, :3], -mass * motion.accel_sensor_mps2, atol=1e-12)
    with pytest.raises(ParameterError, match="specific_force_mps2"):
        compensator.compensate(readings, R, specific_force_mps2=f[:5])


def test_the_whole_inertial_wrench_from_an_imu_compensates_a_turning_tool() -> None:
    t, readings, R, f, motion = _moving_tool()
    g_sensor = np.einsum("nji,j->ni", R, TOOL.gravity_base_N) / (
        TOOL.weight_N / STANDARD_GRAVITY_MPS2
    )
    from_imu = imu_motion(t, f, motion.omega_sensor_rad_s, g_sensor)
    out = InertialCompensator(TOOL, INERTIA).compensate(readings, R, from_imu)
    inner = slice(20, -20)  # the derivative filter's edges extrapolate
    # Only alpha is differentiated (within 5e-3 rad/s^2): through m c and the inertia it is
    # at most 0.33 kg * 0.05 m * 5e-3 ~ 1e-4 N and |I| 5e-3 ~ 5e-6 N*m.
    np.testing.assert_allclose(out[inner, :3], 0.0, atol=2e-4)
    np.testing.assert_allclose(out[inner, 3:], 0.0, atol=2e-5)


def test_still_the_accelerometer_gives_what_the_pose_does_through_a_mount(
    rng: np.random.Generator,
) -> None:
    # A calibration recorded in the flange's frame, its sensor turned in it: at rest the
    # accelerometer reads gravity's opposite in the *sensor's* axes, and must give the same
    # contact wrench as the flange's orientation does through the mount.
    calibration = calibrate(synthetic_samples(rng))
    rotvec = np.array([0.1, -0.3, 1.2])
    R_rec_sensor = Rotation.from_rotvec(rotvec).as_matrix()
    mounted = dataclasses.replace(
        calibration, mount=MountRotation("full", R_rec_sensor, rotvec, np.zeros(3))
    )
    compensator = GravityCompensator(mounted)
    R_base_rec = Rotation.random(20, rng=rng).as_matrix()
    R_base_sensor = R_base_rec @ R_rec_sensor
    gravity = calibration.model.gravity_base_N / compensator.mass_kg
    f = -np.einsum("nji,j->ni", R_base_sensor, gravity)
    readings = rng.normal(0.0, 5.0, (20, 6))
    np.testing.assert_allclose(
        compensator.compensate(readings, R_base_rec, specific_force_mps2=f),
        compensator.compensate(readings, R_base_rec),
        atol=1e-9,
    )
    np.testing.assert_allclose(
        compensator.compensate(readings[3], R_base_rec[3], specific_force_mps2=f[3]),
        compensator.compensate(readings[3], R_base_rec[3]),
        atol=1e-9,
    )
