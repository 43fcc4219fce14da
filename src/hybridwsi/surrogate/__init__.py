"""Hybrid solver: force network (PyTorch), its linearisation and the rollout with the network
in the loop. Modules import torch lazily through :mod:`~hybridwsi.surrogate.network`.

- :mod:`~hybridwsi.surrogate.features` — window features of kinematics and wave elevation;
- :mod:`~hybridwsi.surrogate.network` — :class:`ForceNetwork` (fit/predict/save/load);
- :mod:`~hybridwsi.surrogate.linearise` — alpha_s, beta_s, gamma_s by autograd;
- :mod:`~hybridwsi.surrogate.rollout` — batched hybrid rollout (lagged/corrected/implicit)
  with the stability check before running;
- :mod:`~hybridwsi.surrogate.fast` — folded NumPy network and the compiled (Numba) loop of
  the lagged/corrected rollout;
- :mod:`~hybridwsi.surrogate.demo` — which partition may a network take over (issue 6);
- :mod:`~hybridwsi.surrogate.kramer` — the hybrid on the Kramer decay measurements, leave one
  drop out (its structured residual in :mod:`~hybridwsi.surrogate.structured`, its multi-step
  training in :mod:`~hybridwsi.surrogate.multistep`);
- :mod:`~hybridwsi.surrogate.fowt` — the OC3-Hywind multi-DOF diagnostic and 3-DOF hybrid.
"""
