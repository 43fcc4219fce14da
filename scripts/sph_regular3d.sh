#!/bin/sh
# The paper's sphere (D = 0.3 m, 7.056 kg) in regular waves T = 0.75 s, H = 0.05 m, heave free,
# in a narrow flume (half width 0.45 m, mirror plane y = 0) with a Biésel piston and a damping
# zone, from the body-fitted packed start, without artificial viscosity between the fluid and the
# sphere (ALPHA_BODY=0, as the validated decay runs; the walls and the paddle keep it). Depth 0.45 m: kh = 3.2, deep water for this wave,
# half the particles of the 0.9 m tank. The history shipped as
# src/hybridwsi/data/sph_regular_waves.nc (Table 1's SPH column) was made with the defaults
# below: dp = D/12, 70 008 particles, 25 226 steps, 88 min on 2 cores (docs/SPH_RUNS.md).
# GAIN is the paddle-stroke factor calibrated in the empty flume at this spacing so that the
# wave reaching the sphere has the target height:
#   OMP_NUM_THREADS=1 python scripts/sph_wave_calibration.py --dim 2 --dp 0.025 --iterations 2
# Resumable: re-run the same command after an interruption.
set -e
DP=${DP:-0.025}
DEPTH=${DEPTH:-0.45}
TF=${TF:-9}
GAIN=${GAIN:-1.30}
ALPHA_BODY=${ALPHA_BODY:-0}
OUT=${OUT:-results/sph}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
mkdir -p "$OUT"
hybridwsi sph regular3d --dp "$DP" --depth "$DEPTH" --tf "$TF" --gain "$GAIN" --packing packed \
    --alpha-body "$ALPHA_BODY" \
    --out "$OUT/regular3d_dp${DP}_d${DEPTH}.nc" --resume --openmp --checkpoint-every 300
