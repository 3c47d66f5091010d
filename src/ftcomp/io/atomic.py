"""Atomic file output: write a temporary file beside the target, then rename it into place.

A reader never sees a half-written file, and a failure leaves any earlier file untouched.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ftcomp.errors import ParameterError

__all__ = ["atomic_write_text", "check_writable"]


def check_writable(path: str | os.PathLike[str], *, overwrite: bool) -> Path:
    """Refuse to replace an existing file unless ``overwrite``; return the path.

    Raises:
        ParameterError: the file exists and ``overwrite`` is false, or it is a directory.
    """
    target = Path(path)
    if target.is_dir():
        raise ParameterError(f"{target}: is a directory, expected a file path")
    if target.exists() and not overwrite:
        raise ParameterError(f"{target}: exists; pass --force (overwrite=True) to replace it")
    return target


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; creates missing parent directories."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp_name, target)
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
