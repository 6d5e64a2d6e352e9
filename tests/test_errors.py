"""The library names its own arguments; the command line names its options (issue 25)."""

import ast
from pathlib import Path

import pytest

import warpcloth as wc
from warpcloth.cli.app import main
from warpcloth.cli.flags import FLAGS, LIBRARY_ONLY, as_option, flag_of
from warpcloth.errors import ArgumentError, OptionError

PACKAGE = Path(wc.__file__).parent
NAMING = ("ArgumentError", "ArgumentTypeError", "OptionError", "checked_index")
"""Calls whose first argument is the name an error blames."""


def test_a_library_caller_reads_the_argument_it_wrote(tmp_path):
    sweep = wc.expand({"run": {"duration_s": 0.01}, "sweep": {"grid": {"damping.gamma_per_s": [0.1, 0.2]}}})
    with pytest.raises(ArgumentError, match=r"^workers: must be ≥ 0 \(0 runs the batches in this process\), got -1$"):
        wc.run_sweep(sweep, tmp_path / "s", workers=-1)
    with pytest.raises(ArgumentError, match="^max_batch: must be ≥ 1, got 0$") as raised:
        wc.run_sweep(sweep, tmp_path / "s", max_batch=0)
    assert not isinstance(raised.value, OptionError) and raised.value.argument == "max_batch"
    assert not (tmp_path / "s").exists()


def test_the_command_line_names_the_option_with_the_same_message(capsys):
    # analyse(source, t_from=...) refuses t_from; `warpcloth analyse INPUT --from` says --from
    assert main(["analyse", "damped_swing_laser", "--from", "100"]) == 2
    assert capsys.readouterr().err == (
        "warpcloth analyse: error in option: --from: 100 s is not before the "
        "window's end 1.5 s (the end of damped_swing_laser)\n"
    )
    assert main(["analyse", "no_such_laser"]) == 2
    assert "error in option: INPUT: cannot read the measured motion file no_such_laser" in capsys.readouterr().err
    # a bundled name misspelt: the closest bundled one, and all of them; a path: neither
    assert main(["analyse", "damped_swing_lazer"]) == 2
    err = capsys.readouterr().err
    assert "did you mean damped_swing_laser? (bundled: damped_swing_laser, " in err and err.count("\n") == 1
    assert main(["analyse", "./damped_swing_lazer.csv"]) == 2
    assert capsys.readouterr().err.endswith("damped_swing_lazer.csv: No such file or directory\n")
    converted = as_option(ArgumentError("t_from", "1 s is not before the window's end"))
    assert (type(converted), str(converted)) == (OptionError, "--from: 1 s is not before the window's end")
    own = OptionError("--csv", "exists")
    assert as_option(own) is own and flag_of("--out") == "--out"


def _named_arguments() -> dict[str, list[str]]:
    # Every name the library (all but cli/) can blame, with where: the first argument of
    # the calls in NAMING, an `argument=` keyword, the default of a parameter `argument`,
    # and the first items of a loop `for argument, ... in (("name", ...), ...)`.
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if "cli" in path.relative_to(PACKAGE).parts:
            continue
        tree = ast.parse(path.read_text())
        where = str(path.relative_to(PACKAGE.parent))
        for node in ast.walk(tree):
            names: list[ast.expr] = []
            if isinstance(node, ast.Call):
                func = node.func
                called = func.id if isinstance(func, ast.Name) else getattr(func, "attr", None)
                if called in NAMING and node.args:
                    names.append(node.args[0])
                names += [k.value for k in node.keywords if k.arg == "argument"]
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                args = node.args.args + node.args.kwonlyargs
                defaults = [None] * (len(node.args.args) - len(node.args.defaults)) + node.args.defaults
                defaults += node.args.kw_defaults
                names += [d for a, d in zip(args, defaults, strict=True) if a.arg == "argument" and d is not None]
            elif (
                isinstance(node, ast.For)
                and isinstance(node.target, ast.Tuple)
                and getattr(node.target.elts[0], "id", None) == "argument"
                and isinstance(node.iter, ast.Tuple)
            ):
                names += [item.elts[0] for item in node.iter.elts if isinstance(item, ast.Tuple)]
            for name in names:
                if isinstance(name, ast.Constant) and name.value is None:
                    continue  # no name given: the error is of another kind (a DataFileError)
                if isinstance(name, ast.Constant) and isinstance(name.value, str):
                    found.setdefault(name.value, []).append(f"{where}:{name.lineno}")
                elif not (isinstance(name, ast.Name) and name.id == "argument"):
                    # a name computed some other way cannot be checked here
                    found.setdefault(ast.unparse(name), []).append(f"{where}:{name.lineno} (not a literal)")
    return found


def test_every_argument_the_library_names_has_an_option_or_is_library_only():
    found = _named_arguments()
    assert {"variants", "workers", "t_from", "name_or_path", "out"} <= set(found)  # the scan sees the library
    unmapped = {
        name: where
        for name, where in found.items()
        if name not in FLAGS and name not in LIBRARY_ONLY and not name.startswith("--")
    }
    assert unmapped == {}
    assert not set(FLAGS) & LIBRARY_ONLY
    assert set(FLAGS) | LIBRARY_ONLY <= set(found), "a mapping for an argument nothing names"


def test_only_the_command_line_raises_option_errors():
    raised = []
    for path in sorted(PACKAGE.rglob("*.py")):
        inside = path.relative_to(PACKAGE).parts
        if inside[0] == "cli":
            continue
        raised += [
            f"{path.name}:{node.lineno}"
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "OptionError"
        ]
    assert raised == []


BUILTIN = frozenset({"ValueError", "KeyError", "TypeError", "IndexError", "RuntimeError"})
"""The builtin exceptions the library must not raise at a user (warpcloth.errors has its own)."""


def _raised_builtin(node: ast.Raise) -> str | None:
    # the builtin a `raise X(...)`, `raise X` or `raise builtins.X(...)` raises, else None
    exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
    if isinstance(exc, ast.Name):
        name = exc.id
    elif isinstance(exc, ast.Attribute) and isinstance(exc.value, ast.Name) and exc.value.id == "builtins":
        name = exc.attr
    else:
        return None
    return name if name in BUILTIN else None


def test_no_bare_raise_in_the_library():
    # every problem with an argument is warpcloth's own error naming it (ArgumentError,
    # ArgumentTypeError, SceneError, DataFileError, ...), a broken invariant an
    # InternalError; a bare builtin names nothing the caller wrote
    import warpcloth.kernels

    offenders = []
    for root in (PACKAGE, Path(warpcloth.kernels.__file__).parent):
        for path in sorted(root.rglob("*.py")):
            raises = [
                node
                for node in ast.walk(ast.parse(path.read_text(), filename=str(path)))
                if isinstance(node, ast.Raise)
            ]
            offenders += [
                f"{path.relative_to(root.parent)}:{node.lineno}: raise {name}"
                for node in sorted(raises, key=lambda node: node.lineno)
                if (name := _raised_builtin(node))
            ]
    assert offenders == [], "builtin exceptions raised by the library:\n" + "\n".join(offenders)


def test_a_wrong_type_is_an_argument_error_and_a_type_error():
    from warpcloth.scene.overrides import override_pairs

    with pytest.raises(TypeError, match="^overrides: must be a list of 'key=value' strings or a dict") as raised:
        override_pairs("damping.gamma_per_s=0.5")
    assert isinstance(raised.value, ArgumentError) and raised.value.argument == "overrides"
    assert issubclass(wc.ArgumentTypeError, ValueError) and issubclass(wc.InternalError, RuntimeError)


def test_a_lookup_names_its_argument_and_what_there_is():
    from warpcloth.sheet import rectangle
    from warpcloth.strip.material import ELASTIC, LawParameters

    geometry = rectangle(0.02, 0.02, 0.005, (0.005, 0.005))
    with pytest.raises(
        ArgumentError,
        match=r"^\(i, j\): the sheet has no node at lattice \(i, j\) = \(9, 0\); its lattice reaches i ≤ 5, j ≤ 4",
    ):
        geometry.node(9, 0)
    with pytest.raises(ArgumentError, match=r"^family: must be WARP \(0\) or WEFT \(1\), got 2"):
        geometry.hinge(2, 1, 1)
    with pytest.raises(
        ArgumentError, match=f"^name: the {ELASTIC.law} law has no parameter 'nope'; it has hysteresis_d1, "
    ):
        ELASTIC["nope"]
    with pytest.raises(AttributeError, match="has no parameter 'nope'"):
        ELASTIC.nope  # noqa: B018
    with pytest.raises(ArgumentError, match="^values: the masing law needs hysteresis_d1"):
        LawParameters.of("masing", {})


@pytest.mark.parametrize(
    "call, argument",
    [
        (lambda wc, s: wc.simulate(s, out=5), "out"),
        (lambda wc, s: wc.load_scene(5), "name_or_path"),
        (lambda wc, s: wc.run_sweep("damped_swing_sweep", "unused"), "sweep"),
        (lambda wc, s: wc.run_sweep(wc.load_sweep("damped_swing_sweep"), "unused", max_batch="2"), "max_batch"),
        (lambda wc, s: wc.run_sweep(wc.load_sweep("damped_swing_sweep"), "unused", workers=1.5), "workers"),
        (lambda wc, s: wc.export_usd("a_run_directory", "stage.usda"), "recording"),
        (lambda wc, s: wc.viz.usd.check_stage_path(7), "out_file"),
        (lambda wc, s: wc.expand(wc.load_sweep("damped_swing_sweep")), "raw"),
        (lambda wc, s: wc.simulate(s, threads="2"), "threads"),
        (lambda wc, s: wc.run(123), "scene"),
    ],
)
def test_a_wrong_type_at_the_api_names_its_argument_where_it_enters(call, argument, tmp_path, monkeypatch):
    """A number, a name or a result object where the API wants another is refused where it
    enters, naming the argument and what it got (issue 39: these were bare TypeErrors and
    AttributeErrors from deep inside)."""
    import warpcloth as wc

    monkeypatch.chdir(tmp_path)
    scene = wc.load_scene("damped_swing", ["run.duration_s=0.01"])
    with pytest.raises(wc.ArgumentTypeError, match=f"^{argument}: "):
        call(wc, scene)
    assert not any(tmp_path.iterdir())  # refused before anything was written


def test_swing_metrics_refuse_series_of_different_lengths():
    import numpy as np

    from warpcloth.metrics import swing_summary

    with pytest.raises(ArgumentError, match=r"^laser: t, laser and tip must be one sample each per time; .*'laser': 5"):
        swing_summary(np.arange(10.0), np.zeros(5), np.zeros(10))


def test_json_results_are_strict_json_with_null_for_a_number_without_value():
    """fit.json, meta.json and sweep.json are read by other tools: NaN or ±inf (a σ from
    too few resamples, an energy that diverged) is written as null, never as NaN."""
    import json
    import math

    import numpy as np

    from warpcloth.io.json_file import json_text

    text = json_text({"sigma": float("nan"), "values": [1.0, float("inf"), np.float64("-inf")], "n": np.int64(3)})

    def refuse(constant):
        raise AssertionError(f"{constant} is not JSON")

    assert json.loads(text, parse_constant=refuse) == {"sigma": None, "values": [1.0, None, None], "n": 3}
    assert math.isfinite(json.loads(json_text({"x": 2.5}))["x"])


@pytest.mark.parametrize(
    "option, value, says",
    [
        ("--space-filling", "0", "--space-filling: must be ≥ 1, got 0"),
        ("--bootstrap", "1", "--bootstrap: is 1: a bootstrap σ needs at least 2 resamples"),
    ],
)
def test_a_fit_option_that_would_mean_something_else_is_refused(option, value, says, tmp_path):
    from conftest import run_cli

    done = run_cli(
        "fit",
        "damped_swing",
        "--measured",
        "damped_swing_laser",
        "--free",
        "gamma",
        "--out",
        tmp_path / "f",
        option,
        value,
    )
    assert done.returncode == 2 and says in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert not (tmp_path / "f").exists() or not any((tmp_path / "f").iterdir())


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["track", "v.mp4", "--plane", "p.json", "--thickness-mm", "-0.5"], "'-0.5' must be positive"),
        (["run"], "the following arguments are required: scene"),
        (["bogus"], "invalid choice: 'bogus'"),
        (["clamp", "fit-angle"], "the following arguments are required: ENCODER"),
    ],
    ids=["a-bad-value", "a-missing-argument", "no-such-command", "a-nested-command"],
)
def test_an_option_the_parser_refuses_is_one_line_naming_it(argv, says, capsys):
    # argparse printed its whole usage first (17 lines for `warpcloth track`)
    with pytest.raises(SystemExit) as raised:
        main(argv)
    assert raised.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and says in lines[0] and lines[0].endswith("--help lists the options)"), lines
