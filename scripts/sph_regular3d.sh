#!/bin/sh
# The paper's sphere (D = 0.3 m, 7.056 kg) in regular waves T = 0.75 s, H = 0.05 m, heave free,
# in a narrow flume (half width 0.45 m, symmetry plane y = 0) with a Biésel piston and a damping
# zone. Depth 0.45 m: kh = 3.2, deep water for this wave, half the particles of the 0.9 m tank.
# The history shipped as src/hybridwsi/data/sph_regular_waves.nc (Table 1's SPH column) was
# made with the defaults below: dp = D/8, 32 127 particles, 11 211 steps, about 14 min on
# 2 cores (OpenMP) here. Resumable: re-run the same command after an interruption.
#   DP=0.03 sh scripts/sph_regular3d.sh      # finer: about 2.5x the cost
set -e
DP=${DP:-0.0375}
DEPTH=${DEPTH:-0.45}
TF=${TF:-6}
OUT=${OUT:-results/sph}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
mkdir -p "$OUT"
hybridwsi sph regular3d --dp "$DP" --depth "$DEPTH" --tf "$TF" \
    --out "$OUT/regular3d_dp${DP}_d${DEPTH}.nc" --resume --openmp --checkpoint-every 300
