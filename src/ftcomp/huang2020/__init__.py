"""Huang et al. 2020 reproduced on the simulated cell: an application on the ftcomp library.

``ftcomp demo`` runs it (:func:`.demo.run_demo`). The experiments return typed records
(:mod:`.gravity`, :mod:`.beyond`, :mod:`.beyond_inertial`, :mod:`.drift_sim`); the demo's
sections (:mod:`.demo_calibration`, :mod:`.demo_gravity`, :mod:`.demo_placement`,
:mod:`.demo_beyond`) turn them into files, figures (:mod:`.figures`) and report sections, each
with its metrics record; :mod:`.comparisons` sets the paper's results beside ours and
:mod:`.terminal` prints them. The library never imports this package. It needs the extra
``demo`` (MuJoCo and matplotlib); nothing is imported here, so a submodule can be imported on
its own.
"""

__all__: list[str] = []
