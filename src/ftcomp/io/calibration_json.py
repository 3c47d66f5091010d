"""The calibration file: JSON, format ``ftcomp.calibration/1``, written atomically.

Keys (SI units, sensor frame unless stated): ``format``, ``method``, ``tool_weight_N``,
``tool_mass_kg``, ``center_of_gravity_m`` [3], ``force_bias_N`` [3], ``torque_bias_Nm`` [3],
``base_tilt_deg`` {``U``, ``V``}, ``gravity_in_base_N`` [3] (base frame), ``std_errors`` (the same
keys), ``residual_rms`` {``force_N``, ``torque_Nm``}, ``relative_error_percent`` {``per_pose``
[[6]...], ``mean`` [6]}, ``poses``, and diagnostics (``condition_number``, ``pose_ids``,
``per_pose_residuals``, ``leave_one_out``, ``warnings``). Unmeasurable values (a relative error
where the reading is zero) are ``null``. Optional, when identified: ``bias_drift`` (model,
``t_ref_s``, ``t_range_s`` (the validity window: outside it the bias is held at the window's
nearer end, never extrapolated), then for ``linear``/``quadratic`` the coefficients per power of
seconds with standard errors, for ``stochastic`` the Matérn 3/2 process: ``time_constant_s``,
``scale`` [6], ``white_noise`` [6], ``knots_t_s`` [P], ``weights`` [P][6], ``knot_std`` [P][6],
``end_std`` [6]; for ``temperature``, instead of times: ``T_ref_C``, ``T_range_C`` (the validity
window, held outside it as a time range is), ``slopes_per_C`` [6] and ``std_errors`` [6]),
``sensor_map`` (``delta`` [6][3]: force rows dimensionless, torque rows in
metres; ``std_errors``; ``log_evidence_gain``; ``supported``; ``applied``: compensation folds
``delta`` in only when true) and
``mount`` (``axes``, ``angles_deg``, ``std_errors_deg``); files without them load as before.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.calibration_record import (
    DRIFT_ORDERS,
    BiasDrift,
    Calibration,
    MountRotation,
    SensorMap,
    StandardErrors,
    StochasticBiasDrift,
    TemperatureBiasDrift,
    mount_matrix,
)
from ftcomp.errors import CalibrationFileError, ParameterError
from ftcomp.io.atomic import atomic_write_text
from ftcomp.model import GravityModel

__all__ = [
    "FORMAT",
    "PLAUSIBLE_LIMITS",
    "calibration_to_dict",
    "check_plausible",
    "load_calibration",
    "model_from_dict",
    "model_to_dict",
    "read_json_object",
    "save_calibration",
]

FORMAT = "ftcomp.calibration/1"
_VECTOR_KEYS = ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm", "gravity_in_base_N")
_REQUIRED = ("method", "tool_weight_N", *_VECTOR_KEYS[:3], "base_tilt_deg")


def _json_array(arr: NDArray[np.float64]) -> Any:
    """Nested lists with NaN/inf as None (JSON has no NaN)."""
    return [_json_array(a) if np.ndim(a) else (float(a) if math.isfinite(a) else None) for a in arr]


def model_to_dict(model: GravityModel) -> dict[str, Any]:
    """The physical parameters under the calibration-file keys (also the simulator's truth)."""
    return {
        "tool_weight_N": model.weight_N,
        "tool_mass_kg": model.mass_kg,
        "center_of_gravity_m": model.center_of_gravity_m.tolist(),
        "force_bias_N": model.force_bias_N.tolist(),
        "torque_bias_Nm": model.torque_bias_Nm.tolist(),
        "base_tilt_deg": {
            "U": math.degrees(model.tilt_U_rad),
            "V": math.degrees(model.tilt_V_rad),
        },
        "gravity_in_base_N": model.gravity_base_N.tolist(),
    }


def _std_errors_to_dict(se: StandardErrors, model: GravityModel) -> dict[str, Any]:
    return {
        "tool_weight_N": se.weight_N,
        "tool_mass_kg": se.weight_N * model.mass_kg / model.weight_N if model.weight_N else 0.0,
        "center_of_gravity_m": se.center_of_gravity_m.tolist(),
        "force_bias_N": se.force_bias_N.tolist(),
        "torque_bias_Nm": se.torque_bias_Nm.tolist(),
        "base_tilt_deg": {"U": math.degrees(se.tilt_U_rad), "V": math.degrees(se.tilt_V_rad)},
        "gravity_in_base_N": se.gravity_base_N.tolist(),
    }


def calibration_to_dict(calibration: Calibration) -> dict[str, Any]:
    """Everything in a calibration file, as JSON-ready data."""
    force_rms, torque_rms = calibration.residual_rms
    loo_force, loo_torque = calibration.loo_rms
    return {
        "format": FORMAT,
        "method": calibration.method,
        **model_to_dict(calibration.model),
        "std_errors": _std_errors_to_dict(calibration.std_errors, calibration.model),
        "residual_rms": {"force_N": force_rms, "torque_Nm": torque_rms},
        "relative_error_percent": {
            "columns": ["fx", "fy", "fz", "tx", "ty", "tz"],
            "per_pose": _json_array(calibration.relative_error_percent),
            "mean": _json_array(calibration.relative_error_mean_percent),
        },
        "poses": len(calibration.pose_ids),
        "pose_ids": list(calibration.pose_ids),
        "readings_per_pose": calibration.readings_per_pose.astype(int).tolist(),
        "pose_quaternions_xyzw": _json_array(
            Rotation.from_matrix(calibration.R_base_sensor).as_quat(canonical=True)
            if len(calibration.pose_ids)
            else np.zeros((0, 4))
        ),
        "pose_mean_wrench": _json_array(calibration.wrench_mean),
        "condition_number": calibration.condition_number,
        "per_pose_residuals": _json_array(calibration.residuals),
        "leave_one_out": {
            "per_pose": _json_array(calibration.loo_error),
            "rms": {
                "force_N": loo_force if math.isfinite(loo_force) else None,
                "torque_Nm": loo_torque if math.isfinite(loo_torque) else None,
            },
        },
        "warnings": list(calibration.warnings),
        **(
            {"bias_drift": _drift_to_dict(calibration.bias_drift)} if calibration.bias_drift else {}
        ),
        **({"mount": _mount_to_dict(calibration.mount)} if calibration.mount else {}),
        **({"sensor_map": _map_to_dict(calibration.sensor_map)} if calibration.sensor_map else {}),
    }


def _map_to_dict(sensor_map: SensorMap) -> dict[str, object]:
    return {
        "model": "linear",
        "delta": sensor_map.delta.tolist(),
        "std_errors": _json_array(sensor_map.std_errors),
        "log_evidence_gain": sensor_map.log_evidence_gain,
        "supported": sensor_map.supported,
        "applied": sensor_map.applied,
    }


def _sensor_map(data: Any, source: str) -> SensorMap | None:
    """The optional ``sensor_map`` entry (absent or null: the physical model)."""
    if data is None:
        return None
    delta = _optional_array(data.get("delta") if isinstance(data, dict) else None, (6, 3))
    gain = data.get("log_evidence_gain") if isinstance(data, dict) else None
    if not np.all(np.isfinite(delta)) or not isinstance(gain, (int, float)):
        raise CalibrationFileError(
            f"{source}: 'sensor_map' needs delta [6][3] finite and log_evidence_gain"
        )
    applied = data.get("applied", True)
    return SensorMap(
        delta,
        _optional_array(data.get("std_errors"), (6, 3)),
        float(gain),
        applied=applied is True,
    )


def _drift_to_dict(
    drift: BiasDrift | StochasticBiasDrift | TemperatureBiasDrift,
) -> dict[str, object]:
    if isinstance(drift, TemperatureBiasDrift):
        return {
            "model": drift.name,
            "T_ref_C": drift.T_ref_C,
            "T_range_C": [drift.T_min_C, drift.T_max_C],
            "outside_range": "held at the nearer end (never extrapolated)",
            "columns": ["fx", "fy", "fz", "tx", "ty", "tz"],
            "slopes_per_C": drift.slopes.tolist(),
            "std_errors": [v if math.isfinite(v) else None for v in drift.std_errors.tolist()],
        }
    head: dict[str, object] = {
        "model": drift.name,
        "t_ref_s": drift.t_ref_s,
        "t_range_s": [drift.t_min_s, drift.t_max_s],
        "outside_range": "held at the nearer end (never extrapolated)",
        "columns": ["fx", "fy", "fz", "tx", "ty", "tz"],
    }
    if isinstance(drift, StochasticBiasDrift):
        return {
            **head,
            "time_constant_s": drift.time_constant_s,
            "scale": drift.scale.tolist(),
            "white_noise": drift.white_noise.tolist(),
            "knots_t_s": drift.t_knots_s.tolist(),
            "weights": drift.weights.tolist(),
            "knot_std": _json_array(drift.knot_std),
            "end_std": [v if math.isfinite(v) else None for v in drift.end_std.tolist()],
        }
    return {
        **head,
        "coefficients_per_s_power": drift.coefficients.tolist(),
        "std_errors": [[v if math.isfinite(v) else None for v in r] for r in drift.std_errors],
    }


def _mount_to_dict(mount: MountRotation) -> dict[str, object]:
    """Degrees at the edge."""
    return {
        "axes": mount.axes,
        "angles_deg": np.degrees(mount.angles_rad).tolist(),
        "std_errors_deg": [
            math.degrees(v) if math.isfinite(v) else None for v in mount.std_errors_rad
        ],
    }


#: Largest magnitudes a calibration may hold: far beyond any F/T sensor and tool (the largest
#: six-axis sensors measure about 1e5 N and 1e4 N*m), so anything beyond is a corrupt file or a
#: failed fit, not a tool. [N], [m], [N], [N*m].
PLAUSIBLE_LIMITS: dict[str, float] = {
    "tool_weight_N": 1e5,
    "center_of_gravity_m": 10.0,
    "force_bias_N": 1e5,
    "torque_bias_Nm": 1e4,
}
#: Deepest JSON nesting read (a calibration file nests 3 levels).
_MAX_DEPTH = 32


def check_plausible(model: GravityModel, source: str) -> None:
    """Raise unless every parameter is within :data:`PLAUSIBLE_LIMITS` (naming the key)."""
    values = {
        "tool_weight_N": np.array([model.weight_N]),
        "center_of_gravity_m": model.center_of_gravity_m,
        "force_bias_N": model.force_bias_N,
        "torque_bias_Nm": model.torque_bias_Nm,
    }
    for key, limit in PLAUSIBLE_LIMITS.items():
        worst = float(np.max(np.abs(values[key])))
        if not worst <= limit:
            raise CalibrationFileError(
                f"{source}: {key!r} = {worst:.4g} is beyond any plausible tool or sensor "
                f"(limit {limit:g}); the file is corrupt or the fit failed"
            )


def save_calibration(path: str | os.PathLike[str], calibration: Calibration) -> None:
    """Write a calibration file atomically (a temporary file, then rename).

    Raises:
        CalibrationFileError: a parameter beyond :data:`PLAUSIBLE_LIMITS` (nothing is written).
    """
    check_plausible(calibration.model, str(path))
    text = json.dumps(_finite_or_null(calibration_to_dict(calibration)), indent=2, allow_nan=False)
    atomic_write_text(path, text + "\n")


def _finite_or_null(value: Any) -> Any:
    """JSON-ready: a diagnostic nobody measured (NaN, e.g. a calibration loaded from a file with
    only the parameters) becomes ``null``; the parameters are finite (checked)."""
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite_or_null(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _number(data: dict[str, Any], key: str, source: str) -> float:
    value = data.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CalibrationFileError(f"{source}: {key!r} must be a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:  # an integer too large for a float
        raise CalibrationFileError(
            f"{source}: {key!r} is too large ({len(str(value))} digits)"
        ) from None
    if not math.isfinite(number):
        raise CalibrationFileError(f"{source}: {key!r} is not finite ({value})")
    return number


def _depth(value: Any, limit: int) -> int:
    """Nesting depth of parsed JSON, counted up to ``limit + 1``."""
    todo, depth = [(value, 1)], 0
    while todo:
        item, level = todo.pop()
        depth = max(depth, level)
        if depth > limit:
            return depth
        if isinstance(item, dict):
            todo.extend((v, level + 1) for v in item.values())
        elif isinstance(item, list):
            todo.extend((v, level + 1) for v in item)
    return depth


def _vector(data: dict[str, Any], key: str, source: str) -> NDArray[np.float64]:
    value = data.get(key)
    if not isinstance(value, list) or len(value) != 3:
        raise CalibrationFileError(f"{source}: {key!r} must be a list of 3 numbers, got {value!r}")
    return np.array([_number({key: v}, key, source) for v in value])


def model_from_dict(data: dict[str, Any], source: str = "<dict>") -> GravityModel:
    """Read the physical parameters back from calibration-file keys (checked)."""
    for key in _REQUIRED:
        if key not in data:
            raise CalibrationFileError(f"{source}: missing key {key!r}")
    tilt = data["base_tilt_deg"]
    if not isinstance(tilt, dict):
        raise CalibrationFileError(f"{source}: 'base_tilt_deg' must be an object {{U, V}}")
    U = _number(tilt, "U", f"{source}: base_tilt_deg")
    V = _number(tilt, "V", f"{source}: base_tilt_deg")
    for name, value in (("U", U), ("V", V)):
        if not abs(value) < 90.0:
            raise CalibrationFileError(
                f"{source}: base_tilt_deg.{name} = {value:g} deg; a base tilt must be within "
                "+-90 deg (and is a fraction of a degree on a level floor)"
            )
    weight = _number(data, "tool_weight_N", source)
    if weight < 0.0:
        raise CalibrationFileError(f"{source}: 'tool_weight_N' must be >= 0, got {weight}")
    return GravityModel(
        weight,
        _vector(data, "center_of_gravity_m", source),
        _vector(data, "force_bias_N", source),
        _vector(data, "torque_bias_Nm", source),
        tilt_U_rad=math.radians(U),
        tilt_V_rad=math.radians(V),
    )


def _optional_array(data: Any, shape: tuple[int, ...]) -> NDArray[np.float64]:
    try:
        arr = np.array(data, dtype=float)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an int beyond float range
        return np.full(shape, np.nan)
    return arr if arr.shape == shape else np.full(shape, np.nan)


def _finite_float(value: Any) -> float:
    """A diagnostic number, or NaN when absent, not a number or beyond float range."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return math.nan
    try:
        return float(value)
    except OverflowError:
        return math.nan


def _object(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def _list(value: Any) -> list[Any]:
    return value if isinstance(value, list) else []


def _pose_rotations(data: Any, n: int) -> NDArray[np.float64]:
    quat = _optional_array(data, (n, 4))
    if n == 0 or not np.all(np.isfinite(quat)) or np.any(np.linalg.norm(quat, axis=1) == 0):
        return np.full((n, 3, 3), np.nan)
    return np.asarray(Rotation.from_quat(quat).as_matrix(), dtype=float).reshape(n, 3, 3)


def _not_a_calibration(data: dict[str, Any]) -> str:
    """What a JSON object without this format looks like, and what ftcomp reads."""
    fmt = data.get("format")
    keys = [str(k) for k in data][:8]
    shown = ", ".join(repr(k) for k in keys) + (", ..." if len(data) > len(keys) else "")
    found = (
        f"its format is {fmt!r}"
        if fmt is not None
        else f"a JSON object with no 'format' key (keys: {shown or 'none'})"
    )
    return (
        f"not an ftcomp calibration file: {found}; ftcomp reads calibration files with "
        f'"format": "{FORMAT}" and the tool\'s parameters (docs/files.md), as ftcomp '
        "calibrate writes them"
    )


def read_json_object(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A JSON file's top-level object (checked: readable, valid, not too deep, an object).

    Raises:
        CalibrationFileError: unreadable, not JSON, nested too deeply, not an object.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CalibrationFileError(f"{source}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationFileError(f"{source}: cannot read ({exc})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CalibrationFileError(
            f"{source}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})"
        ) from None
    except RecursionError:
        raise CalibrationFileError(
            f"{source}: JSON nested too deeply to be a calibration"
        ) from None
    except ValueError as exc:  # an integer too long to parse
        raise CalibrationFileError(f"{source}: not valid JSON ({exc})") from None
    if _depth(data, _MAX_DEPTH) > _MAX_DEPTH:
        raise CalibrationFileError(f"{source}: JSON nested too deeply to be a calibration")
    if not isinstance(data, dict):
        raise CalibrationFileError(f"{source}: expected a JSON object")
    return data


def load_calibration(path: str | os.PathLike[str]) -> Calibration:
    """Read and check a calibration file.

    The physical parameters must be present and finite; the diagnostics are read where present
    (NaN where absent), so a hand-written file with just the parameters also loads.

    Raises:
        CalibrationFileError: unreadable, not JSON, unknown format, missing keys, NaN.
    """
    source = str(path)
    data = read_json_object(path)
    if data.get("format") != FORMAT:
        raise CalibrationFileError(f"{source}: {_not_a_calibration(data)}")
    if data.get("method") not in ("paper", "joint"):
        raise CalibrationFileError(
            f"{source}: 'method' must be 'paper' or 'joint', got {data.get('method')!r}"
        )
    model = model_from_dict(data, source)
    check_plausible(model, source)
    se_data = _object(data.get("std_errors"))
    se_tilt = _object(se_data.get("base_tilt_deg"))

    std_errors = StandardErrors(
        weight_N=_finite_float(se_data.get("tool_weight_N")),
        center_of_gravity_m=_optional_array(se_data.get("center_of_gravity_m"), (3,)),
        force_bias_N=_optional_array(se_data.get("force_bias_N"), (3,)),
        torque_bias_Nm=_optional_array(se_data.get("torque_bias_Nm"), (3,)),
        tilt_U_rad=math.radians(_finite_float(se_tilt.get("U"))),
        tilt_V_rad=math.radians(_finite_float(se_tilt.get("V"))),
        gravity_base_N=_optional_array(se_data.get("gravity_in_base_N"), (3,)),
    )
    ids = _list(data.get("pose_ids"))
    n = len(ids)
    relative = data.get("relative_error_percent")
    per_pose = relative.get("per_pose") if isinstance(relative, dict) else None
    loo = data.get("leave_one_out")
    cond = data.get("condition_number")
    return Calibration(
        model=model,
        method=data["method"],
        std_errors=std_errors,
        pose_ids=tuple(str(i) for i in ids),
        R_base_sensor=_pose_rotations(data.get("pose_quaternions_xyzw"), n),
        wrench_mean=_optional_array(data.get("pose_mean_wrench"), (n, 6)),
        readings_per_pose=_optional_array(data.get("readings_per_pose"), (n,)),
        residuals=_optional_array(data.get("per_pose_residuals"), (n, 6)),
        relative_error_percent=_optional_array(per_pose, (n, 6)),
        loo_error=_optional_array(loo.get("per_pose") if isinstance(loo, dict) else None, (n, 6)),
        condition_number=_finite_float(cond),
        warnings=tuple(w for w in _list(data.get("warnings")) if isinstance(w, str)),
        bias_drift=_drift(data.get("bias_drift"), source),
        mount=_mount(data.get("mount"), source),
        sensor_map=_sensor_map(data.get("sensor_map"), source),
    )


def _stochastic(data: dict[str, Any], source: str) -> StochasticBiasDrift:
    """A ``bias_drift`` entry of model ``stochastic``."""
    where = f"{source}: bias_drift"
    knots = data.get("knots_t_s")
    n = len(knots) if isinstance(knots, list) else 0
    arrays = {
        "knots_t_s": _optional_array(knots, (n,)),
        "weights": _optional_array(data.get("weights"), (n, 6)),
        "scale": _optional_array(data.get("scale"), (6,)),
        "white_noise": _optional_array(data.get("white_noise"), (6,)),
    }
    span = data.get("t_range_s")
    if n < 2 or not isinstance(span, list) or len(span) != 2:
        raise CalibrationFileError(
            f"{where}: a stochastic drift needs knots_t_s [2 or more] and t_range_s [2]"
        )
    for name, value in arrays.items():
        if not np.all(np.isfinite(value)):
            raise CalibrationFileError(f"{where}.{name} must be finite numbers of the right shape")
    try:
        return StochasticBiasDrift(
            t_knots_s=arrays["knots_t_s"],
            weights=arrays["weights"],
            scale=arrays["scale"],
            time_constant_s=_number(data, "time_constant_s", where),
            white_noise=arrays["white_noise"],
            knot_std=_optional_array(data.get("knot_std"), (n, 6)),
            end_std=_optional_array(data.get("end_std"), (6,)),
            t_min_s=_number({"t": span[0]}, "t", f"{where}.t_range_s"),
            t_max_s=_number({"t": span[1]}, "t", f"{where}.t_range_s"),
        )
    except ParameterError as exc:
        raise CalibrationFileError(f"{where}: {exc}") from None


def _temperature(data: dict[str, Any], source: str) -> TemperatureBiasDrift:
    """A ``bias_drift`` entry of model ``temperature``."""
    where = f"{source}: bias_drift"
    span = data.get("T_range_C")
    slopes = _optional_array(data.get("slopes_per_C"), (6,))
    if not isinstance(span, list) or len(span) != 2 or not np.all(np.isfinite(slopes)):
        raise CalibrationFileError(
            f"{where}: a temperature drift needs T_range_C [2] and slopes_per_C [6], finite"
        )
    try:
        return TemperatureBiasDrift(
            T_ref_C=_number(data, "T_ref_C", where),
            T_min_C=_number({"T": span[0]}, "T", f"{where}.T_range_C"),
            T_max_C=_number({"T": span[1]}, "T", f"{where}.T_range_C"),
            slopes=slopes,
            std_errors=_optional_array(data.get("std_errors"), (6,)),
        )
    except ParameterError as exc:
        raise CalibrationFileError(f"{where}: {exc}") from None


def _drift(data: Any, source: str) -> BiasDrift | StochasticBiasDrift | TemperatureBiasDrift | None:
    """The optional ``bias_drift`` entry (absent or null: a constant bias)."""
    if data is None:
        return None
    if isinstance(data, dict) and data.get("model") == "stochastic":
        return _stochastic(data, source)
    if isinstance(data, dict) and data.get("model") == "temperature":
        return _temperature(data, source)
    order = DRIFT_ORDERS.get(str(data.get("model"))) if isinstance(data, dict) else None
    if not isinstance(data, dict) or not order:
        raise CalibrationFileError(
            f"{source}: 'bias_drift.model' must be linear, quadratic, stochastic or temperature"
        )
    span = data.get("t_range_s")
    coefficients = _optional_array(data.get("coefficients_per_s_power"), (order, 6))
    if not isinstance(span, list) or len(span) != 2 or not np.all(np.isfinite(coefficients)):
        raise CalibrationFileError(
            f"{source}: 'bias_drift' needs t_range_s [2] and coefficients_per_s_power "
            f"[{order}][6], finite"
        )
    t_min = _number({"t": span[0]}, "t", f"{source}: bias_drift.t_range_s")
    t_max = _number({"t": span[1]}, "t", f"{source}: bias_drift.t_range_s")
    t_ref = _number(data, "t_ref_s", f"{source}: bias_drift")
    return BiasDrift(
        order,
        t_ref,
        t_min,
        t_max,
        coefficients,
        _optional_array(data.get("std_errors"), (order, 6)),
    )


def _mount(data: Any, source: str) -> MountRotation | None:
    """The optional ``mount`` entry (absent or null: the orientations are the sensor's)."""
    if data is None:
        return None
    if not isinstance(data, dict) or data.get("axes") not in ("yaw", "full"):
        raise CalibrationFileError(f"{source}: 'mount' must be {{axes: yaw|full, angles_deg}}")
    axes = data["axes"]
    n = 1 if axes == "yaw" else 3
    angles = data.get("angles_deg")
    try:
        values = np.array(angles, dtype=float)
    except (TypeError, ValueError):
        values = np.array([])
    if values.shape != (n,) or not np.all(np.isfinite(values)):
        raise CalibrationFileError(
            f"{source}: 'mount.angles_deg' must be {n} finite number(s), got {angles!r}"
        )
    se = data.get("std_errors_deg")
    se_values = np.array(
        [float(v) if isinstance(v, (int, float)) else math.nan for v in se]
        if isinstance(se, list) and len(se) == n
        else [math.nan] * n
    )
    phi = np.radians(values)
    return MountRotation(axes, mount_matrix(phi, axes), phi, np.radians(se_values))
