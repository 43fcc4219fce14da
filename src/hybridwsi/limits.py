"""Plausible ranges of physical inputs: a value beyond them is a typo, refused with the range.

One place for the bounds the command line (``commands/_options``) and the library
(:mod:`hybridwsi.waves`) both check, so that ``--mass 1e300`` or a 1e300 m sea is one
``error:`` line naming the range rather than a run that ends in overflow or ``Re λ = inf``.
"""

from __future__ import annotations

#: masses [kg] of floating bodies: from a 1 g tank model to 10 million tonnes (15 times the
#: largest ship ever built, Seawise Giant, 657 000 t loaded)
MASS_RANGE = (1e-3, 1e10)
#: wave heights [m], significant or regular: the highest wave measured at sea is about 30 m
#: (significant-height records near 19 m)
MAX_WAVE_HEIGHT = 30.0
