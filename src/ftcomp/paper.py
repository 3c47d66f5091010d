"""Huang et al. 2020: every published number and constant of the paper, in one place.

The numbers come from the shipped ``data/huang2020_published_results.json`` (Tables 3 and 4, the
identified parameters, the sensor's specification, the placement test's settings) and the
paper's real readings from ``data/huang2020_table1_2.csv`` (Tables 1 and 2). Nothing else in
ftcomp spells a published number: the simulated cell's defaults, the demo's comparisons and the
CLI's defaults all read them here.

This module imports only the standard library at load time (the CLI reads its defaults here).
It sits in the layer of calibration and compensation, above the file formats
(docs/architecture.md): :func:`paper_samples` reads the shipped readings with
:func:`ftcomp.io.samples_csv.read_samples` (imported when called).

Print where the shipped data files are: ``python -m ftcomp.paper``.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import TYPE_CHECKING, Any, Final

if TYPE_CHECKING:
    from ftcomp.samples import PoseList, Samples

__all__ = [
    "CENTER_OF_GRAVITY_M",
    "FORCE_BIAS_N",
    "PUBLISHED",
    "SENSING_END_WEIGHT_N",
    "SENSOR",
    "TABLE4_LOAD_WEIGHTS_N",
    "TILT_DEG",
    "TOOL_WEIGHT_N",
    "TORQUE_BIAS_Nm",
    "data_path",
    "paper_poses",
    "paper_samples",
]

_RESULTS_FILE: Final = "huang2020_published_results.json"
_READINGS_FILE: Final = "huang2020_table1_2.csv"


def _load_published() -> dict[str, Any]:
    text = resources.files("ftcomp.data").joinpath(_RESULTS_FILE).read_text("utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


#: Everything the paper publishes (the shipped JSON as a dict; treat it as read-only).
PUBLISHED: Final[dict[str, Any]] = _load_published()

#: Identified base tilt (U, V) [deg] (section 2.2.1): the simulated arm's default mounting.
TILT_DEG: Final[tuple[float, float]] = (
    float(PUBLISHED["base_tilt_deg"]["U"]),
    float(PUBLISHED["base_tilt_deg"]["V"]),
)
#: Identified tool weight G, sensing end plus gripper [N].
TOOL_WEIGHT_N: Final[float] = float(PUBLISHED["tool_weight_N"])
#: Weight of the sensor's sensing end alone [N] (the no-gripper calibration).
SENSING_END_WEIGHT_N: Final[float] = float(PUBLISHED["sensor_sensing_end_weight_N"])
#: Identified centre of gravity P of sensing end plus gripper, sensor frame [m].
CENTER_OF_GRAVITY_M: Final[tuple[float, float, float]] = tuple(  # type: ignore[assignment]
    float(v) for v in PUBLISHED["center_of_gravity_m"]
)
#: Identified sensor zero F0 [N] and M0 [N*m], sensor frame.
FORCE_BIAS_N: Final[tuple[float, float, float]] = tuple(  # type: ignore[assignment]
    float(v) for v in PUBLISHED["force_bias_N"]
)
TORQUE_BIAS_Nm: Final[tuple[float, float, float]] = tuple(  # type: ignore[assignment]
    float(v) for v in PUBLISHED["torque_bias_Nm"]
)
#: True weights of the six loads of Table 4 [N] (scale mass times 9.8 m/s^2).
TABLE4_LOAD_WEIGHTS_N: Final[tuple[float, ...]] = tuple(
    float(v) for v in PUBLISHED["table4_load_weight_N"]["true"]
)
#: The paper's sensor: ranges [N, N*m], overload [%], resolution, output rate [Hz].
SENSOR: Final[dict[str, float]] = {k: float(v) for k, v in PUBLISHED["sensor"].items()}


def data_path(name: str = _READINGS_FILE) -> str:
    """The installed path of a shipped data file (the readings CSV by default)."""
    resource = resources.files("ftcomp.data").joinpath(name)
    return str(resource)


def paper_samples() -> Samples:
    """The paper's real readings, Tables 1-2: nine poses, the mean of 500 readings at each."""
    from ftcomp.io.samples_csv import read_samples

    with resources.as_file(resources.files("ftcomp.data").joinpath(_READINGS_FILE)) as path:
        return read_samples(path)


def paper_poses() -> PoseList:
    """The nine poses of Table 1 (angles ``R = Rz(alpha) Ry(beta) Rx(gamma)``)."""
    from ftcomp.samples import PoseList

    samples = paper_samples()
    from scipy.spatial.transform import Rotation

    assert samples.pose is not None  # the shipped file has a pose column
    return PoseList(
        tuple(str(p) for p in samples.pose),
        Rotation.from_matrix(samples.R_base_sensor),
        "paper Table 1",
    )


if __name__ == "__main__":  # pragma: no cover
    print(data_path())
    print(data_path(_RESULTS_FILE))
