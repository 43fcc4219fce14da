"""The timing every ``benchmarks/bench_*.py`` shares: figures that hold still on a shared machine.

A benchmark states each figure as a :class:`Figure` (a call and the work it does, in the
benchmark's unit: a call, a case-step, a simulated second...) and hands a baseline and its
candidates to :func:`compare`, which

- times each figure by repeating its call until the sample lasts at least ``min_time``
  (0.2 s): a call of 3 ms timed once is at the mercy of one scheduler tick; the sample is
  the median time per call over the blocks of calls it is made of (:func:`sample`);
- takes ``repeat`` (at least 5) samples, **alternating** baseline and candidates within each
  round, so a load that comes and goes slows both sides alike;
- reports per figure the median time per unit and, per candidate, the median of the per-round
  ratios candidate / baseline with their spread (min-max), which is what to quote.

A *marginal* figure (:func:`marginal`) is the difference of a long and a short run divided by
the extra work: one-off set-up inside each call (history metadata, dispatch) cancels.

CPU time (``time.process_time``) is the better clock for single-threaded work on a shared
machine (it leaves out the time other jobs hold the core); wall time (the default) is the one
for anything multi-threaded or multi-process, whose CPU time adds up over threads.
"""

from __future__ import annotations

import gc
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

#: shortest sample [s] and fewest samples per figure (issue 31 item 6)
MIN_TIME = 0.2
REPEAT = 5
#: shortest timed block of calls within a sample [s] (clock overhead and resolution negligible)
BLOCK_TIME = 1e-3

Clock = Callable[[], float]


def sample(fn: Callable[[], object], min_time: float = MIN_TIME,
           clock: Clock = time.perf_counter) -> float:
    """Seconds per call of ``fn``, calling it until the sample lasts ``min_time`` [s].

    The calls are timed in blocks of at least :data:`BLOCK_TIME` (one call when a call is
    longer) and the sample is the median block's time per call: one call stalled by another
    job (a page-fault storm, a descheduled core) does not move it, as it would move the mean
    of three 70 ms calls. The garbage collector is run before and kept off during the sample
    (as ``timeit`` does): a collection of the previous figure's objects would otherwise land
    in a random sample.
    """
    gc.collect()
    enabled = gc.isenabled()
    gc.disable()
    try:
        block, total, per_call = 1, 0.0, []
        while total < min_time or not per_call:
            start = clock()
            for _ in range(block):
                fn()
            elapsed = clock() - start
            total += elapsed
            if elapsed < BLOCK_TIME and not per_call:
                block *= 2  # still calibrating: too short to time reliably
                continue
            per_call.append(elapsed / block)
        return float(np.median(per_call))
    finally:
        if enabled:
            gc.enable()


@dataclass(frozen=True)
class Figure:
    """One timed quantity: ``fn`` does ``units`` of work per call.

    With ``short`` (doing ``short_units``), the figure is marginal: (time of ``fn`` − time of
    ``short``) / (``units`` − ``short_units``), each timed as its own sample.
    """

    fn: Callable[[], object]
    units: float = 1.0
    short: Callable[[], object] | None = None
    short_units: float = 0.0

    def measure(self, min_time: float = MIN_TIME, clock: Clock = time.perf_counter) -> float:
        """One sample: seconds per unit of work."""
        t = sample(self.fn, min_time, clock)
        if self.short is None:
            return t / self.units
        return (t - sample(self.short, min_time, clock)) / (self.units - self.short_units)


def marginal(run: Callable[[int], object], n_long: int, n_short: int,
             per_step: float = 1.0) -> Figure:
    """The marginal cost per unit of ``run(n)`` (``n`` steps of ``per_step`` units each)."""
    return Figure(lambda: run(n_long), n_long * per_step, lambda: run(n_short),
                  n_short * per_step)


@dataclass(frozen=True)
class Timing:
    """The samples of one figure: seconds per unit and, for a candidate, the per-round ratios
    to the baseline (candidate / baseline: > 1 means slower)."""

    label: str
    times: np.ndarray
    ratios: np.ndarray | None = None

    @property
    def median(self) -> float:
        """Median seconds per unit."""
        return float(np.median(self.times))

    @property
    def ratio(self) -> float:
        """Median ratio candidate / baseline."""
        return float(np.median(self.ratios))

    def ratio_text(self, speedup: bool = False) -> str:
        """``"median 2.31x (spread 2.20-2.45, 5 samples)"``; ``speedup``: baseline / candidate."""
        r = 1.0 / self.ratios if speedup else self.ratios
        return (f"{float(np.median(r)):.3g}x (spread {r.min():.3g}-{r.max():.3g}, "
                f"{r.size} samples)")

    def time_text(self, scale: float = 1.0, unit: str = "s") -> str:
        """``"12.3 us (spread 11.9-13.0)"``: the median time per unit times ``scale``."""
        t = self.times * scale
        return f"{np.median(t):.4g} {unit} (spread {t.min():.4g}-{t.max():.4g})"


def compare(baseline: Figure | None, candidates: Mapping[str, Figure],
            repeat: int = REPEAT, min_time: float = MIN_TIME,
            clock: Clock = time.perf_counter, warmup: bool = True,
            baseline_label: str = "baseline") -> dict[str, Timing]:
    """Time ``baseline`` and ``candidates`` in alternating rounds.

    Parameters
    ----------
    baseline : Figure or None
        Timed first in every round; ``None``: the candidates alone (no ratios).
    candidates : mapping of label to Figure
        Timed after the baseline in every round, in this order.
    repeat : int
        Rounds (samples per figure); fewer than :data:`REPEAT` prints a note.
    min_time : float
        Shortest sample [s].
    clock : callable
        ``time.perf_counter`` (wall) or ``time.process_time`` (CPU of this process).
    warmup : bool
        Call every figure once, untimed, first (compilation, caches).

    Returns
    -------
    dict of label to Timing
        ``baseline_label`` first (if a baseline), then the candidates with their ratios.
    """
    if repeat < REPEAT:
        print(f"note: {repeat} samples per figure (fewer than {REPEAT}: spreads are rough)")
    figures = ({baseline_label: baseline} if baseline is not None else {}) | dict(candidates)
    if warmup:
        for fig in figures.values():
            fig.fn()
            if fig.short is not None:
                fig.short()
    times: dict[str, list[float]] = {label: [] for label in figures}
    for _ in range(repeat):
        for label, fig in figures.items():
            times[label].append(fig.measure(min_time, clock))
    base = np.array(times[baseline_label]) if baseline is not None else None
    out = {}
    for label, t in times.items():
        t = np.array(t)
        ratios = t / base if base is not None and label != baseline_label else None
        out[label] = Timing(label, t, ratios)
    return out


def conditions(clock: Clock = time.perf_counter, repeat: int = REPEAT,
               min_time: float = MIN_TIME) -> str:
    """One line saying how the figures were measured and the machine's load now."""
    name = "CPU time" if clock is time.process_time else "wall time"
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (f"timing: {name}, samples >= {min_time:g} s, {repeat} alternating rounds, medians "
            f"(spread = min-max); load average {load} on {os.cpu_count()} CPUs")
