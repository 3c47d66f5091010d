"""Files: sample and pose CSVs, the calibration JSON, time series, atomic writes."""
