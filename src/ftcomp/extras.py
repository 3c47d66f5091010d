"""The optional dependencies and the extras that install them.

The lean install (``pip install -e .`` in a clone: ftcomp is installed from its repository, it
is not published on PyPI) gives calibration, compensation, file I/O and the hardware backends'
core. The simulated cell needs MuJoCo (extra ``sim``), plots need matplotlib (extra ``report``),
the paper's demo both (extra ``demo``), reading a URDF needs pytransform3d (extra ``urdf``; it
requires matplotlib itself). :func:`require_extra` says in one line which extra to
install when one is missing, as :func:`install_hint` writes it: a command that works from the
clone (``pip install 'ftcomp[sim]'`` would look for a distribution that is not published).
"""

from __future__ import annotations

import importlib

from ftcomp.errors import MissingExtraError

__all__ = ["EXTRAS", "install_hint", "require_extra"]

#: The modules each extra installs (``pip install -e '.[EXTRA]'`` in the clone).
EXTRAS: dict[str, tuple[str, ...]] = {
    "demo": ("mujoco", "matplotlib"),
    "report": ("matplotlib",),
    "sim": ("mujoco",),
    "urdf": ("pytransform3d",),
    "view": ("foxglove",),
}

#: How a message names each optional module.
_DISPLAY_NAME = {
    "foxglove": "foxglove-sdk",
    "matplotlib": "matplotlib",
    "mujoco": "MuJoCo",
    "pytransform3d": "pytransform3d",
}


def _importable(module: str) -> bool:
    try:
        importlib.import_module(module)
    except ImportError as exc:  # not installed, or installed without its compiled library
        if exc.name is not None and exc.name.partition(".")[0] != module:
            raise  # the module is there but one of *its* imports failed: not ours to explain
        return False
    return True


def install_hint(extra: str) -> str:
    """How to install ``extra``: ``pip install -e '.[sim]' (in the ftcomp clone)``."""
    return f"pip install -e '.[{extra}]' (in the ftcomp clone)"


def require_extra(extra: str, what: str) -> None:
    """Check that every module of ``extra`` (a key of :data:`EXTRAS`) imports, for ``what``.

    Raises:
        MissingExtraError: one is not installed; the message names the extra, e.g.
            ``ftcomp demo needs MuJoCo and matplotlib: pip install -e '.[demo]' (in the ftcomp
            clone)``.
    """
    modules = EXTRAS[extra]
    if not all(_importable(m) for m in modules):
        names = " and ".join(_DISPLAY_NAME[m] for m in modules)
        raise MissingExtraError(f"{what} needs {names}: {install_hint(extra)}")
