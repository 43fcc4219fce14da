#!/usr/bin/env python
"""Compare an SPH decay history (hybridwsi sph decay3d/decay2d) with Kramer et al. (2021).

    python scripts/sph_compare_kramer.py results/sph/decay3d_dp0.03.nc
"""

import json
import sys

from hybridwsi.history import read_netcdf
from hybridwsi.sph.decay import compare_decay

hist = read_netcdf(sys.argv[1])
z0 = float(hist["z"].values[0, 0])
print(json.dumps(compare_decay(hist, z0), indent=1))
