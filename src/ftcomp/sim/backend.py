"""The ``sim://`` backend: the MuJoCo cell as a robot and its wrist sensor.

Robot URI options (all optional), each a field of :class:`~ftcomp.sim.cell_config.CellConfig`
(where their ranges are)::

    sim://?arm=c4|ur5e|fr3    the arm (:data:`ftcomp.sim.arm.ARMS`; default c4, the C4-like arm)
          &tilt_deg=U,V       base mounting tilt [deg] (default: the paper's -0.204,-0.129)
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

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.sim.arm import ARMS
from ftcomp.sim.cell import SimCell
from ftcomp.sim.cell_config import MAX_LOAD_KG, CellConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.surfaces import SURFACE_KINDS

__all__ = [
    "MAX_LOAD_KG",
    "as_sim_cell",
    "cell_config_from_uri",
    "open_robot",
    "open_sensor",
    "sensor_spec_from_uri",
]


def cell_config_from_uri(uri: Uri) -> CellConfig:
    """The :class:`CellConfig` a ``sim://`` robot URI's options describe.

    Raises:
        ParameterError: an unknown, malformed or out-of-range option, naming the URI.
    """
    options = uri.reader()
    tilt = options.floats("tilt_deg", paper.TILT_DEG)
    gripper = options.flag("gripper", True)
    load_kg = options.number("load_kg", None)
    grasp = options.flag("grasp", False)
    surface = options.text("surface", "none", SURFACE_KINDS)
    seed = options.integer("seed", 0)
    clearance_mm = options.number("clearance_mm", None)
    arm = options.text("arm", "c4", tuple(ARMS))
    text = uri.options.get("gain_error_percent")
    gain: float | tuple[float, ...] = (
        options.floats("gain_error_percent", (0.0,) * 6)
        if text is not None and "," in text
        else options.number("gain_error_percent", 0.0) or 0.0
    )
    rate_f = options.floats("drift_N_per_min", (0.0, 0.0, 0.0))
    rate_t = options.floats("drift_Nm_per_min", (0.0, 0.0, 0.0))
    walk = options.number("drift_walk_N", 0.0) or 0.0
    realistic = options.number("realistic_drift", 0.0) or 0.0
    options.done()
    try:
        return CellConfig(
            arm=ARMS[arm](),
            tilt_deg=(tilt[0], tilt[1]),
            gripper=gripper,
            load_kg=load_kg,
            grasp=grasp,
            surface=surface,  # type: ignore[arg-type]
            clearance_mm=clearance_mm,
            seed=seed,
            gain_error_percent=gain,
            drift_N_per_min=(rate_f[0], rate_f[1], rate_f[2]),
            drift_Nm_per_min=(rate_t[0], rate_t[1], rate_t[2]),
            drift_walk_N=walk,
            realistic_drift=realistic,
        )
    except ParameterError as error:
        raise ParameterError(f"{uri.text!r}: {error}", field=error.fields) from None


def sensor_spec_from_uri(uri: Uri) -> SensorSpec:
    """The sensor model of a ``sim://`` URI (gain error, bias drift):
    ``cell_config_from_uri(uri).sensor_spec()``.

    Raises:
        ParameterError: a malformed or out-of-range value, naming the URI.
    """
    return cell_config_from_uri(uri).sensor_spec()


def open_robot(uri: Uri) -> Robot:
    """A fresh simulated cell (:meth:`CellConfig.open_cell` of the URI's config)."""
    return cell_config_from_uri(uri).open_cell()


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
        raise ParameterError(f"{needs} needs a sim:// robot")
    return robot


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """The wrist sensor of the session's simulated cell."""
    if uri.options or uri.host or uri.path:
        raise ParameterError(
            f"{uri.text!r}: the simulated sensor takes no options; give them to the sim:// robot"
        )
    return as_sim_cell(robot, f"{uri.text!r}: the simulated sensor").sensor
