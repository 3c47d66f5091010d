"""Gravity compensation at run time (:mod:`.compensator`) and weighing a grasped load
(:mod:`.load`).
"""
