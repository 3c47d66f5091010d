"""Beyond the paper in the simulated cell: a 500 g load grasped and released during a slow move."""

from __future__ import annotations

import numpy as np

from ftcomp.huang2020.beyond import run_grasp_during_move, run_motion_without_grasp
from ftcomp.huang2020.beyond_inertial import run_fast_move


def test_a_load_grasped_during_a_slow_move_is_weighed_within_one_second() -> None:
    run = run_grasp_during_move(seed=11, samples_per_pose=60)
    assert [k for k, _ in run.events] == ["grasp", "release"]
    i = run.at(run.grasp_s + 1.0)
    # The bounds: mass within 1 %, centre of gravity within 2 mm, 1 s after the grasp.
    assert abs(run.mass_kg[i] - run.true_mass_kg) < 0.01 * run.true_mass_kg
    assert np.linalg.norm(run.cog_m[i] - run.true_cog_m) < 2e-3
    assert run.state[i] == "holding"
    assert 0.0 <= run.detected_release_s - run.release_s <= 0.2


def test_moving_without_a_load_reports_no_grasp() -> None:
    run = run_motion_without_grasp(seed=12, duration_s=9.0, samples_per_pose=60)
    assert run.false_grasps == 0
    assert run.duration_s == 9.0


def test_inertial_compensation_with_identified_inertia_cuts_a_fast_moves_error_fivefold() -> None:
    run = run_fast_move(seed=13, samples_per_pose=60)
    # The move the issue asks for: up to 3 m/s^2 and 2 rad/s (the truth's peaks).
    assert 2.5 < run.peak_accel_mps2 <= 3.1 and 1.5 < run.peak_omega_rad_s <= 2.0
    assert run.inertial_rms_N <= 0.2 * run.static_rms_N
    # With an IMU in the sensor (MuJoCo's accelerometer and gyroscope truth plus a Bota's
    # noise): the accelerometer's apparent gravity alone, with no inertia and no derivative,
    # cuts the error fourfold (0.17-0.18 measured); the whole inertial wrench of the IMU's
    # motion about as well as that of the poses' (0.16-0.18 and 0.15-0.16, seeds 13 and 14).
    assert run.imu_linear_rms_N <= 0.25 * run.static_rms_N
    assert run.imu_inertial_rms_N <= 0.2 * run.static_rms_N
    # The inertia is ftcomp's, identified within 5 % of the simulated tool's moments.
    true = np.linalg.eigvalsh(run.true_inertia_kgm2)
    got = np.linalg.eigvalsh(run.dynamic.inertia_cog_kgm2)
    np.testing.assert_allclose(got, true, rtol=0.05)
