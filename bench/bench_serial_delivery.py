"""How long a serial device's bytes wait while real-time threads hold every core.

A serial sensor's bytes (a USB serial adapter's, and the twin's serial faces' pseudo-terminal)
reach the reading process through the kernel's tty layer, which moves them to the reader in a
kernel worker thread (a kworker) of normal priority. While SCHED_FIFO threads hold every core,
that worker does not run, and the bytes wait, however high the reader's own priority. A socket's
data (the Net F/T's UDP, RTDE's TCP) are delivered in the sender's context and do not wait.

For each hold time H: one SCHED_FIFO thread per core spins for H ms; 10 ms in, a writer
(SCHED_FIFO, above the spinners) writes 8 bytes to a pty's master, or to a socket (the baseline,
timed in the same run); a reader (SCHED_FIFO, above the spinners) waits for them on the other
side. Prints the wait per channel and the ratio pty/socket:

    python bench/bench_serial_delivery.py             # holds of 50, 100 and 200 ms

Each measurement runs in a process of its own. On this project's 2-core host (2026-11-28),
medians of 3: pty 41.8, 92.2, 192.5 ms; socket 0.2 ms each (ratios 189x, 483x, 1052x). A pty's
wait is the rest of the hold: the kworker runs when a core frees. The worker is woken on the
writer's core, so one real-time thread that runs long there is enough: ur_rtde's receive
thread and numpy's OpenBLAS worker, raised to ``ftcomp run``'s priority, once held a core for
75-80 ms and a serial face's stream went that long silent (hardware/pacing.py; ``run`` leaves
them at their own priority since). A real serial sensor wants a core that real-time threads
leave free now and then (docs/hardware.md, "Real time"). Needs real-time scheduling (root or
CAP_SYS_NICE); exits 2 without it.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import select
import socket
import subprocess
import sys
import time
import tty

import numpy as np

#: Priorities: the spinners below the writer and the reader.
_SPIN, _IO = 10, 20
#: The write comes this long after the spinners start [s].
_WRITE_AFTER_S = 0.01


def _fifo(priority: int) -> None:
    os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))


def _spin(cpu: int, start: float, hold_s: float) -> None:
    os.sched_setaffinity(0, {cpu})
    _fifo(_SPIN)
    while time.monotonic() < start:
        pass
    end = start + hold_s
    while time.monotonic() < end:
        pass


def _write(fd: int, cpu: int, at: float) -> None:
    os.sched_setaffinity(0, {cpu})
    _fifo(_IO)
    while time.monotonic() < at:
        pass
    os.write(fd, time.monotonic_ns().to_bytes(8, "little"))


def wait_ms(channel: str, hold_s: float) -> float:
    """The time from the write to the reader's wake-up [ms], with every core held ``hold_s``."""
    if channel == "pty":
        master, slave = os.openpty()
        tty.setraw(slave)
        read_fd, write_fd, keep = slave, master, (master, slave)
    else:
        a, b = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
        read_fd, write_fd, keep = a.fileno(), b.fileno(), ()
    allowed = os.sched_getaffinity(0)
    cpus = sorted(allowed)
    start = time.monotonic() + 0.2
    workers = [mp.Process(target=_spin, args=(cpu, start, hold_s)) for cpu in cpus]
    workers.append(mp.Process(target=_write, args=(write_fd, cpus[0], start + _WRITE_AFTER_S)))
    _fifo(_IO)
    os.sched_setaffinity(0, {cpus[-1]})
    for worker in workers:
        worker.start()
    try:
        ready, _, _ = select.select([read_fd], [], [], 5.0 + hold_s)
        arrived = time.monotonic_ns()
        if not ready:
            raise RuntimeError(f"{channel}: nothing arrived")
        sent = int.from_bytes(os.read(read_fd, 8), "little")
    finally:
        for worker in workers:
            worker.join()
        for fd in keep:
            os.close(fd)
        if channel != "pty":
            a.close()
            b.close()
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        os.sched_setaffinity(0, allowed)
    return (arrived - sent) * 1e-6


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--hold-ms", type=float, nargs="+", default=[50.0, 100.0, 200.0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per hold and channel")
    parser.add_argument("--one", choices=("pty", "socket"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if any(not 0 < h <= 500 for h in args.hold_ms):
        print("error: --hold-ms: each in (0, 500] ms", file=sys.stderr)
        return 2
    if not 1 <= args.repeats <= 20:
        print("error: --repeats: 1 to 20", file=sys.stderr)
        return 2
    if args.one:  # one measurement, in a process of its own (none of a previous one's state)
        print(f"{wait_ms(args.one, args.hold_ms[0] * 1e-3):.3f}")
        return 0
    try:
        _fifo(_IO)
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    except OSError as exc:
        print(f"error: real-time scheduling refused ({exc.strerror}): run as root", file=sys.stderr)
        return 2

    def measure(channel: str, hold_ms: float) -> float:
        one = [sys.executable, __file__, "--one", channel, "--hold-ms", str(hold_ms)]
        return float(subprocess.run(one, capture_output=True, text=True, check=True).stdout)

    print(
        f"{len(os.sched_getaffinity(0))} cores held by SCHED_FIFO spinners, a write 10 ms in; "
        f"the wait [ms], min / median / max of {args.repeats}"
    )
    for hold_ms in args.hold_ms:
        waits = {
            channel: np.array([measure(channel, hold_ms) for _ in range(args.repeats)])
            for channel in ("pty", "socket")
        }
        text = ", ".join(
            f"{channel} {w.min():6.2f} / {np.median(w):6.2f} / {w.max():6.2f}"
            for channel, w in waits.items()
        )
        ratio = np.median(waits["pty"]) / np.median(waits["socket"])
        print(f"hold {hold_ms:4.0f} ms: {text} (median ratio {ratio:4.0f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
