"""One hybrid pipeline: diagnose the partition → train → predict stability → couple → roll out.

Every hybrid in hybridwsi (``hybridwsi hybrid``, the sphere demo of :mod:`.demo`, the model
folders of :mod:`.certified` that ``simulate --network`` runs) goes through
:class:`HybridPipeline`::

    pipe = HybridPipeline("auto", mode="corrected").fit(histories, coeffs)
    res = pipe.rollout(cases)          # RolloutResult (hybridwsi.surrogate.rollout)

1. **Partition** (:func:`resolve_partition`): the known components are candidates of the
   component selection (:mod:`hybridwsi.diagnostic.partition`: ``hydrostatic``,
   ``added_mass_inf``, ``radiation_memory``, ``linear_damping``, ``excitation``) named
   explicitly (``"hydrostatic+added_mass_inf+excitation"``), by a preset of :data:`PRESETS`,
   or ``"auto"``: the diagnostic's rank-1 partition on the first history
   (:func:`~hybridwsi.diagnostic.partition.select_partition`, without its reconstructions,
   which cost minutes on long records and do not change the order of partitions whose
   residual stability differs).
2. **Train** a :class:`~hybridwsi.surrogate.network.ForceNetwork` on the residual
   ``F_bb = F_tot − Σ known`` (paper Eq. 3).
3. **Predict stability** (:func:`predict_stability`): the network's linearisation in the very
   step map of the rollout (:func:`~hybridwsi.surrogate.rollout.check_stability`, a
   :class:`~hybridwsi.diagnostic.stability.StabilityReport` built by
   :func:`~hybridwsi.diagnostic.stability.assess` from a
   :class:`~hybridwsi.diagnostic.stability.CoupledStep`), for ``corrected`` with the number
   of corrections :func:`~hybridwsi.surrogate.coupled.corrections_for` gives. A partition
   predicted unstable raises :class:`~hybridwsi.surrogate.rollout.UnstablePartitionError`
   unless ``allow_unstable`` (then a RuntimeWarning).
4. **Roll out** (:meth:`HybridPipeline.rollout`): the known components in the ODE with the
   network force in the loop (:func:`~hybridwsi.surrogate.rollout.rollout`).

Learned attributes end in ``_`` (scikit-learn style); :meth:`HybridPipeline.from_network`
builds a fitted pipeline from a trained network (a model folder) without training.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.diagnostic import stability
from hybridwsi.diagnostic.partition import CANDIDATES, build_candidates, select_partition
from hybridwsi.errors import InputError
from hybridwsi.forces import KnownComponent, as_matrix
from hybridwsi.forces.linear import mass_from
from hybridwsi.history import KINEMATICS, check_compatible, nrms_per_dof, time_step
from hybridwsi.surrogate.coupled import MODES, corrections_for
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.rollout import RolloutResult, UnstablePartitionError, check_stability
from hybridwsi.surrogate.rollout import rollout as run_rollout

__all__ = ["PRESETS", "HybridPipeline", "partition_candidates", "predict_stability",
           "required_variables", "resolve_partition"]

#: named partitions: (known candidates, network inputs). ``recommended``: hydrostatics, A∞
#: and excitation known, the network takes the radiation memory from a ż window (α_s = 0 by
#: construction); ``added_mass_to_network``: the network carries A∞ too (from ż, z̈), the
#: loosely coupled scheme's added-mass instability when A∞ > m (docs/THEORY.md §4c)
PRESETS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "recommended": (("hydrostatic", "added_mass_inf", "excitation"), ("zdot",)),
    "added_mass_to_network": (("hydrostatic", "excitation"), ("zdot", "zddot")),
}
#: what each candidate's force needs from a history
CANDIDATE_NEEDS = {"hydrostatic": ("z",), "added_mass_inf": ("zddot",),
                   "radiation_memory": ("zdot",), "linear_damping": ("zdot",),
                   "quadratic_damping": ("zdot",), "excitation": ("F_exc",)}


def partition_candidates(name: str) -> tuple[str, ...]:
    """The candidate names of a partition given as a preset or ``a+b+c`` (``none``: nothing
    known)."""
    if name in PRESETS:
        return PRESETS[name][0]
    if name in ("none", "(none)"):
        return ()
    names = tuple(n.strip() for n in name.split("+") if n.strip())
    bad = [n for n in names if n not in CANDIDATES]
    if bad or not names:
        raise InputError(f"unknown partition {name!r}: give auto, "
                         f"{', '.join(PRESETS)}, or known components joined by '+' among "
                         f"{', '.join(CANDIDATES)}")
    return names


def default_inputs(candidates: Sequence[str], hist: xr.Dataset) -> tuple[str, ...]:
    """Network inputs of a partition without preset inputs: z and ż (the restoring and
    damping forces left over), z̈ only when A∞ is not known (otherwise the network would
    share the inertia with the ODE: α_s ≠ 0), η when the history has it (the drag and any
    excitation left over feel the wave)."""
    inputs = ["z", "zdot"] + ([] if "added_mass_inf" in candidates else ["zddot"])
    return tuple(inputs + (["eta"] if "eta" in hist else []))


def resolve_partition(name: str, hist: xr.Dataset, coeffs: xr.Dataset | None, *,
                      mass: np.ndarray, dt: float) -> tuple[str, tuple[str, ...], Any]:
    """``(name, candidates, diagnosis)``: ``auto`` runs the diagnostic on ``hist`` and takes
    its rank-1 partition (``diagnosis``: its row as a dict); any other name is
    :func:`partition_candidates` (``diagnosis`` None)."""
    if name != "auto":
        return name, partition_candidates(name), None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = select_partition(hist, coeffs, dt=dt, mass=mass, reconstruct_each=False)
    row = table.iloc[0].to_dict()
    return str(row["partition"]), tuple(row["known"]), row


def required_variables(candidates: Sequence[str], inputs: Sequence[str],
                       force: str = "F_tot") -> list[str]:
    """The history variables a partition needs: kinematics, its total force, what its known
    components read and the network's inputs."""
    need = [*KINEMATICS, force]
    for c in candidates:
        need += CANDIDATE_NEEDS.get(c, ())
    need += list(inputs)
    return list(dict.fromkeys(need))


def check_variables(histories: Sequence[xr.Dataset], need: Sequence[str], what: str,
                    names: Sequence[str] | None = None) -> None:
    """One InputError naming the first history that lacks a variable of ``need``."""
    for i, h in enumerate(histories):
        missing = [v for v in need if v not in h]
        if missing:
            label = names[i] if names else f"history {i}"
            raise InputError(f"{label} has no {', '.join(missing)}, which {what} needs")


def predict_stability(net: ForceNetwork, references: Sequence[xr.Dataset], *,
                      mass: Any, known: Sequence[KnownComponent], mode: str,
                      corrections: int | None = None, dt: float | None = None,
                      stride: int = 5) -> tuple[stability.StabilityReport, int]:
    """The rollout's predicted stability and its number of corrections.

    ``corrected`` without ``corrections``: the fewest even number that cuts the added-mass
    error to 1 % (:func:`corrections_for` of the network's added-mass ratio), and the
    prediction is made again for it. Other modes: 1.
    """
    kw = {"mass": mass, "known": known, "mode": mode, "dt": dt, "stride": stride}
    pred = check_stability(net, references, **kw)
    n_corr = 1
    if mode == "corrected":
        n_corr = corrections or corrections_for(pred.added_mass_ratio)
        if n_corr != 1:
            pred = check_stability(net, references, corrections=n_corr, **kw)
    return pred, int(n_corr)


class HybridPipeline:
    """Partition, network, stability prediction and coupling of one hybrid model.

    Parameters
    ----------
    partition : str
        ``"auto"`` (the diagnostic's recommendation), a preset of :data:`PRESETS`, or
        candidate names joined by ``+`` (:func:`partition_candidates`).
    inputs : sequence of str, optional
        Network inputs (default: the preset's, else :func:`default_inputs`).
    known : sequence of KnownComponent, optional
        The partition's known components as built already (then ``partition`` only names
        it; no diagnosis, no candidates built from the histories).
    known_extra : sequence of KnownComponent
        Components known besides the partition's (a case's linearised mooring and linear
        damping: the network then learns only their nonlinear remainder).
    mode : {"lagged", "corrected", "implicit"}
        Coupling of the network in the time step (:mod:`hybridwsi.surrogate.rollout`).
    corrections : int, optional
        Corrections per step of ``corrected`` (default :func:`corrections_for`).
    network : mapping, optional
        :class:`ForceNetwork` settings besides ``inputs`` (hidden, window, stride, lead, ...).
    allow_unstable : bool
        Accept a partition predicted unstable (warn instead of raising).
    force : str
        Total force variable [N] of the histories.
    progress : bool
        Show the training progress bar.
    """

    def __init__(self, partition: str = "auto", *, inputs: Sequence[str] | None = None,
                 known: Sequence[KnownComponent] | None = None,
                 known_extra: Sequence[KnownComponent] = (), mode: str = "corrected", corrections: int | None = None,
                 network: Mapping[str, Any] | None = None, allow_unstable: bool = False,
                 force: str = "F_tot", progress: bool = False) -> None:
        if mode not in MODES:
            raise InputError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        self.partition = partition
        self.inputs = None if inputs is None else tuple(inputs)
        self.known = None if known is None else list(known)
        self.known_extra = list(known_extra)
        self.mode = mode
        self.corrections = corrections
        self.network = dict(network or {})
        self.allow_unstable = allow_unstable
        self.force = force
        self.progress = progress

    # ------------------------------------------------------------------------- training
    def fit(self, histories: Sequence[xr.Dataset], coeffs: xr.Dataset | None = None, *,
            mass: Any = None, names: Sequence[str] | None = None) -> HybridPipeline:
        """Diagnose (``auto``), check the data, train, predict stability.

        Parameters
        ----------
        histories : list of TimeHistory
            Training histories: one body, one time step, one set of DOFs.
        coeffs : Dataset, optional
            BEM coefficients of the known components (else the histories' matrices).
        mass : float or array, optional
            Rigid-body mass [kg, kg m²] (default: the histories', else the coefficients').
        names : sequence of str, optional
            How error messages name the histories (their files).

        Raises
        ------
        InputError
            Mixed histories, missing variables, no mass (before any training).
        UnstablePartitionError
            The partition is predicted unstable and ``allow_unstable`` is off.
        """
        hs = list(histories)
        if not hs:
            raise InputError("no training histories")
        check_compatible(hs)
        m = mass if mass is not None else mass_from(hs[0], coeffs)
        if m is None:
            raise InputError("neither the histories nor the coefficients carry a 'mass'")
        self.mass_ = as_matrix(m, hs[0].sizes["dof"], "mass")
        self.dt_ = time_step(hs[0])
        self.dofs_ = tuple(str(d) for d in hs[0]["dof"].values)
        check_variables(hs, [*KINEMATICS, self.force], "the hybrid pipeline", names)
        self._partition(hs, coeffs, names)
        self.network_ = ForceNetwork(**{**self.network, "inputs": self.inputs_}).fit(
            hs, "F_bb", known=self.known_, force=self.force, progress=self.progress)
        return self._predict(hs)

    def _partition(self, hs: list[xr.Dataset], coeffs: xr.Dataset | None,
                   names: Sequence[str] | None) -> None:
        """``partition_``, ``candidates_``, ``diagnosis_``, ``inputs_`` and ``known_``, the
        histories checked to hold what they need."""
        if self.known is not None:
            self.partition_, self.candidates_, self.diagnosis_ = self.partition, (), None
        else:
            self.partition_, self.candidates_, self.diagnosis_ = resolve_partition(
                self.partition, hs[0], coeffs, mass=self.mass_, dt=self.dt_)
        inputs = self.inputs or (PRESETS[self.partition_][1] if self.partition_ in PRESETS
                                 else default_inputs(self.candidates_, hs[0]))
        self.inputs_ = tuple(inputs)
        check_variables(hs, required_variables(self.candidates_, self.inputs_, self.force),
                        f"partition {self.partition_!r} (network inputs "
                        f"{', '.join(self.inputs_)})", names)
        self.known_ = (list(self.known) if self.known is not None else
                       list(build_candidates(hs[0], coeffs, self.candidates_).values())
                       ) + self.known_extra

    def _predict(self, references: Sequence[xr.Dataset]) -> HybridPipeline:
        """``stability_`` and ``corrections_``; refuse (or warn on) a predicted-unstable
        partition."""
        self.stability_, self.corrections_ = predict_stability(
            self.network_, list(references), mass=self.mass_, known=self.known_,
            mode=self.mode, corrections=self.corrections, dt=self.dt_)
        pred = self.stability_
        if not pred.stable:
            msg = (f"hybrid {self.mode} rollout of partition {self.partition_!r} predicted "
                   f"unstable: spectral radius {pred.spectral_radius:.4f} > 1, "
                   f"|alpha_s|/(m+A_k) = {pred.added_mass_ratio:.3f}")
            if not self.allow_unstable:
                raise UnstablePartitionError(msg)
            warnings.warn("UNSTABLE PARTITION: " + msg, RuntimeWarning, stacklevel=3)
        return self

    @classmethod
    def from_network(cls, network: ForceNetwork, known: Sequence[KnownComponent], *,
                     mass: Any, dt: float, mode: str = "corrected", corrections: int = 1,
                     partition: str = "", candidates: Sequence[str] = (),
                     stability_report: stability.StabilityReport | None = None
                     ) -> HybridPipeline:
        """A fitted pipeline from a trained network (a model folder): no training, no
        diagnosis; ``stability_report`` the certificate's prediction when known."""
        network._check_fitted()
        pipe = cls(partition, inputs=network.inputs, mode=mode, corrections=corrections,
                   network=network.get_params(), allow_unstable=True)
        pipe.network_, pipe.known_ = network, list(known)
        pipe.mass_ = as_matrix(mass, network.n_dof_, "mass")
        pipe.dt_, pipe.corrections_ = float(dt), int(corrections)
        pipe.partition_, pipe.candidates_, pipe.diagnosis_ = partition, tuple(candidates), None
        pipe.inputs_ = tuple(network.inputs)
        pipe.stability_ = stability_report
        return pipe

    # ------------------------------------------------------------------------- running
    def rollout(self, cases: xr.Dataset | Sequence[xr.Dataset], **kw: Any) -> RolloutResult:
        """The hybrid rollout of ``cases`` (their time grid, ``F_exc``/``eta``, first
        window): :func:`hybridwsi.surrogate.rollout.rollout` with this pipeline's network,
        known components, mass, coupling and corrections; no second stability check (made by
        :meth:`fit`). ``kw``: the rollout's other options (``n_steps``, ``compiled``,
        ``progress``...)."""
        if not hasattr(self, "network_"):
            raise InputError("this HybridPipeline is not fitted; call fit() or from_network()")
        with warnings.catch_warnings():
            if self.allow_unstable:  # warned once by fit(); the rollout would warn again
                warnings.simplefilter("ignore", RuntimeWarning)
            return run_rollout(self.network_, cases, mass=self.mass_, known=self.known_,
                               mode=self.mode, corrections=self.corrections_, check=False,
                               force=True, **kw)

    def score(self, histories: Sequence[xr.Dataset]) -> list[float]:
        """Held-out R² of the network's force on each history."""
        return [self.network_.score(h, "F_bb", known=self.known_, force=self.force)
                for h in histories]
