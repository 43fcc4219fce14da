"""The report layer: what ``hybridwsi reproduce`` writes (tables, figures, prose).

- :mod:`~hybridwsi.report.reproduce`: orchestration of the paper's Table 1, Fig. 1 and Fig. 2
  (BEM → Cummins → regression, stability, reconstruction → files);
- :mod:`~hybridwsi.report.validation`: the decay validation against Kramer et al. (2021)
  (Fig. 1 and its RMS / crossing-period table);
- :mod:`~hybridwsi.report.markdown`: the Markdown tables and notes of the report;
- :mod:`~hybridwsi.report.plots`: the figures (PNG; matplotlib is imported only here).

Nothing below this layer imports it (docs/DATA_MODEL.md).
"""
