"""The command-line layer: one meaning per option, help on every option, one-line errors,
the output-path guard and missing optional dependencies."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hybridwsi import cli
from hybridwsi.commands import _options as o
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path

SRC = Path(cli.__file__).resolve().parents[1]


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


@pytest.fixture(scope="module")
def parsers() -> dict[str, argparse.ArgumentParser]:
    return _subparsers(cli.build_parser())


def test_every_command_is_built(parsers):
    assert set(parsers) == set(cli.COMMANDS)


def test_every_option_has_help(parsers):
    missing = []
    for name, p in {"hybridwsi": cli.build_parser(), **parsers}.items():
        for action in p._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            if action.help == argparse.SUPPRESS:  # deprecated hidden aliases
                continue
            if not (action.help or "").strip():
                missing.append(f"{name} {'/'.join(action.option_strings) or action.dest}")
    assert not missing, f"options without help: {missing}"


#: option -> commands allowed to have it; the same name must mean the same thing everywhere
#: (docs/CLI.md). Options that were overloaded before must not come back.
RETIRED = ("--force", "--window", "--dof", "--jobs", "--stride", "--gamma",
           "--estimate-derivatives", "--lr")


def test_retired_option_names_are_gone(parsers):
    for name, p in parsers.items():
        for opt in RETIRED:
            assert opt not in p._option_string_actions, f"{name} still has {opt}"


def test_dofs_wherever_dofs_matter(parsers):
    for name in ("import", "diagnose", "simulate", "select", "bem", "sweep", "hybrid"):
        action = parsers[name]._option_string_actions["--dofs"]
        assert action.type is o.dof_names, name
    assert parsers["diagnose"].parse_args(["--dofs", "surge,Pitch"]).dofs == ("Surge", "Pitch")


def test_case_mooring_and_eta_options_are_one_definition(parsers):
    """--case NAME|FILE, --mooring and --eta mean one thing in every command that has them."""
    for name in ("bem", "simulate", "sweep"):
        action = parsers[name]._option_string_actions["--case"]
        assert action.metavar == "NAME|FILE" and "case TOML file" in action.help, name
    for name in ("simulate", "sweep"):
        assert parsers[name]._option_string_actions["--mooring"].choices == o.MOORING_MODELS
    for name in ("import", "diagnose", "hybrid", "simulate"):
        assert parsers[name]._option_string_actions["--eta"].help.startswith(
            "wave-elevation column"), name


def test_rotor_and_wind_options_are_one_definition(parsers):
    """--rotor, --wind-speed, --turbulence-intensity, --wind-seed, --slow-drift (issue 29):
    the same action in simulate and sweep, the rotor states those of forces/rotor.py."""
    from hybridwsi.forces.rotor import STATES

    assert o.ROTOR_STATES == STATES
    opts = ("--rotor", "--wind-speed", "--turbulence-intensity", "--wind-seed", "--slow-drift")
    for opt in opts:
        sim, swp = (parsers[n]._option_string_actions[opt] for n in ("simulate", "sweep"))
        assert (sim.type, sim.choices, sim.help) == (swp.type, swp.choices, swp.help), opt
    args = parsers["sweep"].parse_args(["--hs", "4", "--tp", "10", "--out", "x",
                                        "--no-slow-drift", "--wind-speed", "11.4"])
    assert (args.slow_drift, args.wind_speed) == (False, 11.4)


def test_quiet_everywhere(parsers):
    for name, p in parsers.items():
        assert "--quiet" in p._option_string_actions, name
    # the old spelling of sph still works, hidden
    assert parsers["sph"].parse_args(["hydrostatic", "--no-progress"]).quiet is True


def test_shared_options_share_one_definition(parsers):
    """--mass, --coeffs, --out: same type and metavar family in every command."""
    for name, p in parsers.items():
        acts = p._option_string_actions
        if "--mass" in acts:
            assert acts["--mass"].type is o.mass, name
            assert acts["--mass"].help.startswith("rigid-body mass [kg]"), name
        if "--coeffs" in acts:
            assert acts["--coeffs"].help.startswith("coefficient file"), name


def test_hybrid_training_options_default_to_the_former_constants(parsers):
    from hybridwsi.commands.hybrid import _network_settings

    # options left out resolve (without a case) to the constants the command always used
    net = _network_settings(parsers["hybrid"].parse_args(["a.nc", "b.nc", "--out", "x"]))
    assert (net["lr"], net["patience"], net["batch_size"]) == (3e-3, 30, 128)
    assert net["hidden"] == (32,) and net["window"] == 11 and net["seed"] == 0
    assert parsers["hybrid"].parse_args(["a.nc", "--out", "x", "--hidden", "16,8"]).hidden \
        == (16, 8)


@pytest.mark.parametrize("kind,text", [
    (o.positive_float, "nan"), (o.positive_float, "inf"), (o.positive_float, "-inf"),
    (o.positive_float, "0"), (o.positive_float, "-1e-3"), (o.positive_float, "abc"),
    (o.nonnegative_float, "-1"), (o.finite_float, "nan"), (o.positive_int, "0"),
    (o.positive_int, "1.5"), (o.nonnegative_int, "-1"), (o.fraction, "1"), (o.fraction, "0"),
    (o.positive_floats, "0.1,nan"), (o.positive_floats, ","), (o.positive_ints, "abc"),
    (o.dof_names, "Heave,Wobble"), (o.dof_names, "Heave,heave"),
    (o.scheduler_address, "notaurl"), (o.scheduler_address, "tcp://"),
])
def test_types_refuse(kind, text):
    with pytest.raises(argparse.ArgumentTypeError):
        kind(text)


def test_types_accept():
    assert o.positive_float("1e-3") == 1e-3 and o.nonnegative_float("0") == 0.0
    assert o.positive_floats("0.1, 0.2") == (0.1, 0.2) and o.positive_ints("32,16") == (32, 16)
    assert o.scheduler_address("tcp://10.0.0.1:8786") == "tcp://10.0.0.1:8786"


@pytest.mark.parametrize("argv", [
    ["frobnicate"], ["--bogus"], ["diagnose", "--bogus"], ["simulate", "--dt", "nan"],
    ["simulate"], ["hybrid", "--hidden", "abc"], ["sph", "tsunami"],
])
def test_usage_errors_are_one_line(argv, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: hybridwsi"), err
    assert "usage:" not in err


def test_help_still_exits_zero(capsys):
    assert cli.main(["diagnose", "--help"]) == 0
    assert "--force-column" in capsys.readouterr().out


# ----------------------------------------------------------------------- output guard
def test_output_guard(tmp_path):
    src = tmp_path / "h.csv"
    src.write_text("x\n")
    link = tmp_path / "link.csv"
    link.symlink_to(src)
    with pytest.raises(InputError, match="is the input"):
        check_output_path(src, [src])
    with pytest.raises(InputError, match="is the input"):
        check_output_path(link, [src])  # the same file through a link
    with pytest.raises(InputError, match="is the input"):
        check_output_path(tmp_path / "." / "h.csv", [str(src)])
    with pytest.raises(InputError, match="not a regular file"):
        check_output_path("/dev/full")
    with pytest.raises(InputError, match="folder"):
        check_output_path(tmp_path)
    with pytest.raises(InputError, match="not a folder"):
        check_output_path(src / "x.nc")
    with pytest.raises(InputError, match="not a folder"):
        check_output_path(src, kind="dir")
    with pytest.raises(InputError, match="is the input"):
        check_output_path(tmp_path, [src], kind="dir", products=("h.csv",))
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    with pytest.raises(InputError, match="not a regular file"):
        check_output_path(loop)
    # new files, new folders, an existing regular file that is no input: fine
    assert check_output_path(tmp_path / "new" / "deeper" / "x.nc", [src]).name == "x.nc"
    assert check_output_path(tmp_path / "h2.csv", [src, None])
    assert check_output_path(tmp_path / "results", [src], kind="dir")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into read-only folders")
def test_output_guard_unwritable_folder(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(InputError, match="not writable"):
            check_output_path(ro / "x.nc")
    finally:
        ro.chmod(0o700)


def test_diagnose_never_overwrites_its_input(tmp_path, capsys):
    from hybridwsi.commands.diagnose import example_history
    from hybridwsi.history import to_csv

    csv = tmp_path / "h.csv"
    to_csv(example_history(), csv)
    before = csv.read_bytes()
    assert cli.main(["diagnose", str(csv), "--json", str(csv)]) == 2
    assert "is the input" in capsys.readouterr().err
    assert csv.read_bytes() == before


# ----------------------------------------------------------------- optional dependencies
@pytest.mark.parametrize("module,extra,argv", [
    ("torch", "ml", ["hybrid", "a.nc", "b.nc", "--out", "{tmp}/n"]),
    ("distributed", "sweep", ["sweep", "--hs", "0.1", "--tp", "1", "--out", "{tmp}/s"]),
    ("pysph", "sph", ["sph", "hydrostatic", "--out", "{tmp}/s.nc"]),
])
def test_missing_extra_is_one_line(module, extra, argv, monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
    rc = cli.main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert f"pip install 'hybridwsi[{extra}]'" in err and module in err


def test_missing_extra_deep_inside_a_command(monkeypatch, capsys):
    """A missing optional module found late (not by require) is still one line."""
    def run(args):
        import h5py  # noqa: F401

    monkeypatch.setitem(sys.modules, "h5py", None)
    ns = argparse.Namespace(_run=run)
    assert cli._run(ns) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "hybridwsi[bemio]" in err


def test_missing_extra_messages():
    for module, extra in o.EXTRAS.items():
        assert f"hybridwsi[{extra}]" in o.missing_dependency(module)
    assert o.missing_dependency("numpy") is None


# ------------------------------------------------------------------------ resources
def test_allocation_estimate_refuses_before_allocating():
    with pytest.raises(InputError, match="GiB"):
        o.check_steps(1e9, 1e-9, 1)
    assert o.check_steps(30.0, 0.01, 6) == 3001


# ------------------------------------------------------------------------ python -m
@pytest.mark.parametrize("module", ["hybridwsi.cli", "hybridwsi"])
def test_python_dash_m(module, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.run([sys.executable, "-m", module, "--version"], capture_output=True,
                          text=True, env=env, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.startswith("hybridwsi "), proc.stderr


# ------------------------------------------------------------------------ SIGTERM
_TERMINATED_JOB = """
import os, signal, sys, time
from hybridwsi.cli import run_script

def main():
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(60)  # the signal arrives here; SIGTERM's default would kill without cleanup
    finally:
        open(sys.argv[1], "w").write("checkpoint")  # what a long run does on KeyboardInterrupt
    return 0

run_script(main)
"""


def test_sigterm_stops_a_run_as_ctrl_c_does(tmp_path):
    """kill / a batch scheduler's SIGTERM: the run's cleanup (its checkpoint) is written, one
    error line, exit status 143; a background job of a script ignores SIGINT, not SIGTERM."""
    marker = tmp_path / "ckpt"
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.run([sys.executable, "-c", _TERMINATED_JOB, str(marker)],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == cli.EXIT_TERMINATED, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        "error: terminated (partial results were not written; re-run to resume)"]
    assert marker.read_text() == "checkpoint"


def test_sigterm_handler_is_restored_after_a_command():
    import signal

    before = signal.getsignal(signal.SIGTERM)
    seen = []
    args = argparse.Namespace(_run=lambda a: seen.append(signal.getsignal(signal.SIGTERM)))
    assert cli._run(args) == 0
    assert signal.getsignal(signal.SIGTERM) is before
    if before == signal.SIG_DFL:  # installed while the command ran
        assert seen == [cli._raise_terminated]

def test_select_dofs_keeps_units_per_dof():
    import numpy as np

    from hybridwsi.history import make_history, select_dofs, units_per_dof

    t = np.arange(0, 1, 0.1)
    z = np.zeros((t.size, 2))
    h = make_history(t, z, z, z, {"F_tot": z}, dof=["Surge", "Pitch"], mass=np.eye(2))
    p = select_dofs(h, ("Pitch",))
    assert list(p["dof"].values) == ["Pitch"] and units_per_dof(p, "z") == ["rad"]
    assert units_per_dof(p, "F_tot") == ["N m"] and p["mass"].shape == (1, 1)
    with pytest.raises(InputError, match="no DOF Heave"):
        select_dofs(h, ("Heave",))


SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


@pytest.mark.parametrize("args, message", [
    (["sph_compare_kramer.py", "no_such_history.nc"], "error: file not found"),
    (["kramer_damped_fit.py", "--bogus"], "error: kramer_damped_fit.py: unrecognized arguments"),
])
def test_scripts_give_one_error_line(tmp_path, args, message):
    # the scripts in scripts/ handle bad input as the CLI does: one line, exit status 2
    env = dict(os.environ, PYTHONPATH=str(SRC))
    res = subprocess.run([sys.executable, str(SCRIPTS / args[0]), *args[1:]], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == cli.EXIT_ERROR
    assert res.stderr.startswith(message) and res.stderr.count("\n") == 1, res.stderr


def test_every_script_runs_through_the_cli_error_handling():
    for path in sorted(SCRIPTS.glob("*.py")):
        text = path.read_text()
        if '__name__ == "__main__"' in text:
            assert "run_script(main)" in text, path.name
            assert "argparse.ArgumentParser(" not in text, path.name


# ------------------------------------------------------- the last bad inputs (issue 31 item 7)
@pytest.mark.parametrize("kind, text", [
    (o.mass, "1e300"), (o.mass, "1e11"), (o.mass, "1e-300"), (o.mass, "0"), (o.mass, "nan"),
    (o.wave_height, "1e300"), (o.wave_height, "31"), (o.wave_height, "0"),
    (o.wave_heights, "0.1,1e300"),
])
def test_absurd_magnitudes_are_refused_with_the_range(kind, text):
    with pytest.raises(argparse.ArgumentTypeError) as err:
        kind(text)
    if text not in ("nan", "0"):
        assert "between" in str(err.value), err.value


def test_absurd_seas_are_refused_by_the_wave_models_too():
    # what simulate --jonswap/--regular and the sweep's workers build
    from hybridwsi import waves

    for build in (lambda: waves.JONSWAP(hs=1e300, tp=8.0), lambda: waves.Regular(8.0, 31.0)):
        with pytest.raises(InputError, match="at most 30 m"):
            build()
    assert waves.JONSWAP(hs=19.0, tp=16.0).hs == 19.0


def test_magnitudes_of_real_bodies_and_seas_pass():
    # a 7 kg model sphere, the 657 000 t Seawise Giant; the paper's 5 cm sea, a 19 m Hs record
    assert o.mass("7.06") == 7.06 and o.mass("6.57e8") == 6.57e8
    assert o.wave_heights("0.05,19") == (0.05, 19.0)


def test_sweep_unreachable_scheduler_is_one_line_and_leaves_nothing(tmp_path, monkeypatch,
                                                                    capsys):
    pytest.importorskip("distributed")
    pytest.importorskip("zarr")
    from hybridwsi import sweep

    monkeypatch.setattr(sweep, "CONNECT_TIMEOUT", "1s")
    out = tmp_path / "s"
    rc = cli.main(["sweep", "--hs", "0.05", "--tp", "0.8", "--duration", "1", "--scheduler",
                   "tcp://127.0.0.1:1", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    # the client connects before any progress bar or file: the error is the only output
    assert err.count("\n") == 1 and err.startswith("error: cannot connect to the Dask "
                                                   "scheduler tcp://127.0.0.1:1"), err
    assert not out.exists()


def test_sweep_whose_every_case_fails_clears_its_bar_and_leaves_nothing(tmp_path, capsys):
    pytest.importorskip("zarr")
    out = tmp_path / "s"
    # 25 m waves on the 0.3 m sphere: its cap buoyancy leaves its domain in every case
    rc = cli.main(["sweep", "--hs", "25", "--tp", "0.8", "--nonlinear-hydrostatics",
                   "--duration", "2", "--scheduler", "synchronous", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    # one line: the bar drawn with carriage returns, then blanked, then the error
    assert err.count("\n") == 1 and "Traceback" not in err, err
    bar, _, last = err.rstrip("\n").rpartition("\r")
    assert "sweep:" in bar and bar.rsplit("\r", 1)[-1].strip() == "", "bar not cleared"
    assert last.startswith("error: every case failed, nothing was written"), err
    assert not out.exists()  # no manifest "running", no empty parts/


def test_output_through_a_link_writes_where_it_points(tmp_path):
    target = tmp_path / "results" / "h.nc"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "h.nc"
    link.symlink_to(target)
    assert cli.main(["simulate", "--case", "paper_sphere", "--duration", "0.5", "--out",
                     str(link), "--quiet"]) == 0
    assert link.is_symlink() and link.resolve() == target.resolve()
    assert target.read_bytes()[:4] == b"\x89HDF"  # the history, in the file linked to
    assert sorted(p.name for p in tmp_path.iterdir()) == ["h.nc", "results"]
    assert sorted(p.name for p in target.parent.iterdir()) == ["h.nc"]  # no temporary left


# ------------------------------------------------- end-of-run warnings (issue 31 item 8)
def test_end_of_run_warnings_are_printed_once_and_notes_as_notes():
    import warnings

    from hybridwsi.errors import Note

    def command(_args):
        for _ in range(2):  # one flag raised by two steps of a run (from two call sites)
            warnings.warn("BEM coefficients (cached): added_mass_zero is NaN", UserWarning)
        warnings.warn("BEM coefficients (cached): added_mass_zero is NaN", UserWarning,
                      stacklevel=2)
        warnings.warn("something else", UserWarning)
        warnings.warn(Note("A(0) is not used"))
        return 0

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert cli._run(argparse.Namespace(_run=command)) == 0
    texts = [str(w.message) for w in caught]
    assert texts == ["BEM coefficients (cached): added_mass_zero is NaN", "something else",
                     "A(0) is not used"]
    lines = [cli._format_warning(w.message, w.category, w.filename, w.lineno) for w in caught]
    assert lines[0].startswith("warning: ") and lines[2] == "note: A(0) is not used\n"


def test_reproduce_words_the_unused_a0_flag_as_information(tmp_path, monkeypatch):
    import warnings

    from hybridwsi.commands import reproduce as command
    from hybridwsi.errors import Note

    def run(out, **_kw):  # the BEM flag of the finite-depth sphere, from its two loads
        for _ in range(2):
            warnings.warn("BEM coefficients (cached): added_mass_zero is NaN (not computable "
                          "for this water depth/Green function)", UserWarning)
        warnings.warn("a real problem", UserWarning)

    monkeypatch.setattr(command, "reproduce", run)  # the command's name for report.run
    args = cli.build_parser().parse_args(["reproduce", "--quick", "--out", str(tmp_path / "r")])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert cli._run(args) == 0
    kinds = [(w.category, str(w.message)) for w in caught]
    assert kinds == [(Note, command.A0_NOTE), (UserWarning, "a real problem")]
