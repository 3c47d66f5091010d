"""Views of ftcomp's results: plots as PNG files (:mod:`.figures`, matplotlib from the extra
``report``, imported only when a plot is drawn), self-contained HTML pages (:mod:`.html`), a
calibration's page (:mod:`.calibration_report`, ``calibrate --report``), and the live views of a
session (:mod:`.live`: ``--log FILE.mcap`` and ``--view HOST:PORT``, the latter a Foxglove
WebSocket server, :mod:`.foxglove_view`, extra ``view``).
"""

__all__: list[str] = []
