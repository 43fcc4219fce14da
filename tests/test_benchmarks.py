"""The benchmarks share one timing harness (issue 31 item 6): ``benchmarks/timing.py``."""

from __future__ import annotations

import ast
import sys
import time
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))

import timing  # noqa: E402


def _loops_that_read_a_clock(tree: ast.AST) -> list[int]:
    """Line numbers of for/while loops that call a clock (an own timing loop)."""
    clocks = {"perf_counter", "process_time", "time", "monotonic", "repeat", "timeit"}
    lines = []
    for loop in ast.walk(tree):
        if isinstance(loop, (ast.For, ast.While)):
            for node in ast.walk(loop):
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                        and node.func.attr in clocks
                        and isinstance(node.func.value, ast.Name)
                        and node.func.value.id in ("time", "timeit")):
                    lines.append(loop.lineno)
    return lines


@pytest.mark.parametrize("path", sorted(BENCH.glob("bench_*.py")), ids=lambda p: p.name)
def test_every_benchmark_times_through_the_harness(path):
    text = path.read_text()
    assert "from timing import" in text, f"{path.name} does not use benchmarks/timing.py"
    assert "import timeit" not in text
    assert not _loops_that_read_a_clock(ast.parse(text)), f"{path.name}: own timing loop"


def _busy(seconds: float) -> None:
    """Work for ``seconds`` of CPU time (the tests time CPU: wall time and sleeps stretch by
    tens of ms on a loaded machine)."""
    start = time.process_time()
    while time.process_time() - start < seconds:
        pass


def test_sample_lasts_the_minimum_and_reports_the_median_call():
    calls = []

    def fn():  # every fifth call stalls: the median call does not see it
        calls.append(1)
        _busy(0.012 if len(calls) % 5 == 0 else 0.002)
    start = time.process_time()
    per_call = timing.sample(fn, min_time=0.1, clock=time.process_time)
    assert time.process_time() - start >= 0.1
    assert 0.002 <= per_call < 0.006, per_call


def test_compare_alternates_and_gives_per_round_ratios():
    order = []
    base = timing.Figure(lambda: (order.append("b"), _busy(0.002)), units=1)
    cand = timing.Figure(lambda: (order.append("c"), _busy(0.002)), units=2)
    res = timing.compare(base, {"c": cand}, repeat=5, min_time=0.02, warmup=False,
                         clock=time.process_time)
    assert res["baseline"].ratios is None and res["c"].ratios.size == 5
    # the candidate does the same time per call for twice the units: half the time per unit
    assert res["c"].ratio == pytest.approx(0.5, rel=0.3)
    runs = "".join(order)
    assert runs.index("c") < runs.rindex("b")  # rounds interleave the two
