"""Read ahead: the next item of an iterator produced in a worker thread while this one is used.

:func:`read_ahead` lets reading and parsing a file's next block overlap with processing the
current one: pyarrow and numpy release the GIL, so the two run on two cores. At most one item
waits between the two threads, so memory stays bounded.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from typing import TypeVar, cast

__all__ = ["read_ahead"]

T = TypeVar("T")


def read_ahead(items: Iterator[T]) -> Iterator[T]:
    """``items``, with the next one produced in a worker thread meanwhile.

    An error in the worker is raised here, at the item where it happened. When the consumer
    stops early (``close()``, or the generator is dropped) the worker stops too: it never
    blocks for good on an item nobody will take.
    """
    ready: queue.Queue[tuple[bool, T | None, BaseException | None]] = queue.Queue(maxsize=1)
    stop = threading.Event()

    def hand_over(item: tuple[bool, T | None, BaseException | None]) -> bool:
        while not stop.is_set():  # never block for good: the consumer may have left
            try:
                ready.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def work() -> None:
        try:
            for item in items:
                if not hand_over((False, item, None)):
                    return
            hand_over((True, None, None))
        except BaseException as exc:  # raised again in the consumer
            hand_over((True, None, exc))

    worker = threading.Thread(target=work, name="ftcomp-read-ahead", daemon=True)
    worker.start()
    try:
        while True:
            done, item, error = ready.get()
            if error is not None:
                raise error
            if done:
                return
            yield cast(T, item)  # not done: an item of ``items``
    finally:
        stop.set()
        worker.join()
