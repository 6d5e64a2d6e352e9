"""Every bending law fitted to KES-FB2 loops and compared (issue 15; docs/model.md §13.5):
each fitter recovers its own law's parameters from a loop that law made, the generating
law ranks first by AIC on noisy loops, the KES values each fit reproduces, and
``material fit-kes --law`` / ``material compare`` end to end."""

import csv
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import kes_cycle, kes_moment
from warpcloth.kernels import BENDING_LAWS, bending_tagawa2003

import warpcloth as wc
from warpcloth.calibrate import kes
from warpcloth.cli import main
from warpcloth.errors import ArgumentError
from warpcloth.scene import MaterialSection, material_fields, read_material_file, to_si
from warpcloth.strip import moment_along_path

ROOT = Path(__file__).resolve().parents[1]
FB1 = ROOT / "scenes" / "data" / "kes_fb1_example.csv"
FB2 = ROOT / "scenes" / "data" / "kes_fb2_example.csv"
DATA = ROOT / "scenes" / "data"
GF_CM = 9.80665e-3  # gf·cm/cm → N
NOISE = 0.002  # gf·cm/cm: the bundled FB2 example's (scenes/data/make_kes_examples.py)

PAPER = MaterialSection()  # the default material: the bundled examples' truth
DAHL_SOFT = MaterialSection(
    bending_law="dahl",
    bending_rigidity_gf_cm2_per_cm=0.1,
    dahl_moment_gf_cm_per_cm=0.02,
    dahl_curvature_per_cm=0.3,
    dahl_exponent=0.4,
)  # saturates within a finite bend
DAHL_SLOW = MaterialSection(
    bending_law="dahl",
    bending_rigidity_gf_cm2_per_cm=0.1,
    dahl_moment_gf_cm_per_cm=0.02,
    dahl_curvature_per_cm=0.2,
    dahl_exponent=2.5,
)  # approaches saturation slowly
FRICTION = MaterialSection(
    bending_law="frictional_couple",
    bending_rigidity_gf_cm2_per_cm=0.1,
    friction_moment_gf_cm_per_cm=0.02,
    friction_width_per_cm=0.1,
)


def law_loop(material: MaterialSection, seed=None, k0=2.5):
    k = kes_cycle(k0)
    m = kes_moment(material, k)
    if seed is not None:
        m = m + np.random.default_rng(seed).normal(0.0, NOISE, len(m))
    return kes.bending_loop(k, m)


def write_loop(path, loop):
    path.write_text(
        "curvature_per_cm,moment_gf_cm_per_cm\n"
        + "".join(f"{a:.3f},{b:.6f}\n" for a, b in zip(loop.curvature, loop.moment, strict=True))
    )
    return path


def cli(monkeypatch, tmp_path, capsys, *args):
    monkeypatch.chdir(tmp_path)
    status = main(["material", *args])
    out, err = capsys.readouterr()
    return status, out, err


# ------------------------------------------------------------------------------- the fitters


def test_every_kernel_law_has_a_fitter_and_its_free_parameters():
    assert tuple(kes.LAW_FITTERS) == tuple(BENDING_LAWS)
    assert {law: f.free_parameters for law, f in kes.LAW_FITTERS.items()} == {
        "tagawa2003": 3,
        "dahl": 4,
        "frictional_couple": 3,
        "masing": 3,
        "masing_growing": 4,
    }  # K0 is fixed by the data
    for law, fitter in kes.LAW_FITTERS.items():  # a fit gives exactly the fields its law reads
        assert sorted(p.field for p in fitter.parameters) == sorted(
            f for f in material_fields(law) if f not in ("name", "density_g_per_cm2", "tensile_gf_per_cm")
        )


@pytest.mark.parametrize(
    "material",
    [
        PAPER,
        MaterialSection(bending_rigidity_gf_cm2_per_cm=0.05, hysteresis_d1_gf_cm_per_cm=0.08, hysteresis_alpha_cm=0.6),
        DAHL_SOFT,
        DAHL_SLOW,
        MaterialSection(
            bending_law="dahl",
            bending_rigidity_gf_cm2_per_cm=0.05,
            dahl_moment_gf_cm_per_cm=0.06,
            dahl_curvature_per_cm=1.2,
            dahl_exponent=2.5,
        ),  # never saturates within the cycle
        FRICTION,
        MaterialSection(
            bending_law="frictional_couple",
            bending_rigidity_gf_cm2_per_cm=0.03,
            friction_moment_gf_cm_per_cm=0.05,
            friction_width_per_cm=0.6,
        ),
    ],
    ids=["paper", "paper-soft", "dahl-0.4", "dahl-2.5", "dahl-2.5-unsaturated", "friction", "friction-wide"],
)
def test_fit_kes_recovers_each_law_from_a_loop_it_made(material, tmp_path):
    # Noise-free loops made by each law along the KES cycle. Measured: every parameter to
    # ≤ 3.7e-11 relative (dahl's n), RMS ≤ 1.8e-12 of the moment range; bound 1e-9.
    law = material.bending_law
    fit = kes.fit_kes(kes.read_tensile_csv(FB1), law_loop(material), law=law)
    b = fit.bending
    assert b.law == law and b.note == "" and b.rms_relative < 1e-9
    for name, value in b.parameters.items():
        assert value == pytest.approx(getattr(material, name), rel=1e-9), name
    # the material file says the law and gives its fields, and a scene runs that law
    data = kes.material_file_data(fit, "fitted", 0.02, "test")
    assert data["material"]["bending_law"] == law
    assert set(data["material"]) == {"source", "bending_law", *material_fields(law)}
    path = kes.write_material_file(tmp_path / "m.toml", data)
    scene = wc.load_scene("damped_swing", [f"material.from_file={path}"])
    assert scene.material.bending_law == law
    k = kes_cycle()
    assert np.max(np.abs(kes_moment(scene.material, k) - kes_moment(material, k))) < 1e-9 * np.ptp(b.moment)


def test_dahl_fitted_to_the_papers_loop_is_the_papers_law():
    # Dahl with n = 1 is tagawa2003 (M_s = M0, K_s = 1/α, docs/model.md §4.8), so on the
    # paper's own loop the 2-D search must end there. Measured: n − 1 = −3.3e-11,
    # K_s α − 1 = −2.9e-11, M_s / M0 − 1 = −4.2e-12 (Nelder–Mead stops on a loop fitted to
    # 2.1e-13 of its range); bound 1e-6.
    comparison = kes.compare_laws(law_loop(PAPER))
    dahl = comparison.fits["dahl"].parameters
    m0 = bending_tagawa2003.loop_asymptote(
        PAPER.hysteresis_d1_gf_cm_per_cm, PAPER.hysteresis_alpha_cm, PAPER.hysteresis_k0_per_cm
    )
    assert dahl["dahl_exponent"] == pytest.approx(1.0, abs=1e-6)
    assert dahl["dahl_curvature_per_cm"] * PAPER.hysteresis_alpha_cm == pytest.approx(1.0, abs=1e-6)
    assert dahl["dahl_moment_gf_cm_per_cm"] == pytest.approx(m0, rel=1e-6)
    assert "within 0.05 of 1" in comparison.same_as_tagawa2003()


def test_a_shape_parameter_at_the_edge_of_its_search_is_noted():
    # A frictional couple sharper than the sampling: Dahl's n runs to the grid's 0.1 edge
    # on this loop, which the verdict reports as at_bound.
    comparison = kes.compare_laws(law_loop(FRICTION), ["dahl", "frictional_couple"])
    assert comparison.fits["dahl"].parameters["dahl_exponent"] == pytest.approx(kes.EXPONENT_GRID[0])
    assert "n at the edge of its search range (n = 0.1)" in comparison.fits["dahl"].note
    assert comparison.status("dahl")[0] == "at_bound"
    assert comparison.status("frictional_couple")[0] == "converged"


def test_the_kes_values_each_fit_reproduces():
    # Along the standard cycle every law's own noise-free fit gives the loop's own B and
    # 2HB (measured: to 5e-13 relative; bound 1e-9), and the saturated frictional couple
    # gives B = D and 2HB = 2 M_f exactly (docs/model.md §4.9).
    for material in (PAPER, DAHL_SOFT, FRICTION):
        comparison = kes.compare_laws(law_loop(material), [material.bending_law])
        model, data = comparison.reproduced[material.bending_law], comparison.measured
        assert model.b_gf_cm2_per_cm == pytest.approx(data.b_gf_cm2_per_cm, rel=1e-9)
        assert model.hb2_gf_cm_per_cm == pytest.approx(data.hb2_gf_cm_per_cm, rel=1e-9)
    (friction,) = kes.reproduced_kes_values([kes.compare_laws(law_loop(FRICTION)).fits["frictional_couple"]], 2.5)
    assert friction.b_gf_cm2_per_cm == pytest.approx(FRICTION.bending_rigidity_gf_cm2_per_cm, rel=1e-9)
    assert friction.hb2_gf_cm_per_cm == pytest.approx(2 * FRICTION.friction_moment_gf_cm_per_cm, rel=1e-9)


# ------------------------------------------------------------------------------- ranking by AIC

SEEDS = range(10)


@pytest.mark.slow
@pytest.mark.parametrize("material", [DAHL_SOFT, DAHL_SLOW], ids=["n=0.4", "n=2.5"])
def test_a_dahl_loop_is_recognised_by_aic(material):
    # n clearly away from 1: over seeds 0–19 dahl ranks first on every seed, ΔAIC to the
    # next at least 50 (n = 0.4) and 143 (n = 2.5); bound 20 over seeds 0–9. The fitted n
    # (0.33–0.48 and 2.24–2.91 over those seeds) is not mistaken for the paper's.
    for seed in SEEDS:
        comparison = kes.compare_laws(law_loop(material, seed))
        first, second = comparison.ranking()[:2]
        assert first == "dahl", (seed, comparison.table())
        assert comparison.delta_aic()[second] > 20, (seed, comparison.table())
        assert comparison.same_as_tagawa2003() is None


@pytest.mark.slow
def test_a_frictional_couple_loop_is_recognised_by_aic():
    # Dahl's n → 0 is the frictional couple, but its n stops at 0.1, 1 parameter more:
    # measured over seeds 0–19, AIC ranks frictional_couple first on 19 (dahl once, by
    # 2.9), BIC on all 20; tagawa2003 at least 105 behind. Bounds over seeds 0–9: AIC
    # first on at least 9, BIC on all, tagawa2003 more than 50 behind.
    aic_first = 0
    for seed in SEEDS:
        comparison = kes.compare_laws(law_loop(FRICTION, seed))
        aic_first += comparison.recommended == "frictional_couple"
        assert min(comparison.fits, key=lambda law: comparison.fits[law].bic()) == "frictional_couple", seed
        assert comparison.delta_aic()["tagawa2003"] > 50, seed
    assert aic_first >= 9


@pytest.mark.slow
def test_a_papers_loop_is_recognised_by_its_fewer_parameters():
    # dahl contains tagawa2003 (n = 1), so it can only tie on the paper's loop: its SSE is
    # never above tagawa2003's (the 2-D search finds at least the nested optimum), and the
    # two differ by the noise's χ²₁, so AIC prefers tagawa2003 only through its penalty for
    # dahl's 4th parameter: in about 84 % of loops (P(χ²₁ < 2)); measured 16 of seeds 0–19,
    # 8 of 0–9 (bound 7); BIC (penalty ln 501 = 6.2) on all 20 (bound: all of 0–9). dahl's
    # n is then the paper's within its uncertainty on 9 of 0–9 (bound 8).
    aic_first = same = 0
    for seed in SEEDS:
        comparison = kes.compare_laws(law_loop(PAPER, seed))
        paper, dahl = comparison.fits["tagawa2003"], comparison.fits["dahl"]
        assert dahl.rms_gf_cm_per_cm <= paper.rms_gf_cm_per_cm * (1 + 1e-9), seed
        assert min(comparison.fits, key=lambda law: comparison.fits[law].bic()) == "tagawa2003", seed
        assert comparison.delta_aic()["frictional_couple"] > 50, seed
        aic_first += comparison.recommended == "tagawa2003"
        same += comparison.same_as_tagawa2003() is not None
    assert aic_first >= 7 and same >= 8


def test_ties_and_caveats_are_said():
    # The bundled loop: dahl within ΔAIC 0.64 of tagawa2003 with n = 0.937, not
    # significantly different from 1 (likelihood ratio 1.36 < 3.84).
    comparison = kes.compare_laws(kes.read_bending_csv(FB2))
    caveats = "\n".join(comparison.caveats())
    assert comparison.recommended == "tagawa2003"
    assert "recommended by AIC: tagawa2003 (next: dahl, ΔAIC 0.64)" in caveats
    assert "dahl is within ΔAIC < 2 of tagawa2003: not a preference" in caveats
    assert "dahl's n = 0.937 is within its uncertainty of 1" in caveats
    assert "so on this loop the two are the same law" in caveats
    assert "says nothing about rate effects" in caveats


def test_an_unknown_law_is_named():
    with pytest.raises(
        ArgumentError,
        match=r"law: unknown bending law 'bao'; known: tagawa2003, dahl, "
        r"frictional_couple, masing, masing_growing$",
    ):
        kes.fit_kes(kes.read_tensile_csv(FB1), kes.read_bending_csv(FB2), law="bao")


# ------------------------------------------------------------------------------- the command line


def test_cli_fit_kes_law_all_on_the_bundled_example(monkeypatch, tmp_path, capsys):
    status, out, err = cli(
        monkeypatch,
        tmp_path,
        capsys,
        "fit-kes",
        "--tensile",
        "kes_fb1_example",
        "--bending",
        "kes_fb2_example",
        "-o",
        "wool.toml",
        "--density-g-per-cm2",
        "2.03e-2",
        "--law",
        "all",
        "--plot",
        "laws.png",
    )
    assert status == 0, err
    table = out[out.index("law  ") :]
    for law, numbers in (
        ("tagawa2003", "3     0.0021346   -6155.78   -6143.13     0.00     0.00"),
        ("dahl", "4     0.0021317   -6155.14   -6138.27     0.64     4.85"),
        ("frictional_couple", "3     0.0025158   -5991.15   -5978.50   164.62   164.62"),
    ):
        assert any(line.startswith(law) and numbers in line for line in table.splitlines()), (law, table)
    assert "0.09949      0.038249  (the data's own KES values)" in table
    assert "recommended by AIC: tagawa2003" in out
    assert "wrote wool.toml with the tagawa2003 bending law, the one AIC recommends" in out
    # unchanged from --law tagawa2003 (tests/test_kes.py) where the law is the same
    assert "D 0.100093 ± 8.2e-05 gf·cm²/cm, D1 0.0398362 ± 0.00022 gf·cm/cm, α 5.05015 ± 0.15 cm, K0 2.5 1/cm" in out
    data = tomllib.loads((tmp_path / "wool.toml").read_text())
    assert data["material"]["bending_law"] == "tagawa2003"
    assert "the lowest AIC of tagawa2003, dahl, frictional_couple" in data["material"]["source"]
    assert sorted(data["fit"]["bending_comparison"]) == sorted(BENDING_LAWS)
    assert data["fit"]["bending_comparison"]["dahl"]["delta_aic"] == pytest.approx(0.638, abs=1e-3)
    assert (tmp_path / "laws.png").stat().st_size > 10_000
    read_material_file(tmp_path / "wool.toml")  # a usable material file


@pytest.mark.parametrize("material", [DAHL_SLOW, FRICTION], ids=["dahl", "frictional_couple"])
def test_cli_fit_kes_law_all_writes_the_generating_law(material, monkeypatch, tmp_path, capsys):
    write_loop(tmp_path / "fb2.csv", law_loop(material, seed=0))
    status, out, err = cli(
        monkeypatch,
        tmp_path,
        capsys,
        "fit-kes",
        "--tensile",
        str(FB1),
        "--bending",
        "fb2.csv",
        "-o",
        "m.toml",
        "--density-g-per-cm2",
        "0.02",
        "--law",
        "all",
    )
    law = material.bending_law
    assert status == 0, err
    assert f"recommended by AIC: {law}" in out
    written = read_material_file(tmp_path / "m.toml")["material"]
    assert written["bending_law"] == law
    for name in kes.law_fitter(law).parameters:
        assert written[name.field] == pytest.approx(getattr(material, name.field), rel=0.25), name.field


def test_cli_fit_kes_one_other_law(monkeypatch, tmp_path, capsys):
    status, out, err = cli(
        monkeypatch,
        tmp_path,
        capsys,
        "fit-kes",
        "--tensile",
        "kes_fb1_example",
        "--bending",
        "kes_fb2_example",
        "-o",
        "dahl.toml",
        "--density-g-per-cm2",
        "2.03e-2",
        "--law",
        "dahl",
        "--plot",
        "dahl.png",
    )
    assert status == 0, err
    assert (
        "law dahl: D 0.100114 ± 8.2e-05 gf·cm²/cm, M_s 0.019848 ± 0.00012 gf·cm/cm, K_s 0.197751 ± 0.0056 1/cm, "
        "n 0.936558 ± 0.053"
    ) in out
    assert "AIC -6155.14, BIC -6138.27 (4 free parameters)" in out
    assert "law  " not in out  # one law: no comparison table
    material = read_material_file(tmp_path / "dahl.toml")["material"]
    assert material["bending_law"] == "dahl" and "hysteresis_d1_gf_cm_per_cm" not in material
    assert (tmp_path / "dahl.png").stat().st_size > 10_000


def test_cli_compare_on_the_bundled_example(monkeypatch, tmp_path, capsys):
    status, out, err = cli(
        monkeypatch,
        tmp_path,
        capsys,
        "compare",
        "--bending",
        "kes_fb2_example",
        "--plot",
        "cmp.png",
        "--csv",
        "cmp.csv",
    )
    assert status == 0, err
    assert "recommended by AIC: tagawa2003 (next: dahl, ΔAIC 0.64)" in out
    assert "says nothing about rate effects" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cmp.csv", "cmp.png"]  # no material file
    with open(tmp_path / "cmp.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["law"] for r in rows] == [*BENDING_LAWS, "measured"]
    assert [r["recommended"] for r in rows[:4]] == ["True", "False", "False", "False"]
    assert float(rows[1]["dahl_exponent"]) == pytest.approx(0.936558, rel=1e-5) and rows[0]["dahl_exponent"] == ""
    assert float(rows[2]["delta_aic"]) == pytest.approx(164.62, abs=0.01)
    assert float(rows[-1]["2hb_gf_cm_per_cm"]) == pytest.approx(0.038249, rel=1e-4)
    assert rows[0]["inner_rms_gf_cm_per_cm"] == ""  # a major loop alone: no partial cycles
    assert "this loop has no partial cycles, and a major loop does not determine" in out
    assert (tmp_path / "cmp.png").stat().st_size > 10_000
    status, _, err = cli(monkeypatch, tmp_path, capsys, "compare", "--bending", "kes_fb2_example", "--csv", "cmp.csv")
    assert status == 2 and "--csv: cmp.csv already exists" in err


def test_cli_exits_with_the_status_of_a_loop_no_law_describes(monkeypatch, tmp_path, capsys):
    k = kes_cycle()
    write_loop(tmp_path / "sine.csv", kes.bending_loop(k, 0.3 * np.sin(5 * k)))
    status, out, err = cli(monkeypatch, tmp_path, capsys, "compare", "--bending", "sine.csv")
    assert status == 6 and "not a fit (poor_fit): the recommended" in err, err
    assert cli(monkeypatch, tmp_path, capsys, "compare", "--bending", "sine.csv", "--accept")[0] == 0
    fit_kes = [
        "fit-kes",
        "--tensile",
        str(FB1),
        "--bending",
        "sine.csv",
        "-o",
        "m.toml",
        "--density-g-per-cm2",
        "0.02",
        "--law",
        "all",
        "--overwrite",
    ]
    status, out, err = cli(monkeypatch, tmp_path, capsys, *fit_kes)
    assert status == 6 and "not a fit (poor_fit): the bending RMS" in err, err
    assert tomllib.loads((tmp_path / "m.toml").read_text())["fit"]["status"] == "poor_fit"
    assert cli(monkeypatch, tmp_path, capsys, *fit_kes, "--accept")[0] == 0


@pytest.mark.parametrize(
    "args, message",
    [
        (
            [
                "fit-kes",
                "--tensile",
                "kes_fb1_example",
                "--bending",
                "kes_fb2_example",
                "-o",
                "m.toml",
                "--density-g-per-cm2",
                "0.02",
                "--law",
                "bao",
            ],
            "error in option: --law: unknown bending law 'bao'; known: tagawa2003, dahl, frictional_couple, masing, "
            "masing_growing, or "
            "all",
        ),
        (
            ["compare", "--bending", "kes_fb2_example", "--csv", "table.txt"],
            "error in option: --csv: table.txt must be a file ending in .csv",
        ),
        (
            ["compare", "--bending", "kes_fb2_example", "--plot", "figure.jpg"],
            "error in option: --plot: figure.jpg must be a file ending in .png",
        ),
        (["compare", "--bending", "kes_fb1_example"], "error in data file: kes_fb1_example, line 1: header"),
        (
            ["compare", "--bending", "nothere.csv"],
            "error in option: --bending: cannot read the KES-FB2 bending file nothere.csv",
        ),
    ],
)
def test_cli_wrong_inputs_are_one_line_naming_the_culprit(args, message, monkeypatch, tmp_path, capsys):
    status, out, err = cli(monkeypatch, tmp_path, capsys, *args)
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and message in err, err
    assert not any(tmp_path.iterdir())


def test_a_loop_without_hysteresis_is_not_identifiable_for_any_law():
    # M = D K plus noise: every law fits, none of their hysteresis parameters is determined
    # by the data (the elastic line's AIC is as good), and the comparison says so
    import warpcloth.calibrate.kes as kes
    from warpcloth.calibrate.kes.readers import BendingLoop

    rng = np.random.default_rng(0)
    k = np.concatenate(
        [
            np.linspace(0, 2.5, 126),
            np.linspace(2.5, -2.5, 251)[1:],
            np.linspace(-2.5, 2.5, 251)[1:],
            np.linspace(2.5, 0, 126)[1:],
        ]
    )
    loop = BendingLoop(k, 0.1 * k + rng.normal(0, 0.002, len(k)), np.arange(1, len(k) + 1), "elastic")
    comparison = kes.compare_laws(loop)
    for law in comparison.fits:
        status, problems = comparison.status(law)
        assert status == "not_identifiable" and "elastic line M = D K fits it as well" in problems[0]
    assert any("no law's hysteresis is determined" in line for line in comparison.caveats())
    assert not any("same law" in line for line in comparison.caveats())


@pytest.mark.parametrize(
    "law, section",
    [
        ("tagawa2003", {"hysteresis_d1_gf_cm_per_cm": 0.04, "hysteresis_alpha_cm": 5.0}),
        ("frictional_couple", {"friction_moment_gf_cm_per_cm": 0.02, "friction_width_per_cm": 0.2}),
    ],
)
def test_stated_uncertainties_match_the_scatter_over_noise_seeds(law, section):
    # σ from the linearised model (s² (JᵀJ)⁻¹) against the spread of 20 fits to loops
    # with fresh noise (σ = 0.002 gf·cm/cm); measured ratios 0.9–1.1 for tagawa2003. With
    # 20 seeds a spread is known to ±16 %, hence [0.7, 1.4]. (dahl's M_s and n, more
    # nonlinear, are understated by ~30 %: docs/model.md §13.5.)
    from warpcloth.calibrate.kes.readers import BendingLoop

    k = kes_cycle()
    truth = kes_moment(MaterialSection(bending_law=law, **section), k)
    rng = np.random.default_rng(1)
    fits = [
        kes.LAW_FITTERS[law].fit(
            BendingLoop(k, truth + rng.normal(0, 0.002, len(k)), np.arange(1, len(k) + 1), "noisy")
        )
        for _ in range(20)
    ]
    for name in fits[0].sigma:
        spread = np.std([f.parameters[name] for f in fits], ddof=1)
        stated = np.median([f.sigma[name] for f in fits])
        assert 0.7 < spread / stated < 1.4, (name, spread, stated)


# ------------------------------------------------------------------------- partial (inner) cycles


def test_a_record_with_partial_cycles_says_whose_inner_loops_they_are(monkeypatch, tmp_path, capsys):
    # kes_fb2_inner_loops: the standard cycle then partial cycles, made by an Iwan model of
    # fibre friction (scenes/data/make_kes_examples.py, not warpcloth's kernels) with the
    # default material's loop; the major loop cannot tell tagawa2003 from masing, the
    # partial cycles can (measured: masing 0, dahl +163.8, tagawa2003 +172.7)
    loop = kes.read_bending_csv(DATA / "kes_fb2_inner_loops.csv")
    assert loop.inner_start is not None and loop.rows[loop.inner_start] == 602
    major = kes.read_bending_csv(FB2)
    assert major.inner_start is None
    # the KES values come from the major cycle only (the inner cycles are not legs of it)
    assert kes.bending_summary(loop).b_gf_cm2_per_cm == pytest.approx(0.1, abs=0.002)
    comparison = kes.compare_laws(loop)
    delta = comparison.inner_delta()
    assert delta["masing"] == 0.0 and min(delta["tagawa2003"], delta["dahl"], delta["frictional_couple"]) > 50
    assert comparison.recommended == "masing"
    masing = comparison.fits["masing"]
    assert masing.parameters["hysteresis_d1_gf_cm_per_cm"] == pytest.approx(0.04, rel=0.02)
    status, out, err = cli(
        monkeypatch, tmp_path, capsys, "compare", "--bending", "kes_fb2_inner_loops", "--csv", "inner.csv"
    )
    assert status == 0, err
    # masing_growing with β at the bottom of its range is masing: the partial cycles cannot tell them apart
    assert "the inner loops are masing and masing_growing's" in out
    with open(tmp_path / "inner.csv", newline="") as f:
        rows = {r["law"]: r for r in csv.DictReader(f)}
    assert float(rows["masing"]["inner_delta"]) == 0.0 and float(rows["tagawa2003"]["inner_delta"]) > 50


def test_partial_cycles_of_the_papers_own_law_are_its_own():
    # the verdict is not a preference built in: partial cycles made by tagawa2003 itself
    # (noise-free, warpcloth's kernel) are tagawa2003's, and masing's are masing's
    knots = (0.0, 2.5, -2.5, 2.0, 1.6, 2.0, 1.6, -0.8, -0.4, -0.8, 0.0)
    k = np.concatenate(
        [
            *(
                np.linspace(a, b, round(abs(b - a) / 0.02), endpoint=False)
                for a, b in zip(knots[:-1], knots[1:], strict=True)
            ),
            [0.0],
        ]
    )
    noise = np.random.default_rng(5).normal(0.0, 2e-4, len(k))
    for law in ("tagawa2003", "masing"):
        material = to_si(MaterialSection(bending_law=law))
        moment = moment_along_path(material, k * 100.0)[0] / GF_CM + noise
        comparison = kes.compare_laws(kes.bending_loop(k, moment), laws=["tagawa2003", "masing"])
        assert comparison.inner_delta()[law] == 0.0, law
        other = "masing" if law == "tagawa2003" else "tagawa2003"
        assert comparison.inner_delta()[other] > 10, law
