"""The ``sim://`` backend: the MuJoCo cell as a robot and its wrist sensor.

Robot URI options (all optional)::

    sim://?tilt_deg=U,V       base mounting tilt [deg] (default: the paper's -0.204,-0.129)
          &gripper=1|0        the paper's gripper, or the bare sensing end (default 1)
          &load_kg=X          a load of X kg in the scene (parked on the floor)
          &grasp=1|0          start with the load in the gripper (default 0)
          &surface=none|sponge|book   what lies on the table (default none)
          &seed=N             sensor-noise seed (default 0)
          &clearance_mm=X     start holding the grasped load X mm above the surface (needs
                              grasp=1 and a surface; for ``ftcomp run`` placements)
          &gain_error_percent=G | g1,..,g6   sensor gain error per axis [%] (default 0)
          &drift_N_per_min=X,Y,Z            force-bias drift rate [N/min] (default 0)
          &drift_Nm_per_min=X,Y,Z           torque-bias drift rate [N*m/min] (default 0)
          &drift_walk_N=S     force-bias random walk: its std after one minute [N]; the
                              torque walk gets S times the torque/force noise ratio (default 0)
          &realistic_drift=S  a real sensor's drift times S (from a real Axia80's recording):
                              a smooth wander of 0.03-0.05 N, 0.001-0.002 N*m (10 min time
                              constant) and a warm-up of 2.3 N in z from switch-on (15 min),
                              SensorSpec.realistic_drift
                              (default 0: none)

The sensor URI is ``sim://`` with no options: the cell's own sensor, which needs the robot to be
``sim://`` too (they share the simulation clock). The simulated TCP is the sensor frame, so the
mount is the identity.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.sim.cell import SimCell
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.surfaces import SURFACE_KINDS
from ftcomp.sim.tool import LoadSpec

__all__ = [
    "MAX_LOAD_KG",
    "as_sim_cell",
    "open_robot",
    "open_sensor",
    "scene_from_uri",
    "sensor_spec_from_uri",
]

#: Largest load the simulated arm takes [kg] (the C4-A901S is rated for 4 kg).
MAX_LOAD_KG = 4.0


def scene_from_uri(uri: Uri) -> tuple[SceneConfig, int, bool]:
    """``(scene, seed, grasp)`` from a ``sim://`` robot URI's options.

    Raises:
        ParameterError: an unknown or out-of-range option, naming the URI.
    """
    options = uri.reader()
    tilt = options.floats("tilt_deg", paper.TILT_DEG)
    gripper = options.flag("gripper", True)
    load_kg = options.number("load_kg", None)
    grasp = options.flag("grasp", False)
    surface = options.text("surface", "none", SURFACE_KINDS)
    seed = options.integer("seed", 0)
    options.done()
    for name, value in zip(("U", "V"), tilt, strict=True):
        if abs(value) >= 30.0:
            raise ParameterError(f"{uri.text!r}: tilt {name}={value} deg must be within +-30 deg")
    if load_kg is not None and not 0.0 < load_kg <= MAX_LOAD_KG:
        raise ParameterError(f"{uri.text!r}: load_kg must be in (0, {MAX_LOAD_KG}], got {load_kg}")
    if load_kg is not None and not gripper:
        raise ParameterError(f"{uri.text!r}: a load needs the gripper (drop gripper=0)")
    if grasp and load_kg is None:
        raise ParameterError(f"{uri.text!r}: grasp=1 needs a load (load_kg=X)")
    if seed < 0:
        raise ParameterError(f"{uri.text!r}: seed must be >= 0, got {seed}")
    scene = SceneConfig(
        tilt_U_rad=math.radians(tilt[0]),
        tilt_V_rad=math.radians(tilt[1]),
        gripper=gripper,
        load=LoadSpec(load_kg) if load_kg is not None else None,
        surface=surface,  # type: ignore[arg-type]
    )
    return scene, seed, grasp


_SENSOR_OPTIONS = (
    "gain_error_percent",
    "drift_N_per_min",
    "drift_Nm_per_min",
    "drift_walk_N",
    "realistic_drift",
)


def sensor_spec_from_uri(uri: Uri) -> SensorSpec:
    """The sensor's realism options of a ``sim://`` URI (gain error, bias drift); only these
    options are read (the rest are the scene's).

    Raises:
        ParameterError: a malformed or out-of-range value, naming the URI.
    """
    options = replace(uri, options={k: v for k, v in uri.options.items() if k in _SENSOR_OPTIONS})
    reader = options.reader()
    text = options.options.get("gain_error_percent")
    gain = (
        reader.floats("gain_error_percent", (0.0,) * 6)
        if text is not None and "," in text
        else (reader.number("gain_error_percent", 0.0) or 0.0,) * 6
    )
    rate_f = reader.floats("drift_N_per_min", (0.0, 0.0, 0.0))
    rate_t = reader.floats("drift_Nm_per_min", (0.0, 0.0, 0.0))
    walk = reader.number("drift_walk_N", 0.0) or 0.0
    realistic = reader.number("realistic_drift", 0.0) or 0.0
    reader.done()
    if not (math.isfinite(realistic) and 0.0 <= realistic <= 100.0):
        raise ParameterError(f"{uri.text!r}: realistic_drift must be in 0 .. 100, got {realistic}")
    if any(abs(g) >= 50.0 for g in gain):
        raise ParameterError(f"{uri.text!r}: gain_error_percent must be within +-50 %")
    if walk < 0.0:
        raise ParameterError(f"{uri.text!r}: drift_walk_N must be >= 0, got {walk}")
    base = SensorSpec().realistic_drift(realistic) if realistic else SensorSpec()
    walk_6 = np.repeat([walk, walk * base.torque_noise_std_Nm / base.force_noise_std_N], 3)
    return replace(
        base,
        gain_error_fraction=np.array(gain) / 100.0,
        bias_drift_rate_per_s=np.array([*rate_f, *rate_t]) / 60.0,
        bias_walk_per_sqrt_s=walk_6 / math.sqrt(60.0),
    )


def open_robot(uri: Uri) -> Robot:
    """A fresh simulated cell."""
    clearance_mm = uri.options.get("clearance_mm")
    spec = sensor_spec_from_uri(uri)
    options = {
        k: v for k, v in uri.options.items() if k != "clearance_mm" and k not in _SENSOR_OPTIONS
    }
    scene, seed, grasp = scene_from_uri(replace(uri, options=options))
    cell = SimCell(scene, spec, seed=seed)
    if clearance_mm is None:
        if grasp:
            cell.grasp()
        return cell
    try:
        clearance_m = float(clearance_mm) * 1e-3
    except ValueError:
        clearance_m = math.nan
    if not 0.0 <= clearance_m <= 0.1:
        raise ParameterError(
            f"{uri.text!r}: clearance_mm must be in [0, 100], got {clearance_mm!r}"
        )
    if not grasp or scene.surface == "none":
        raise ParameterError(f"{uri.text!r}: clearance_mm needs grasp=1 and a surface")
    # As the placement cell: grasp 20 mm up (empty on the way), then lower to the clearance.
    cell.hold_above_surface(max(clearance_m, 0.02), 0.5)
    cell.grasp()
    cell.hold_above_surface(clearance_m, 0.3)
    return cell


def as_sim_cell(robot: Robot | None, needs: str) -> SimCell:
    """The session's robot as the simulated cell, for what only the simulation has (its own
    sensor, the ground truth).

    Args:
        robot: the session's robot (None: no robot).
        needs: who needs the cell, for the message (e.g. ``"'sim://': the simulated sensor"``).

    Raises:
        ParameterError: the robot is not ``sim://``.
    """
    if not isinstance(robot, SimCell):
        raise ParameterError(f"{needs} needs --robot sim://")
    return robot


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """The wrist sensor of the session's simulated cell."""
    if uri.options or uri.host or uri.path:
        raise ParameterError(
            f"{uri.text!r}: the simulated sensor takes no options; give them to --robot sim://"
        )
    return as_sim_cell(robot, f"{uri.text!r}: the simulated sensor").sensor
