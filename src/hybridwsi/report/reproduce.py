"""Reproduce the paper: Table 1, Fig. 1 and Fig. 2 into a results folder (``hybridwsi reproduce``).

Pipeline (each stage's output is written to ``out/`` so a reader can check every number):

1. BEM coefficients of the paper's sphere (Capytaine; paper configuration, or a coarse mesh with
   ``quick``), cached by a hash of the inputs.
2. A Cummins run of the sphere in regular waves (T = 0.75 s, H = 0.05 m) → TimeHistory with
   every force component (``histories/bem_regular_waves.nc``).
3. Table 1: the regression of the three partitions of the paper, with uncertainty, condition
   number and identifiable combinations (``table1.json`` / ``table1.md``).
4. Fig. 2: reconstruction of the heave with each partition, their stability verdicts and errors,
   and the same with the identified α, β, γ moved into the ODE (``fig2_bem.png`` + NetCDF).
5. Fig. 1: decay validation against Kramer et al. (2021), RMS table next to the 11 published
   codes (``fig1_decay.png``, ``decay_validation.json``/``.md``).
6. ``report.md`` linking all of it (the prose: :mod:`hybridwsi.report.markdown`; figures:
   :mod:`hybridwsi.report.plots`; Fig. 1 scoring: :mod:`hybridwsi.report.validation`).

Every input (the SPH history file: readable, its variables, its length) is checked before the
first expensive step. The results are written as one set: built in a sibling folder
``.<out>.partial`` and swapped into place when complete, so ``out``'s previous content stays
until the new set is whole and a killed run never leaves a folder mixing two runs (the SPH
checkpoint of ``--recompute-sph`` is kept in the partial folder so the run resumes).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import bodies, cummins, waves
from hybridwsi._meta import version
from hybridwsi.cases import load_case
from hybridwsi.diagnostic.partition import select_partition, table_to_json
from hybridwsi.diagnostic.reconstruct import reconstruct
from hybridwsi.diagnostic.regression import regress
from hybridwsi.errors import InputError
from hybridwsi.forces.linear import known_from
from hybridwsi.history import to_netcdf
from hybridwsi.history import write_json as _write_json
from hybridwsi.history import write_text as _write_text
from hybridwsi.hydro import bem, coefficients
from hybridwsi.importers import read_history
from hybridwsi.report.kramer_hybrid import run_kramer_hybrid
from hybridwsi.report.markdown import (
    PARTITION_LABELS,
    dynamic_stiffness_note,
    outlook_markdown,
    report_markdown,
    steady_state_note,
    table1_markdown,
    wave_note,
)
from hybridwsi.report.validation import run_decay_validation
from hybridwsi.sph import tank
from hybridwsi.sph.run import run_case

SPH_HISTORY = "sph_regular_waves.nc"
#: the SPH run's resume checkpoint (hybridwsi.sph.run.run_case), kept across killed runs
SPH_CHECKPOINT = SPH_HISTORY + ".ckpt.npz"
#: wave periods an SPH history must span in Table 1's regression window (one to see a full
#: cycle of z, z', z'', a second so that the fit is not the cycle's own end effects)
MIN_SPH_PERIODS = 2.0
#: what a results folder holds (an existing --out with anything else is not replaced)
RESULT_NAMES = re.compile(
    r"(report\.md|summary\.json|table1(_steady_state)?\.(json|md)|fig[12]_[a-z]+\.(png|nc)"
    r"|fig2_metrics\.json|decay_validation\.(json|md)|selection\.json|hybrid_demo\.json"
    r"|histories|\.hybridwsi-results)")
MARKER = ".hybridwsi-results"


def _log(msg: str, progress: bool) -> None:
    if progress:
        print(f"[reproduce] {msg}", flush=True)


def _bem_coefficients(body, cfg: dict, progress: bool, water_depth: float | None = None):
    omega = np.geomspace(cfg["omega_min"], cfg["omega_max"], cfg["n_omega"])
    depth = cfg.get("water_depth", np.inf) if water_depth is None else water_depth
    return bem.compute(body, omega, water_depth=depth, n_panels=cfg["n_panels"],
                       progress=progress)


def _coefficient(coeffs: xr.Dataset, name: str) -> float | np.ndarray:
    """A (dof, dof) coefficient of the body (hydro.coefficients), a float for one DOF."""
    m = coefficients.matrix(coeffs, name)
    return float(m[0, 0]) if m.shape == (1, 1) else m


@dataclass
class Table1Case:
    """One row of Table 1 (one partition of one generator)."""

    label: str
    result: Any  # RegressionResult
    known: list = field(default_factory=list)

    def entry(self) -> dict[str, Any]:
        d = self.result.to_dict()
        keys = ("alpha", "beta", "gamma", "mean_force", "stderr", "ci95", "r2", "condition_number",
                "singular_values", "identifiable", "identifiable_combinations", "warnings",
                "dominant_omega")
        out = {"F_bb": self.label, **{k: d[k] for k in keys if k in d}}
        # an undetermined term (exact single-frequency data) has an infinite stderr, which
        # to_dict writes as None: keep it a number here (the JSON writer still writes null)
        for k in ("stderr", "condition_number"):
            if k in out:
                out[k] = _none_to_inf(out[k])
        return out


def _none_to_inf(value: Any) -> Any:
    if value is None:
        return np.inf
    if isinstance(value, dict):
        return {k: _none_to_inf(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_none_to_inf(v) for v in value]
    return value


def table1_partitions(coeffs: xr.Dataset, hist: xr.Dataset | None = None) -> dict[str, list]:
    """The paper's three partitions: C and A∞ from the history's matrices, else from the
    coefficients (:func:`hybridwsi.forces.linear.known_from`, the one route)."""
    hydrostatic, added_mass_inf = known_from(hist, coeffs, ["hydrostatic", "added_mass_inf"])
    return {"1": [], "2": [hydrostatic], "3": [hydrostatic, added_mass_inf]}


def regress_table1(hist: xr.Dataset, partitions: dict[str, list],
                   force_accuracy: float) -> dict[str, Table1Case]:
    """Regress F_bb of each partition on the reference motion (paper Eq. 5–7)."""
    return {
        k: Table1Case(PARTITION_LABELS[k], regress(hist, force="F_tot", known=known,
                                                   force_accuracy=force_accuracy), known)
        for k, known in partitions.items()
    }


def _solved(res: Any) -> Any:
    """A reconstruction that succeeded (its failure, data until here, stops the report)."""
    res.solution.raise_on_failure()
    return res


def figure2(hist: xr.Dataset, cases: dict[str, Table1Case], mass: float, out: Path,
            title: str, stem: str, motion_force: str | None = "F_rad_mem",
            bias_fraction: float = 1e-4, force_accuracy: float = 0.01) -> dict[str, Any]:
    """Reconstruct with each partition, and with motion-dependent terms moved into the ODE.

    Prescribing a force as a function of time removes its feedback on the motion
    (docs/THEORY.md §4a). Moving α z̈ + β ż + γ z identified on the *whole* F_bb back into the
    ODE is circular: on the reference F_bb ≡ (m + A_k) z̈ + B_k ż + C_k z (Newton), so it would
    cancel the inertia.
    What restores the feedback is to identify the motion-dependent *component* that F_bb still
    holds (``motion_force``, by default the radiation memory force of the Cummins history), move
    its α, β, γ into the ODE and prescribe only the rest of F_bb. When the α/γ split of that
    component is not identifiable (single-frequency motion), α is fixed to 0 so that the
    identifiable dynamic stiffness goes into γ: a free split along the null direction can put a
    negative stiffness into the ODE and make a stable partition blow up.

    On clean data every partition reconstructs the reference almost exactly; what tells them
    apart is how an error in the prescribed force propagates (docs/THEORY.md §4a). The figure
    therefore prescribes F_bb with a small constant bias, ``bias_fraction`` × max|F_tot| (a
    stand-in for the discretisation or measurement error of a high-fidelity force): with
    nothing known the error grows as δF t²/2m (drift), with C known it stays bounded (δF/C),
    with damping in the ODE it settles. Metrics are reported for clean and biased forces.
    """
    from hybridwsi.report import plots  # matplotlib: imported only when drawing

    ident = (regress(hist, force=motion_force, force_accuracy=force_accuracy)
             if motion_force and motion_force in hist else None)
    if ident is not None and not ident.identifiable:
        ident = regress(hist, force=motion_force, fix_alpha=0.0, force_accuracy=force_accuracy)
    bias = bias_fraction * float(np.abs(hist["F_tot"].values).max())
    biased = hist.assign(F_tot=hist["F_tot"] + bias)
    recs, moved, verdicts, metrics = {}, {}, {}, {}
    for k, case in cases.items():
        r = _solved(reconstruct(hist, force="F_tot", known=case.known, mass=mass))
        rb = _solved(reconstruct(biased, force="F_tot", known=case.known, mass=mass))
        recs[k], verdicts[k] = rb.history, r.stability.prescribed.verdict
        metrics[k] = {"prescribed": r.to_dict(), "prescribed_biased": rb.to_dict()}
        if ident is not None:
            rm = _solved(reconstruct(hist, force="F_tot", known=case.known, mass=mass,
                                     move_identified=ident))
            rmb = _solved(reconstruct(biased, force="F_tot", known=case.known, mass=mass,
                                      move_identified=ident))
            moved[k] = rmb.history
            metrics[k]["moved_identified"] = rm.to_dict()
            metrics[k]["moved_identified_biased"] = rmb.to_dict()
    metrics["force_bias_N"] = bias
    fig = plots.reconstruction_figure(hist, recs, verdicts, moved or None, title=title,
                                      bias=bias)
    plots.save(fig, out / f"{stem}.png")
    t = hist["time"].values

    def _z(rec: xr.Dataset) -> np.ndarray:
        return np.interp(t, rec["time"].values, rec["z"].values[:, 0])

    data = xr.Dataset(
        {f"z_case{k}": ("time", _z(r)) for k, r in recs.items()}
        | {f"z_case{k}_moved": ("time", _z(r)) for k, r in moved.items()}
        | {"z_ref": ("time", hist["z"].values[:, 0])},
        coords={"time": t},
        attrs={"moved_component": str(motion_force),
               "moved_alpha_beta_gamma": json.dumps(
                   None if ident is None else [ident.to_dict()[x] for x in ("alpha", "beta", "gamma")])},
    )
    to_netcdf(data, out / f"{stem}.nc")
    if ident is not None:
        metrics["moved_component"] = {"force": motion_force, **{
            x: ident.to_dict()[x] for x in ("alpha", "beta", "gamma", "condition_number")}}
    return metrics


def outlook(hist: xr.Dataset, coeffs: xr.Dataset, out: Path, *, quick: bool,
            progress: bool, force_accuracy: float = 0.01) -> str:
    """The paper's outlook: component selection and the hybrid (network-in-the-loop) demo.

    Writes ``selection.json`` (every partition of the candidate components ranked,
    docs/THEORY.md §5) and ``hybrid_demo.json`` (predicted vs observed stability of a network-in-the-loop rollout);
    returns the Markdown section of the report.
    """
    from hybridwsi.surrogate.demo import hybrid_demo

    _log("Outlook: component selection", progress)
    # quick: a 10 s window keeps the 24 reconstructions short; the ranking needs them
    sel = hist.sel(time=slice(None, 10.0)) if quick else hist
    table = select_partition(sel, coeffs=coeffs, dt=float(hist["time"][1] - hist["time"][0]),
                             force_accuracy=force_accuracy)
    _write_json(out / "selection.json", table_to_json(table))
    cols = [c for c in ("rank", "partition", "alpha", "beta", "gamma", "spectral_radius",
                        "added_mass_ratio", "recon_nrms", "feasible", "score") if c in table]
    head = table[cols].head(8)
    _log("Outlook: hybrid solver demo (network in the loop)", progress)
    demo_kw = ({"duration": 20.0, "n_train": 2, "n_test": 1, "long_periods": 100}
               if quick else {})
    demo = hybrid_demo(coeffs, **demo_kw)
    _write_json(out / "hybrid_demo.json", demo)
    return outlook_markdown(head, demo)


def sph_source(path: str | Path | None) -> Path | None:
    """The SPH history file of Table 1: ``path``, else the one shipped in ``hybridwsi/data``,
    else None (the column is "pending")."""
    if path is not None:
        return Path(path)
    shipped = Path(__file__).resolve().parent.parent / "data" / SPH_HISTORY
    return shipped if shipped.is_file() else None


def read_sph_history(src: Path, *, mass: float | None, period: float,
                     window_start: float) -> tuple[xr.Dataset, str]:
    """Read and check a user/shipped SPH history and say where it came from.

    Any file ``read_history`` understands (NetCDF, CSV, DualSPHysics FloatingInfo with
    ``mass`` [kg]); it must hold ``F_tot``, ``z``, ``zdot``, ``zddot`` and span at least
    ``MIN_SPH_PERIODS`` wave periods ``period`` [s] after ``window_start`` [s] (Table 1's
    regression window). Raises :class:`InputError` otherwise: called before any BEM run.
    """
    if not src.is_file():
        raise InputError(f"--sph-history: no such file {src}")
    hist = _needs_force(read_history(src, mass=mass), src)
    t = np.asarray(hist["time"].values, dtype=float)
    span = t[-1] - max(t[0], window_start)
    if span < MIN_SPH_PERIODS * period:
        raise InputError(
            f"{src}: the SPH history spans {max(span, 0.0):.3g} s after t = {window_start:g} s; "
            f"Table 1 needs at least {MIN_SPH_PERIODS:g} wave periods ({MIN_SPH_PERIODS * period:.3g} s)"
        )
    try:
        inputs = json.loads(hist.attrs.get("inputs", "{}"))
    except ValueError:
        inputs = {}
    shown = ", ".join(f"{k} = {inputs[k]}" for k in ("engine", "engine_version", "dp", "depth",
                                                    "n_particles", "tf") if k in inputs)
    return hist, (f"SPH column from {src.name} ({hist.attrs.get('source', '?')}"
                  f"{'; ' + shown if shown else ''}; every input in its `inputs` attribute)."
                  f"{wave_note(hist)}")


def sph_history(out: Path, *, recompute: bool = False, path: str | Path | None = None,
                dp: float | None = None, mass: float | None = None, openmp: bool = False,
                progress: bool = True) -> tuple[xr.Dataset | None, str]:
    """The SPH history of Table 1's SPH column and a note saying where it came from.

    ``recompute``: run ``hybridwsi sph regular3d`` now (resumable: an interrupted run continues
    from ``out/histories/sph_regular_waves.nc.ckpt.npz``); else ``path``: any history file
    ``read_history`` understands (:func:`read_sph_history`); else the history shipped in
    ``hybridwsi/data``; else none ("pending").
    """
    case = load_case("paper_sphere")
    if recompute:
        cfg = case["sph_regular_waves"]  # the shipped run's set-up
        sph_case = tank.build("regular3d", **{**cfg, "dp": dp or cfg["dp"]})
        target = out / "histories" / SPH_HISTORY
        hist = run_case(sph_case, target, resume=True, progress=progress, openmp=openmp)
        return _needs_force(hist, target), (
            f"SPH column from a run made now: `hybridwsi sph regular3d --dp {sph_case.dp:g}` "
            f"({sph_case.n_particles} particles), written to histories/{SPH_HISTORY}.")
    src = sph_source(path)
    if src is None:
        return None, ("SPH column: pending; no SPH history is shipped yet (run with "
                      "`--recompute-sph` or pass one with `--sph-history FILE`).")
    rw = case["regular_waves"]
    return read_sph_history(src, mass=mass, period=rw["period"], window_start=rw["window_start"])


def _needs_force(hist: xr.Dataset, src: Path) -> xr.Dataset:
    missing = [v for v in ("F_tot", "z", "zdot", "zddot") if v not in hist]
    if missing:
        raise InputError(f"{src}: the SPH history needs {', '.join(missing)} for Table 1")
    return hist


def _partial_dir(out: Path) -> Path:
    return out.parent / f".{out.name}.partial"


def check_out_folder(out: Path) -> None:
    """Refuse an ``--out`` that exists but is not a results folder (a file, or a folder with
    other content): the new set replaces the folder as a whole."""
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is not a folder")
    if out.is_dir() and not (out / MARKER).is_file():
        other = sorted(p.name for p in out.iterdir() if not RESULT_NAMES.fullmatch(p.name))
        if other:
            raise InputError(f"--out {out} holds files that are not reproduce results "
                             f"({', '.join(other[:3])}{', ...' if len(other) > 3 else ''}); "
                             "choose a new or empty folder")


def _prepare_partial(out: Path) -> Path:
    """A clean ``.<out>.partial`` folder to build the set in.

    What a killed run left there is removed except the SPH checkpoint (so ``--recompute-sph``
    resumes); the checkpoint of a completed run in ``out`` is carried over too. A results folder
    moved aside by a swap that was killed half-way is put back first.
    """
    for old in out.parent.glob(f".{out.name}.old.*"):
        if out.exists():
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(old, out)
    partial = _partial_dir(out)
    keep = partial / "histories" / SPH_CHECKPOINT
    if partial.is_dir():
        for p in partial.iterdir():
            if p.name != "histories":
                shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
        for p in (partial / "histories").glob("*"):
            if p != keep:
                shutil.rmtree(p) if p.is_dir() else p.unlink()
    (partial / "histories").mkdir(parents=True, exist_ok=True)
    done = out / "histories" / SPH_CHECKPOINT
    if done.is_file() and not keep.is_file():
        shutil.copy2(done, keep)
    (partial / MARKER).write_text("a hybridwsi reproduce results folder\n")
    return partial


def _swap_into_place(partial: Path, out: Path) -> None:
    """Replace ``out`` by the completed set in ``partial`` (renames only)."""
    old = out.parent / f".{out.name}.old.{os.getpid()}"
    if out.exists():
        os.replace(out, old)
    os.replace(partial, out)
    shutil.rmtree(old, ignore_errors=True)


def run(out: str | Path = "results", *, quick: bool = False, progress: bool = True,
        decay: bool = True, hybrid: bool = True, recompute_sph: bool = False,
        sph_path: str | Path | None = None, sph_dp: float | None = None,
        sph_openmp: bool = False) -> dict[str, Any]:
    """Run the whole reproduction and write the results folder. Returns the summary dict.

    ``recompute_sph``, ``sph_path``, ``sph_dp`` and ``sph_openmp`` choose the SPH column's
    history (:func:`sph_history`). Inputs are checked first; the folder is replaced as a whole
    when the new set is complete (module docstring).
    """
    out = Path(out).absolute()
    check_out_folder(out)
    case = load_case("paper_sphere")
    rw = case["regular_waves"]
    sph_pre = None
    if not recompute_sph:  # check the SPH history before any expensive step
        src = sph_source(sph_path)
        if src is not None:
            sph_pre = read_sph_history(src, mass=case["body"]["mass"], period=rw["period"],
                                       window_start=rw["window_start"])
    partial = _prepare_partial(out)
    try:
        summary = _build(partial, case, quick=quick, progress=progress, decay=decay,
                         hybrid=hybrid, recompute_sph=recompute_sph, sph_pre=sph_pre,
                         sph_dp=sph_dp, sph_openmp=sph_openmp)
    except BaseException:  # incl. Ctrl-C: out untouched; only an SPH checkpoint is worth keeping
        if not (partial / "histories" / SPH_CHECKPOINT).is_file():
            shutil.rmtree(partial, ignore_errors=True)
        raise
    _swap_into_place(partial, out)
    _log(f"done in {summary['wall_time_s']:.0f} s → {out}/report.md", progress)
    return summary


def _decay_section(out: Path, *, progress: bool) -> str:
    """Fig. 1: the Kramer sphere's BEM (the shipped paper configuration, quick or not) and the
    decay runs against the experiment, written into ``out``; returns the section's Markdown."""
    from hybridwsi.report import plots  # matplotlib: imported only when drawing

    kcase = load_case("kramer2021_decay")
    # the paper configuration's coefficients are shipped (found by their inputs, no solve), so
    # --quick reads them too: its coarse [bem_quick] mesh cost 15 s of BEM (and negative
    # damping above 34 rad/s) for decay RMS errors within 0.001 H0 of these (measured)
    kcfg = kcase["bem"]
    _log("Fig. 1: BEM of the Kramer sphere and decay runs", progress)
    kbody = bodies.FloatingSphere.kramer2021()
    kcoeffs = _bem_coefficients(kbody, kcfg, progress,
                                water_depth=kcase["experiment"]["water_depth"])
    val = run_decay_validation(kcoeffs, progress=progress)
    to_netcdf(val.curves, out / "fig1_decay.nc")
    plots.save(plots.decay_validation_figure(val.curves), out / "fig1_decay.png")
    _write_json(out / "decay_validation.json", val.to_json())
    decay_md = val.to_markdown()
    _write_text(out / "decay_validation.md", decay_md + "\n")
    return decay_md


def _fowt_section(out: Path, *, quick: bool, progress: bool) -> str:
    """Floating wind: OC3-Hywind (mooring, natural frequencies, decays, RAOs) and the OC4
    semi (also its 6x6 diagnostic), written into ``out``; returns their Markdown."""
    # the FOWT reports draw (matplotlib) and train networks (PyTorch): imported when run
    from hybridwsi.report.fowt import run_fowt
    from hybridwsi.report.fowt_semi import run_fowt_semi

    _log("OC3-Hywind: mooring, natural frequencies, decays, RAOs", progress)
    fowt_md = run_fowt(out, quick=quick, progress=progress)
    _log("OC4-DeepCwind semi: natural frequencies, decays, RAOs, 6x6 diagnostic", progress)
    return fowt_md + "\n" + run_fowt_semi(out, quick=quick, progress=progress)


def _build(out: Path, case: dict, *, quick: bool, progress: bool, decay: bool, hybrid: bool,
           recompute_sph: bool, sph_pre: tuple[xr.Dataset, str] | None, sph_dp: float | None,
           sph_openmp: bool) -> dict[str, Any]:
    """Write the whole results set into ``out`` (the partial folder)."""
    t0 = time.perf_counter()
    cfg = case["bem_quick" if quick else "bem"]
    b = case["body"]
    body = bodies.FloatingSphere.paper()
    _log(f"BEM: {cfg['n_panels']} panels, {cfg['n_omega']} frequencies "
         f"{'(quick)' if quick else '(paper configuration)'}", progress)
    coeffs = _bem_coefficients(body, cfg, progress)
    to_netcdf(coeffs, out / "histories" / "bem_coefficients_paper_sphere.nc")

    rw = case["regular_waves"]
    _log(f"Cummins: regular waves T = {rw['period']} s, H = {rw['height']} m, "
         f"{rw['duration']} s", progress)
    hist = cummins.simulate(
        coeffs, mass=b["mass"], duration=rw["duration"], dt=rw["dt"],
        wave=waves.Regular(period=rw["period"], height=rw["height"]), ramp=rw["ramp"],
    )
    to_netcdf(hist, out / "histories" / "bem_regular_waves.nc")
    window = hist.sel(time=slice(rw["window_start"], None))

    partitions = table1_partitions(coeffs, hist)
    acc = case["force_accuracy"]  # per generator (docs/THEORY.md §3b)
    ours = {"BEM": regress_table1(window, partitions, acc["BEM"])}
    if recompute_sph:
        sph, sph_note = sph_history(out, recompute=True, dp=sph_dp, mass=b["mass"],
                                    openmp=sph_openmp, progress=progress)
    else:
        sph, sph_note = sph_pre if sph_pre is not None else sph_history(out)
    if sph is not None:
        ours["SPH"] = regress_table1(sph.sel(time=slice(rw["window_start"], None)), partitions,
                                     acc["SPH"])
    steady = regress_table1(hist.sel(time=slice(rw["steady_state_start"], None)), partitions,
                            acc["BEM"])
    _write_json(out / "table1_steady_state.json",
                {"window_start_s": rw["steady_state_start"],
                 "BEM": {k: c.entry() for k, c in steady.items()}})
    table = {gen: {k: c.entry() for k, c in rows.items()} for gen, rows in ours.items()}
    table.setdefault("SPH", {"status": "pending"})
    _write_json(out / "table1.json", table)
    md = table1_markdown(ours, case["paper_table1"])
    note = dynamic_stiffness_note(ours["BEM"], rw["period"], case["paper_table1"])
    note += "\n\n" + steady_state_note(steady["3"], rw["period"], rw["steady_state_start"])
    _write_text(out / "table1.md", md + "\n\n" + note + "\n\n" + sph_note + "\n")

    _log("Fig. 2: reconstructions", progress)
    fig2 = {"BEM": figure2(window, ours["BEM"], b["mass"], out, "BEM / Cummins", "fig2_bem",
                           force_accuracy=acc["BEM"])}
    if "SPH" in ours:
        fig2["SPH"] = figure2(sph.sel(time=slice(rw["window_start"], None)), ours["SPH"],
                              b["mass"], out, "SPH", "fig2_sph", force_accuracy=acc["SPH"])
    _write_json(out / "fig2_metrics.json", fig2)

    decay_md = _decay_section(out, progress=progress) if decay else \
        "Decay validation skipped."
    kramer_md = ""
    if decay and hybrid:  # the hybrid on the measured decays (leave one drop out)
        _log("Kramer hybrid: leave one drop out", progress)
        kramer_md = run_kramer_hybrid(out, quick=quick, progress=progress)
    # floating wind: OC3-Hywind and the OC4 semi
    fowt_md = _fowt_section(out, quick=quick, progress=progress) if decay else ""

    outlook_md = (outlook(hist, coeffs, out, quick=quick, progress=progress,
                          force_accuracy=acc["BEM"]) if hybrid else "")

    summary = {
        "hybridwsi_version": version(),
        "quick": quick,
        "bem": {"n_panels": cfg["n_panels"], "n_omega": cfg["n_omega"],
                "added_mass_inf": _coefficient(coeffs, "added_mass_inf"),
                "C": _coefficient(coeffs, "hydrostatic_stiffness")},
        "wall_time_s": time.perf_counter() - t0,
    }
    _write_json(out / "summary.json", summary)
    _write_text(out / "report.md", report_markdown(summary, md, note, sph_note, fig2, decay_md,
                                                   "SPH" in ours, decay)
                + "\n" + kramer_md + "\n" + fowt_md + "\n" + outlook_md)
    return summary


