"""File formats: every file ftcomp reads or writes, and how it is written.

- Sample files: :mod:`.sample_format` (the columns and every check, for CSV and Parquet),
  :mod:`.samples_csv` (the CSV reader and writer, and ``read_samples`` for either form),
  :mod:`.parquet`; :mod:`.chunks` cuts text files into chunks of whole lines.
- :mod:`.poses_csv`: pose lists. :mod:`.calibration_json`: the calibration file;
  :mod:`.dynamic_json`: the dynamic calibration file; :mod:`.truth_json`: the simulator's truth.
- Writing: :mod:`.atomic` (atomic writes, output checks), :mod:`.tables` (CSV tables),
  :mod:`.numtext` (float blocks as text, fast), :mod:`.timestamps` (time stamps as text).

The package imports none of its modules (``__all__`` names them), so a command loads only the
ones it uses (pyarrow only for the sample readers).
"""

__all__ = [
    "atomic",
    "calibration_json",
    "chunks",
    "dynamic_json",
    "numtext",
    "parquet",
    "poses_csv",
    "sample_format",
    "samples_csv",
    "tables",
    "timestamps",
    "truth_json",
]
