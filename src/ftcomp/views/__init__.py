"""Views of ftcomp's results: plots as PNG files (:mod:`.figures`, matplotlib from the extra
``report``, imported only when a plot is drawn) and self-contained HTML pages (:mod:`.html`).
"""

__all__: list[str] = []
