"""``ftcomp twin``: serve the simulated cell as a robot with a wrist sensor on loopback.

``ftcomp twin --robot-host 127.0.0.N --sensor-host 127.0.0.M [--robot FACE] [--sensor FACE]
[--seconds S] [--load-kg X
--surface sponge|book|none --clearance-mm C] [--tilt-deg U,V] [--truth truth.json]
[--contact-log contact.csv] [--fault NAME --fault-at-s T] [--tcp-offset-mm X,Y,Z
--tcp-rotvec-rad RX,RY,RZ] [--sensor-rate-hz R] [--view HOST:PORT]``

Each device answers with its own protocol on its host (``--robot ur5e``, the default: RTDE
30004 at 500 Hz, the dashboard 29999 and the script ports 30001-30003, as ``ur_rtde`` needs
them; ``--sensor netft``, the default: HTTP netftapi2.xml and RDT over UDP 49152). Nothing else
is bound. Prints ``twin ready: ...`` once every socket
is bound, serves until ``--seconds`` pass or SIGTERM / Ctrl-C, then a line of what it served.
``--view HOST:PORT`` serves the contact wrench, the TCP pose and the safety state live to
Foxglove or Lichtblick (docs/views.md).
See docs/twin.md for a first session rehearsed against it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ftcomp.cli.live_status import view_address
from ftcomp.cli.options import map_field
from ftcomp.errors import ParameterError
from ftcomp.hardware.devices import devices, twin_faces

__all__ = ["register", "run"]


def _floats(text: str, n: int, name: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise ParameterError(f"{name}: {text!r} is not {n} comma-separated numbers") from None
    if len(values) != n:
        raise ParameterError(f"{name}: {text!r} is not {n} comma-separated numbers")
    return values


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``twin`` command's arguments to its parser."""
    parser.description = __doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else None
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--robot-host", required=True, help="loopback address of the robot")
    parser.add_argument("--sensor-host", required=True, help="loopback address of the sensor")
    parser.add_argument(
        "--seconds", type=float, default=3600.0, help="serve this long [s] (default 3600)"
    )
    robots, sensors = twin_faces("robot"), twin_faces("sensor")
    parser.add_argument(
        "--robot",
        default="ur5e",
        help="the robot answered as: "
        + "; ".join(f"{name}, {d.summary} ({d.uri})" for name, d in robots.items())
        + " (default ur5e)",
    )
    parser.add_argument(
        "--sensor",
        default="netft",
        help="the wrist sensor answered as: "
        + "; ".join(f"{name}, {d.summary} ({d.uri})" for name, d in sensors.items())
        + " (default netft)",
    )
    parser.add_argument(
        "--load-kg", type=float, help="a load held in the gripper [kg] (default: none)"
    )
    parser.add_argument("--surface", default="none", help="none | sponge | book (default none)")
    parser.add_argument(
        "--clearance-mm",
        type=float,
        default=5.0,
        help="with a load and a surface: start it this far above [mm] (default 5)",
    )
    parser.add_argument("--tilt-deg", default="0,0", help="base tilt U,V [deg] (default 0,0)")
    parser.add_argument(
        "--start-q-deg",
        default=None,
        help="start the arm at these joint positions, comma-separated, one per joint [deg] "
        "(default: the face's start pose)",
    )
    parser.add_argument("--seed", type=int, default=0, help="sensor noise seed (default 0)")
    parser.add_argument(
        "--gain-error-percent", type=float, default=0.0, help="sensor gain error [%%] (default 0)"
    )
    parser.add_argument(
        "--drift-N-per-min", default="0,0,0", help="force-bias drift x,y,z [N/min] (default 0,0,0)"
    )
    parser.add_argument(
        "--realistic-drift",
        type=float,
        default=0.0,
        metavar="SCALE",
        help="a real sensor's bias drift times SCALE (from a real Axia80's recording): a wander "
        "of 0.03-0.05 N over ten minutes and a warm-up of 2.3 N in z over the quarter hour "
        "after the twin starts (default 0: none)",
    )
    parser.add_argument(
        "--truth",
        metavar="FILE",
        help="write the true tool, bias, tilt, mount (default: not written)",
    )
    parser.add_argument(
        "--contact-log", metavar="FILE", help="write the contact log (CSV; default: not written)"
    )
    faults = {
        f.name: f"{f.name} ({d.twin.name}: {f.does})"
        for d in devices()
        if d.twin is not None
        for f in d.twin.faults
    }
    parser.add_argument(
        "--fault",
        metavar="NAME",
        help="inject this fault on demand, one of the two faces': "
        + "; ".join(faults.values()).replace("%", "%%")
        + " (default: none)",
    )
    parser.add_argument(
        "--fault-at-s",
        type=float,
        default=1.0,
        help="when, after a client first commands the arm to move (run: its loop's first "
        "cycle) [s] (default 1)",
    )
    parser.add_argument(
        "--tcp-offset-mm",
        default="0,0,0",
        help="the controller's TCP offset X,Y,Z [mm]: the flange sits this far behind the "
        "sensor frame (the TCP); actual_TCP_force is at the flange (default 0,0,0)",
    )
    parser.add_argument(
        "--tcp-rotvec-rad",
        default="0,0,0",
        help="the TCP offset's rotation RX,RY,RZ [rad] (default 0,0,0)",
    )
    parser.add_argument(
        "--sensor-rate-hz",
        type=float,
        default=None,
        metavar="R",
        help="the sensor's output rate [Hz]: samples sent evenly at R, each a fresh sample, "
        "up to the device's fastest (a Net F/T's RDT: 7000 Hz; default: the device's own, "
        "else the simulated sensor's 1200 Hz)",
    )
    parser.add_argument(
        "--view",
        type=view_address,
        metavar="HOST:PORT",
        help="serve the contact wrench, TCP pose and safety state over the Foxglove WebSocket "
        "protocol (PORT alone: on 127.0.0.1; default: no view)",
    )
    parser.add_argument(
        "--no-realtime",
        action="store_true",
        help="do not ask for real-time priority (default: SCHED_FIFO where allowed)",
    )
    # The cell's fields a library error names, by the flag that set them.
    for field, flag in (
        ("p_flange_sensor_m", "--tcp-offset-mm"),
        ("rotvec_flange_sensor_rad", "--tcp-rotvec-rad"),
        ("tilt_deg", "--tilt-deg"),
        ("start_q_deg", "--start-q-deg"),
        ("load_kg", "--load-kg"),
        ("clearance_mm", "--clearance-mm"),
        ("gain_error_percent", "--gain-error-percent"),
        ("realistic_drift", "--realistic-drift"),
        ("drift_N_per_min", "--drift-N-per-min"),
        ("sensor_rate_hz", "--sensor-rate-hz"),
        ("fault_at_s", "--fault-at-s"),
        ("robot_host", "--robot-host"),
        ("sensor_host", "--sensor-host"),
    ):
        map_field(parser, field, flag)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Serve the twin; 0 when it ran its time or was stopped by a signal."""
    from ftcomp.sim.cell_config import CellConfig
    from ftcomp.twin.serve import TwinConfig, face_arm, serve_twin

    tilt = _floats(args.tilt_deg, 2, "--tilt-deg")
    drift = _floats(args.drift_N_per_min, 3, "--drift-N-per-min")
    offset = _floats(args.tcp_offset_mm, 3, "--tcp-offset-mm")
    rotvec = _floats(args.tcp_rotvec_rad, 3, "--tcp-rotvec-rad")
    start_q = None
    if args.start_q_deg is not None:
        start_q = _floats(args.start_q_deg, len(args.start_q_deg.split(",")), "--start-q-deg")
    surface = args.surface
    arm = face_arm(args.robot) if args.robot in twin_faces("robot") else None
    cell = CellConfig(
        **({"arm": arm} if arm is not None else {}),  # type: ignore[arg-type]
        load_kg=args.load_kg,
        grasp=args.load_kg is not None,
        surface=surface,
        clearance_mm=args.clearance_mm if args.load_kg is not None and surface != "none" else None,
        tilt_deg=(tilt[0], tilt[1]),
        seed=args.seed,
        gain_error_percent=args.gain_error_percent,
        realistic_drift=args.realistic_drift,
        drift_N_per_min=(drift[0], drift[1], drift[2]),
        p_flange_sensor_m=(offset[0] * 1e-3, offset[1] * 1e-3, offset[2] * 1e-3),
        rotvec_flange_sensor_rad=(rotvec[0], rotvec[1], rotvec[2]),
        start_q_deg=start_q,
    )
    config = TwinConfig(
        robot_host=args.robot_host,
        sensor_host=args.sensor_host,
        seconds=args.seconds,
        robot=args.robot,
        sensor=args.sensor,
        cell=cell,
        truth_path=Path(args.truth) if args.truth else None,
        contact_log_path=Path(args.contact_log) if args.contact_log else None,
        sensor_rate_hz=args.sensor_rate_hz,
        fault=args.fault,
        fault_at_s=args.fault_at_s,
        realtime=not args.no_realtime,
    )
    observers = []
    if args.view:
        from ftcomp.views.foxglove_view import TwinView

        observers.append(TwinView(args.view))
    try:
        result = serve_twin(config, lambda line: print(line, flush=True), observers=observers)
    finally:
        for view in observers:
            view.close()
    print(result.line(), flush=True)
    print(result.timing.line(), flush=True)
    return 0
