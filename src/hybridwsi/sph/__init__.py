"""SPH numerical wave tank on PySPH (optional extra ``hybridwsi[sph]``).

- :mod:`~hybridwsi.sph.wavemaker`: Biésel piston transfer function, dispersion, paddle motion,
  zero-up-crossing analysis (pure NumPy; no PySPH needed).
- :mod:`~hybridwsi.sph.equations`: our PySPH equations and the wall/body integrator step.
- :mod:`~hybridwsi.sph.tank`: case builders (hydrostatic, dam_break, waves2d, decay2d,
  decay3d, regular3d).
- :mod:`~hybridwsi.sph.packing`: body-fitted packing of the fluid around a round body (the
  ``packing="packed"`` initial state; NumPy/SciPy).
- :mod:`~hybridwsi.sph.run`: ``run_case(case, out)`` -> TimeHistory, with checkpoints/resume.
- :mod:`~hybridwsi.sph.dam_break`, :mod:`~hybridwsi.sph.decay`: comparisons with Martin &
  Moyce (1952) and Kramer et al. (2021).

Only ``wavemaker``, ``packing``, ``dam_break`` and ``decay`` import without PySPH.
"""
