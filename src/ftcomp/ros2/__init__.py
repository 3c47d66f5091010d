"""ROS 2 without installing ROS: bags in, ros2_control parameters out, MCAP logs, live topics.

- :mod:`.bag` reads ROS 2 (MCAP, sqlite3) and ROS 1 bags through rosbags; :mod:`.tf` looks up
  recorded ``/tf`` at any stamp; :mod:`.urdf` gives the sensor's pose from joint states and a
  URDF (pytransform3d's parser); :mod:`.importer` turns a bag into calibration samples
  (``ftcomp import-bag``) with the still segments of :mod:`ftcomp.calibration.still`.
- :mod:`.export` writes a calibration as ros2_control parameters (``ftcomp export ros2``).
- :mod:`.mcap_log` logs control loops as MCAP in the ROS 2 profile (``sim place --log``).
- :mod:`.rclpy_runtime` and :mod:`.live`: ``ros2://`` live topics through rclpy (a sourced ROS 2
  or the optional extra ``ftcomp[ros2]``).

Nothing is imported here, so ``import ftcomp.ros2`` needs none of the optional libraries.
"""

__all__: list[str] = []
