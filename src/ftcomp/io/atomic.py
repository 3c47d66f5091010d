"""The output-file policy of every command, in one place.

- **Check before working.** :func:`check_writable` (a file) and :func:`prepare_output_dir` (a
  folder) run before any work: a path that cannot be written (its parent is a file, no
  permission, a pseudo-filesystem), an existing output without ``overwrite`` (``--force``), or an
  output that is one of the command's own inputs is one clear error, and nothing is computed.
- **Never half-written.** :func:`atomic_output` writes a temporary file beside the target and
  renames it into place: a reader never sees a partial file, and a failure or a kill leaves any
  earlier file untouched. Temporaries a killed run left behind (``.NAME.*.tmp``) are removed the
  next time the same target is written.
- **Modes like any other file.** A new file gets ``0o666`` less the umask (not ``mkstemp``'s
  0600); a replaced file keeps its mode.
- **An output never replaces an input**, even with ``--force``.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from ftcomp.errors import ParameterError

__all__ = ["atomic_output", "atomic_write_text", "check_writable", "prepare_output_dir"]

PathLike = str | os.PathLike[str]


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _writable_folder(folder: Path, what: Path) -> None:
    """Raise unless files can be created in ``folder`` (or in its nearest existing ancestor)."""
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise ParameterError(f"{what}: cannot be written: {probe} is a file, not a folder")
    if not folder.exists() and not os.access(probe, os.W_OK | os.X_OK):
        raise ParameterError(f"{what}: cannot be written: no permission to create {folder}")
    # The only sure test: create a file there, or in the nearest folder that exists when the
    # folder is still to be made (catches read-only and pseudo filesystems such as /proc, where
    # even root's os.access says yes and mkdir then fails).
    try:
        fd, name = tempfile.mkstemp(prefix=".ftcomp-probe-", dir=probe)
    except OSError as exc:
        raise ParameterError(f"{what}: cannot be written ({exc.strerror})") from None
    os.close(fd)
    Path(name).unlink(missing_ok=True)


def check_writable(path: PathLike, *, overwrite: bool, inputs: Iterable[PathLike] = ()) -> Path:
    """Check an output file can be written and may be; return the path.

    Args:
        path: the output file.
        overwrite: whether an existing file may be replaced (``--force``).
        inputs: the command's input files: the output may never be one of them.

    Raises:
        ParameterError: the output is an input, is a directory, exists without ``overwrite``,
            or cannot be written.
    """
    target = Path(path)
    for source in inputs:
        if _same_file(target, Path(source)) or target.resolve() == Path(source).resolve():
            raise ParameterError(
                f"{target}: is also an input of this command; write the output elsewhere"
            )
    if target.is_dir():
        raise ParameterError(f"{target}: is a directory, expected a file path")
    if target.exists() and not overwrite:
        raise ParameterError(
            f"{target}: exists; pass overwrite=True to replace it", field="overwrite"
        )
    if target.exists() and not stat.S_ISREG(target.stat().st_mode):
        raise ParameterError(f"{target}: is not a regular file; choose another output")
    _writable_folder(target.parent, target)
    return target


def prepare_output_dir(
    path: PathLike, *, overwrite: bool, inputs: Iterable[PathLike] = (), create: bool = True
) -> Path:
    """Check (and create) an output folder; a non-empty one needs ``overwrite``.

    Args:
        path: the folder.
        overwrite: whether a folder holding files may be written into (``--force``).
        inputs: the command's input files: the folder may not hold one of them.
        create: make the folder now; False only checks, for a command that has more input to
            check before it may leave anything behind (it makes the folder when it writes).

    Raises:
        ParameterError: the path is a file, holds files without ``overwrite``, holds one of the
            command's inputs, or cannot be written.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"{out}: exists and is not a folder")
    for source in inputs:
        if Path(source).resolve().is_relative_to(out.resolve()) and overwrite:
            raise ParameterError(f"{out}: holds {source}, an input of this command; choose another")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise ParameterError(
            f"{out}: exists and is not empty; pass overwrite=True to write into it (files of "
            "the same name are replaced)",
            field="overwrite",
        )
    _writable_folder(out, out)
    if create:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ParameterError(f"{out}: cannot be created ({exc.strerror})") from None
    return out


def _final_mode(target: Path) -> int:
    """An existing file's mode, else 0o666 less the process's umask."""
    try:
        return stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _remove_leftovers(target: Path) -> None:
    """Temporaries of ``target`` that a killed run left behind."""
    for leftover in target.parent.glob(f".{target.name}.*.tmp"):
        with contextlib.suppress(OSError):
            leftover.unlink()


@contextlib.contextmanager
def atomic_output(path: PathLike) -> Iterator[Path]:
    """Write ``path`` atomically: yields a temporary path beside it to write (in any way, e.g.
    a streaming CSV or Parquet writer), renamed into place when the block ends without error.

    Creates missing parent folders. On any exception (also Ctrl-C) the temporary file is removed
    and the target is untouched.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    _remove_leftovers(target)
    mode = _final_mode(target)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        with tmp.open("rb+") as handle:  # on disk before it replaces anything
            os.fsync(handle.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_text(path: PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`atomic_output`)."""
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="")
