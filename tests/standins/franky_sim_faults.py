"""franky-sim's own MuJoCo FR3 behind the twin's error-state server, a reflex on demand.

franky-sim simulates no reflex (its state's errors stay false), so a test cannot make it stop
a motion as a Franka does. This process serves franky-sim's own simulator
(``franky_sim.MujocoSimulator``, its MuJoCo FR3 and physics) through franky-sim's protocol
server with the arm's error state added (:func:`ftcomp.twin.franka_face.server_with_errors`,
the twin's FR3 face's too): on SIGUSR1, a ``cartesian_reflex`` as libfranka's protocol reports
one (the motion's Move command ends ``kReflexAborted``, the state's robot mode ``kReflex`` and
its ``reflex_reason`` naming the error). The loop is franky-sim's own
(``SimulationServer.run_once``: commands, a physics step, the state, at most 1 kHz).

Run as ``python -m standins.franky_sim_faults HOST MAX_S``; prints ``ready`` once it listens,
``reflex`` once one was raised, and exits by itself after ``MAX_S`` seconds.
"""

from __future__ import annotations

import signal
import sys
import time

import franky_sim
from franky_sim import franka_robot_protocol
from franky_sim.mujoco_simulator import MujocoSimulator

from ftcomp.twin.franka_face import CARTESIAN_REFLEX, server_with_errors

_PERIOD_S = 0.001


def main(host: str, max_s: float) -> int:
    asked: list[int] = []
    signal.signal(signal.SIGUSR1, lambda *_: asked.append(1))
    with MujocoSimulator(enable_visualization=False) as sim:
        robot = sim.add_robot()
        server = server_with_errors(franky_sim, franka_robot_protocol)(robot, host)
        server.init()
        sim.start()
        print("ready", flush=True)
        end = time.monotonic() + max_s
        raised = False
        try:
            while time.monotonic() < end:
                started = time.monotonic()
                if asked and not raised:
                    server.reflex(CARTESIAN_REFLEX)
                    raised = True
                    print("reflex", flush=True)
                server.process_commands()
                sim.step()
                server.send_state()
                time.sleep(max(0.0, _PERIOD_S - (time.monotonic() - started)))
        finally:
            server.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], float(sys.argv[2])))
