"""The truth file: a simulated cell's true parameters under the calibration-file keys, as JSON.

``ftcomp sim collect --truth`` and the demo's ``truth.json`` write it. It is not a calibration
file: its own format tag ``ftcomp.truth/1`` makes
:func:`ftcomp.io.calibration_json.load_calibration` refuse it by name, and its ``method``
``truth`` says nothing was identified. Its parameters are the keys of
:func:`ftcomp.io.calibration_json.model_to_dict` (``tool_weight_N``, ``center_of_gravity_m``,
``force_bias_N``, ``torque_bias_Nm``, ``base_tilt_deg``, ``gravity_in_base_N``), so
:func:`ftcomp.io.calibration_json.model_from_dict` reads them back as a
:class:`~ftcomp.model.GravityModel`; a writer may add keys of its own (e.g. ``simulation``).
"""

from __future__ import annotations

import os
from typing import Any, Final

from ftcomp.errors import CalibrationFileError
from ftcomp.io.calibration_json import FORMAT, model_from_dict, model_to_dict, read_json_object
from ftcomp.model import GravityModel

__all__ = ["TRUTH_FORMAT", "TRUTH_HEADER", "load_truth", "truth_document"]

#: The truth file's format tag.
TRUTH_FORMAT: Final = "ftcomp.truth/1"

#: What a truth file is: its own format tag, so ``load_calibration`` refuses it by name, and
#: ``method`` saying nothing was identified, so ``model_from_dict`` reads its parameters.
TRUTH_HEADER: Final[dict[str, str]] = {
    "format": TRUTH_FORMAT,
    "method": "truth",
    "description": "The simulated cell's true parameters (what it was built with), under the "
    "calibration-file keys; not a calibration file: read it with "
    "ftcomp.io.calibration_json.model_from_dict",
}


def truth_document(truth: GravityModel) -> dict[str, Any]:
    """The true parameters as a truth file's JSON-ready content (:data:`TRUTH_HEADER` and the
    calibration-file keys of :func:`~ftcomp.io.calibration_json.model_to_dict`)."""
    return {**TRUTH_HEADER, **model_to_dict(truth)}


def load_truth(path: str | os.PathLike[str]) -> GravityModel:
    """The true parameters of a truth file (``ftcomp.truth/1``, :mod:`ftcomp.io.truth_json`:
    a simulator's or the twin's), to score a calibration against.

    Raises:
        CalibrationFileError: unreadable, not JSON, not a truth file, missing keys, NaN.
    """
    source = str(path)
    data = read_json_object(path)
    if data.get("format") != TRUTH_FORMAT:
        fmt = data.get("format")
        what = "a calibration, not a truth" if fmt == FORMAT else f"format {fmt!r}"
        raise CalibrationFileError(
            f'{source}: {what} file; a truth file has "format": "{TRUTH_FORMAT}" (what '
            "the simulator and the twin write with their truth option)"
        )
    return model_from_dict(data, source)
