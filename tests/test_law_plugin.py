"""A bending law added from outside warpcloth, end to end: its kernel file, its KES fitter
and one entry point, and nothing else (docs/architecture.md, "Add a bending law").

The toy law is a Jenkins element written afresh (a spring in series with a slider), with
parameter names of its own: the same arithmetic as the built-in frictional couple, so a
scene of the toy law must reproduce the frictional couple's run bit for bit, and its KES
fit the frictional couple's fit. Each thing warpcloth derives from a law's description is
checked on it: the [material] fields and their refusal under another law, the KES → SI
conversion, the kernel dispatch, ``fit --free`` by alias, the figure label, the fitter of
``material fit-kes --law``. The plugin is installed the way a package is, by a
``.dist-info`` with an entry point on ``sys.path``, in a child process.
"""

import json
import os
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

TOY_LAW = '''
"""A toy bending law: a Jenkins element, M = D K + h, h <- clamp(h + (M_y / K_y) dK, -M_y, M_y)."""
import functools

import warp as wp

from warpcloth.kernels.law import BendingLaw, LawFunctions, LawParameter
from warpcloth.kernels.types import precision


def pack(rigidity, moment, width):
    return (rigidity, moment, width)


@functools.cache
def build(scalar):
    types = precision(scalar)
    Memory, Parameters, History = types.law_memory, types.law_parameters, types.reversal_memory
    zero = scalar(0.0)
    one = scalar(1.0)

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        return Memory(zero, one, curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        change = curvature - memory[2]
        yield_moment = p[1]
        if change == zero or yield_moment == zero:
            return Memory(memory[0], memory[1], curvature)
        h = wp.clamp(memory[0] + yield_moment / p[2] * change, -yield_moment, yield_moment)
        return Memory(h, wp.sign(change), curvature)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        return memory[0]

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        yield_moment = p[1]
        if yield_moment == zero or memory[1] * memory[0] >= yield_moment:
            return p[0]
        return p[0] + yield_moment / p[2]

    return LawFunctions(fresh_memory, follow, hysteretic_moment, tangent)


LAW = BendingLaw(
    name="toy_jenkins",
    summary="a toy Jenkins element",
    parameters=(
        LawParameter("toy_moment", "toy_moment_gf_cm_per_cm", "moment", "My", "M_y",
                     "M_y, the slider's yield moment", default=0.01, ge=0, amplitude=True),
        LawParameter("toy_width", "toy_width_per_cm", "curvature", "Ky", "K_y",
                     "K_y, the spring's curvature at yield", default=0.2, gt=0),
    ),
    pack=pack,
    memory=("hysteretic_moment", "direction", "previous_curvature"),
    build=build,
    fitter="toy_jenkins_fit:FITTER",
    mesh_independent=True,
)
'''

# The fitter lives apart from the kernel file: the kernels are loaded before the rest of
# warpcloth, the fitter only by the KES fit.
TOY_FITTER = """
from warpcloth.calibrate.kes.bending_fit import LawFitter, Parameter, ShapeParameter

FITTER = LawFitter(
    law="toy_jenkins",
    amplitude=Parameter("toy_moment_gf_cm_per_cm", "M_y", "gf·cm/cm"),
    shape=(ShapeParameter("toy_width_per_cm", "K_y", "1/cm", 1e-3, 2.0, 64, k0_power=1, scaled="K_y/K0"),),
)
"""

CHECKS = """
import json
import numpy as np
import warpcloth as wc
from warpcloth.calibrate.kes import law_fitter, read_bending_csv
from warpcloth.calibrate.motion_fit import ALIASES, HYSTERESIS_AMPLITUDES, free_parameters
from warpcloth.kernels import BENDING_LAWS
from warpcloth.scene import field_laws, to_si
from warpcloth.viz.plots import field_label

same = {"material.bending_rigidity_gf_cm2_per_cm": 0.1, "run.duration_s": 0.3}
toy = wc.load_scene("damped_swing", {**same, "material.bending_law": "toy_jenkins",
                                     "material.toy_moment_gf_cm_per_cm": 0.03, "material.toy_width_per_cm": 0.15})
twin = wc.load_scene("damped_swing", {**same, "material.bending_law": "frictional_couple",
                                      "material.friction_moment_gf_cm_per_cm": 0.03,
                                      "material.friction_width_per_cm": 0.15})
a, b = wc.simulate([toy, twin]), wc.simulate(twin)
loop = read_bending_csv("kes_fb2_example")
fits = {law: law_fitter(law).fit(loop) for law in ("toy_jenkins", "frictional_couple")}
print(json.dumps({
    "laws": list(BENDING_LAWS),
    "si": to_si(toy.material).bending.as_dict(),
    "twin_si": to_si(twin.material).bending.as_dict(),
    "same_run": bool(np.array_equal(a.probes[..., 0], b.probes[..., 0], equal_nan=True)
                     and np.array_equal(a.frames[:, 0], b.frames[:, 0])),
    "field_laws": field_laws("material.toy_moment_gf_cm_per_cm"),
    "alias": ALIASES["My"],
    "amplitudes": HYSTERESIS_AMPLITUDES,
    "free": [p.field for p in free_parameters("My,Ky", toy)],
    "label": field_label("material.toy_moment_gf_cm_per_cm"),
    "fits": {law: [fit.parameters[k] for k in fit.parameters] + [fit.rms_gf_cm_per_cm]
             for law, fit in fits.items()},
}))
"""


@pytest.fixture(scope="module")
def plugin(tmp_path_factory) -> dict:
    """A child environment in which the toy law is installed as a package's entry point."""
    site = tmp_path_factory.mktemp("site")
    (site / "toy_jenkins.py").write_text(TOY_LAW)
    (site / "toy_jenkins_fit.py").write_text(TOY_FITTER)
    info = site / "toy_jenkins-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-jenkins\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[warpcloth.bending_laws]\ntoy_jenkins = toy_jenkins:LAW\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")])}
    return env


def child(env: dict, *args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=600)


def test_a_law_from_an_entry_point_is_a_law_everywhere(plugin):
    done = child(plugin, "-c", textwrap.dedent(CHECKS))
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["laws"] == ["tagawa2003", "dahl", "frictional_couple", "masing", "masing_growing", "toy_jenkins"]
    # the one KES → SI conversion, by the units the description names
    assert list(out["si"].values()) == list(out["twin_si"].values())
    assert out["same_run"]  # the dispatch reaches the toy's own kernel, batched beside a built-in law
    assert out["field_laws"] == ["toy_jenkins"]
    assert out["alias"] == "material.toy_moment_gf_cm_per_cm"
    assert "material.toy_moment_gf_cm_per_cm" in out["amplitudes"]
    assert out["free"] == ["material.toy_moment_gf_cm_per_cm", "material.toy_width_per_cm"]
    assert out["label"] == "M_y (gf·cm/cm)"
    # its fitter, found through the description: the frictional couple's fit, number for number
    assert out["fits"]["toy_jenkins"] == out["fits"]["frictional_couple"]


def test_the_command_line_knows_the_plugged_in_law(plugin, tmp_path):
    scene = tmp_path / "toy.toml"
    scene.write_text(
        '[material]\nbending_law = "toy_jenkins"\ntoy_moment_gf_cm_per_cm = 0.02\n[run]\nduration_s = 0.05\n'
    )
    done = child(plugin, "-m", "warpcloth", "run", str(scene), "--out", str(tmp_path / "run"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    written = tomllib.loads((tmp_path / "run" / "scene.toml").read_text())["material"]
    assert written["bending_law"] == "toy_jenkins" and written["toy_width_per_cm"] == 0.2  # its default
    # its fields belong to it: under another law they are refused, in one line, before any kernel runs
    scene.write_text("[material]\ntoy_moment_gf_cm_per_cm = 0.02\n")
    done = child(plugin, "-m", "warpcloth", "run", str(scene), "--out", str(tmp_path / "other"), cwd=tmp_path)
    assert done.returncode != 0
    assert "Traceback" not in done.stderr
    assert "material.toy_moment_gf_cm_per_cm" in done.stderr and "toy_jenkins" in done.stderr
    help_text = child(plugin, "-m", "warpcloth", "material", "fit-kes", "--help").stdout
    assert "toy_jenkins" in help_text


def install(site: Path, module: str, law_source: str, fitter_source: str = TOY_FITTER) -> dict:
    """An environment in which ``law_source`` is installed as the plugin ``module``."""
    (site / f"{module}.py").write_text(law_source)
    (site / "toy_jenkins_fit.py").write_text(fitter_source)
    info = site / f"{module}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {module}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[warpcloth.bending_laws]\n{module} = {module}:LAW\n")
    return {**os.environ, "PYTHONPATH": str(site)}


@pytest.mark.parametrize(
    ("law", "fitter", "command", "needle"),
    [
        (
            "LAW = 42\n",
            TOY_FITTER,
            ["--help"],
            "the bending law 'broken' registered under warpcloth.bending_laws as 'broken:LAW' is a int",
        ),
        (
            TOY_LAW.replace('"curvature", "Ky"', '"angle", "Ky"'),
            TOY_FITTER,
            ["--help"],
            "the toy_jenkins law's parameter 'toy_width' has kind 'angle'; a kind is one of",
        ),
        (
            TOY_LAW,
            TOY_FITTER.replace('"toy_width_per_cm", "K_y"', '"toy_span_per_cm", "K_y"'),
            ["material", "compare", "--bending", "kes_fb2_example"],
            "the toy_jenkins bending law's KES fitter 'toy_jenkins_fit:FITTER' fits",
        ),
    ],
)
def test_a_broken_plugin_is_one_line_naming_itself(tmp_path, law, fitter, command, needle):
    env = install(tmp_path, "broken" if law.startswith("LAW = 42") else "toy_jenkins", law, fitter)
    done = child(env, "-m", "warpcloth", *command, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert needle in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_broken_plugin_names_itself(tmp_path):
    (tmp_path / "broken_law.py").write_text("LAW = 42\n")
    info = tmp_path / "broken_law-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-law\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[warpcloth.bending_laws]\nbroken = broken_law:LAW\n")
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    done = child(env, "-c", "import warpcloth.scene")
    assert done.returncode != 0
    assert (
        "the bending law 'broken' registered under warpcloth.bending_laws as 'broken_law:LAW' is a int" in done.stderr
    )
