"""Loopback stand-ins for real devices, each in its own process on its own 127.0.0.x address.

- :mod:`standins.fake_netft`: an ATI Net F/T (HTTP ``netftapi2.xml`` + RDT over UDP).
- :mod:`standins.fake_ur`: a UR controller's RTDE output side (port 30004).

Both serve one :class:`standins.scenario.Scenario`: a known tool model carried through known
poses on a timeline shared through the host's monotonic clock, so tests check numbers.
"""
