#!/bin/sh
# The paper's sphere in regular waves (T = 0.75 s, H = 0.05 m), heave free, narrow flume with a
# piston (Biésel stroke) and a damping zone, half domain (symmetry plane y = 0).
# 10+ hours on 2 cores at dp = 0.03 m. Resumable.
set -e
DP=${DP:-0.03}
OUT=${OUT:-results/sph}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
mkdir -p "$OUT"
hybridwsi sph regular3d --dp "$DP" --out "$OUT/regular3d_dp$DP.nc" --resume --openmp \
    --checkpoint-every 600
