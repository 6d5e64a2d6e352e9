"""Materials from KES data: the readers, the tensile and bending fits (recovering the
model's own parameters, exactly and under stated noise), the KES summary values on
hand-computable loops, every bad-data error, material files and scenes that use them,
and the ``warpcloth material`` commands end to end."""

import copy
import re
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from conftest import kes_cycle, kes_moment, run_cli

import warpcloth as wc
from warpcloth.calibrate import kes
from warpcloth.calibrate.kes.least_squares import least_squares_above
from warpcloth.errors import ArgumentError, DataFileError, SceneError
from warpcloth.scene import (
    DEFAULT_MATERIAL,
    MaterialSection,
    bundled_materials,
    material_fields,
    read_material_file,
    read_scene_file,
    scene_from_dict,
    tensile_slope_minimum,
)

ROOT = Path(__file__).resolve().parents[1]
FB1 = ROOT / "scenes" / "data" / "kes_fb1_example.csv"
FB2 = ROOT / "scenes" / "data" / "kes_fb2_example.csv"
TRUE = MaterialSection()  # the examples are made from the default material (make_kes_examples.py)


def write(path, text):
    path.write_text(text)
    return path


# ------------------------------------------------------------------------------- fits


@pytest.mark.parametrize(
    "fields",
    [
        {},  # the default: α K0 = 12.5, branches that saturate
        {
            "bending_rigidity_gf_cm2_per_cm": 0.05,
            "hysteresis_d1_gf_cm_per_cm": 0.08,
            "hysteresis_alpha_cm": 0.6,
            "hysteresis_k0_per_cm": 2.0,
        },  # α K0 = 1.2: branches that never saturate
    ],
)
def test_bending_fit_recovers_a_loop_made_by_the_model(fields):
    # Measured: D, D1, α recovered to ≤ 3.2e-12 (default) and ≤ 1.2e-11 (soft) relative,
    # RMS ≤ 2e-13 of the moment range; bound 1e-9 on each.
    material = MaterialSection(**fields)
    k = kes_cycle(material.hysteresis_k0_per_cm)
    fit = kes.fit_bending(kes.bending_loop(k, kes_moment(material, k)))
    assert fit.rigidity_gf_cm2_per_cm == pytest.approx(material.bending_rigidity_gf_cm2_per_cm, rel=1e-9)
    assert fit.d1_gf_cm_per_cm == pytest.approx(material.hysteresis_d1_gf_cm_per_cm, rel=1e-9)
    assert fit.alpha_cm == pytest.approx(material.hysteresis_alpha_cm, rel=1e-9)
    assert fit.k0_per_cm == material.hysteresis_k0_per_cm
    assert fit.rms_relative < 1e-9 and fit.note == ""


def test_hysteretic_offset_is_linear_in_d1():
    # The premise of the linear (D, D1) solve: along a path with inner reversals, the
    # kernel's moment for D, D1 equals D K + D1 h₁(α) with h₁ from D1 = 1 gf·cm/cm.
    # Measured: max deviation 4.6e-14 of D1 (rounding); bound 1e-12 of D1.
    k = np.concatenate([kes_cycle(), np.linspace(0, 1.2, 60), np.linspace(1.2, 0.4, 40), np.linspace(0.4, 2.5, 80)])
    alphas = [0.5, 2.0, 5.0, 20.0]
    h1 = kes.hysteretic_offsets(k, alphas, 2.5)
    assert h1.shape == (len(k), 4)
    for j, alpha in enumerate(alphas):
        for d, d1 in ((0.0, 0.04), (0.1, 0.5), (0.02, 3e-4)):
            material = MaterialSection(
                bending_rigidity_gf_cm2_per_cm=d, hysteresis_d1_gf_cm_per_cm=d1, hysteresis_alpha_cm=alpha
            )
            assert np.max(np.abs(kes_moment(material, k) - (d * k + d1 * h1[:, j]))) < 1e-12 * d1
    # one launch for many α gives what single launches give
    single = kes.hysteretic_offsets(k, [alphas[2]], 2.5)[:, 0]
    np.testing.assert_array_equal(single, h1[:, 2])


def test_tensile_fit_recovers_known_quartic():
    # Measured: coefficients to 5e-14 relative; bound 1e-8.
    a = [3000.0, -5e4, 2e6, 1e7]
    e = np.linspace(0, 0.08, 41)
    fit = kes.fit_tensile(kes.tensile_loop(e, np.polyval([*a[::-1], 0.0], e)))
    assert fit.coefficients == pytest.approx(a, rel=1e-8)
    assert not fit.constrained and fit.note == "" and fit.rms_relative < 1e-10


def test_tensile_fit_is_constrained_when_the_quartic_would_turn_down():
    # A saturating curve: the free quartic (RMS 3.0 gf/cm) falls beyond the data, so a
    # scene could not use it (T must increase to the divergence strain, 0.25). The
    # constrained fit increases on [0, 0.25] (measured min slope 5.2 gf/cm) at RMS 12.3 gf/cm.
    e = np.linspace(0, 0.06, 61)
    loop = kes.tensile_loop(e, 400 * (1 - np.exp(-e / 0.01)))
    fit = kes.fit_tensile(loop)
    assert fit.constrained and "the unconstrained quartic (RMS 2.99 gf/cm) decreases at ε = 0.25" in fit.note
    assert tensile_slope_minimum(fit.coefficients, 0.25)[0] > 0
    assert fit.rms_gf_per_cm < 15.0
    wc.scene_from_dict({"material": {"tensile_gf_per_cm": fit.coefficients}})  # usable: passes validation
    # a smaller divergence strain constrains less
    assert kes.fit_tensile(loop, max_strain=0.08).rms_gf_per_cm < fit.rms_gf_per_cm


def test_constrained_least_squares_on_hand_cases():
    # min ‖x − b‖ with x ≥ 0 is max(b, 0); min ‖x − (2, 2)‖ with x1 + x2 ≤ 1 is (½, ½).
    x = least_squares_above(np.eye(3), np.array([1.0, -2.0, 3.0]), np.eye(3), np.zeros(3))
    np.testing.assert_allclose(x, [1.0, 0.0, 3.0], atol=1e-12)
    x = least_squares_above(np.eye(2), np.array([2.0, 2.0]), -np.ones((1, 2)), np.array([-1.0]))
    np.testing.assert_allclose(x, [0.5, 0.5], atol=1e-12)
    with pytest.raises(ValueError, match="infeasible"):
        least_squares_above(np.eye(1), np.array([0.0]), np.array([[1.0], [-1.0]]), np.array([1.0, 0.0]))


def test_noisy_example_data_are_fitted_sensibly():
    # The bundled examples: the default material plus Gaussian noise, σ = 2 gf/cm on the
    # force and σ = 0.002 gf·cm/cm on the moment (make_kes_examples.py). Measured here:
    # D +0.09 %, D1 −0.41 %, α +1.0 %; over 40 other noise seeds the spread (std) is
    # 0.08 %, 0.49 %, 2.6 %, so the bounds are about 5 std. T(ε) of the fit stays within
    # 1.45 gf/cm of the true curve (40 seeds: mean 0.97, max 2.09; bound 3).
    fit = kes.fit_kes(kes.read_tensile_csv(FB1), kes.read_bending_csv(FB2))
    b = fit.bending
    assert b.rigidity_gf_cm2_per_cm == pytest.approx(TRUE.bending_rigidity_gf_cm2_per_cm, rel=0.004)
    assert b.d1_gf_cm_per_cm == pytest.approx(TRUE.hysteresis_d1_gf_cm_per_cm, rel=0.025)
    assert b.alpha_cm == pytest.approx(TRUE.hysteresis_alpha_cm, rel=0.10)
    assert b.k0_per_cm == TRUE.hysteresis_k0_per_cm
    # The residual is the noise: not above it (the truth is in the model family, so a
    # global minimum cannot do worse) and not far below (3 parameters absorb little).
    # Measured: 0.0021346 vs the noise's 0.0021380 gf·cm/cm.
    k = fit.bending_loop.curvature
    noise = fit.bending_loop.moment - kes_moment(TRUE, k)
    noise_rms = np.sqrt(np.mean(noise**2))
    assert 0.99 * noise_rms <= b.rms_gf_cm_per_cm <= noise_rms * (1 + 1e-9)
    e = fit.tensile_loop.strain[fit.tensile_loop.loading]
    truth = np.polyval([*TRUE.tensile_gf_per_cm[::-1], 0.0], e)
    tensile_noise = np.sqrt(np.mean((fit.tensile_loop.force[fit.tensile_loop.loading] - truth) ** 2))
    assert 0.95 * tensile_noise <= fit.tensile.rms_gf_per_cm <= tensile_noise * (1 + 1e-9)  # 1.984 vs 2.039
    assert np.max(np.abs(fit.tensile(e) - truth)) < 3.0
    assert not fit.tensile.constrained
    # KES values of the noisy data against those of the noise-free data (B 0.10041,
    # 2HB 0.039907, LT 0.54406, RT 52.58 %). Measured: B −0.9 %, 2HB −4.2 %, LT −0.4 %,
    # RT +0.2 %; 40-seed std 0.5 %, 1.3 %, 0.45 %, 0.3 %.
    clean = kes.bending_summary(kes.bending_loop(k, kes_moment(TRUE, k)))
    assert fit.bending_kes.b_gf_cm2_per_cm == pytest.approx(clean.b_gf_cm2_per_cm, rel=0.03)
    assert fit.bending_kes.hb2_gf_cm_per_cm == pytest.approx(clean.hb2_gf_cm_per_cm, rel=0.07)
    assert fit.tensile_kes.lt == pytest.approx(0.54406, rel=0.025)
    assert fit.tensile_kes.rt_percent == pytest.approx(52.58, rel=0.015)
    assert fit.tensile_kes.emt_percent == pytest.approx(6.001, abs=1e-9)  # the strain is noise-free


# ------------------------------------------------------------------------------- KES values


def test_tensile_kes_values_of_a_straight_line():
    # T = k ε loaded to εm = 5 %: WT = ½ k εm², LT = 1 exactly (trapezoids are exact);
    # unloading along T·(ε/εm) recovers ∫ k ε²/εm = k εm²/3, RT = 2/3 (to the trapezoid
    # rule's O(Δε²): 1.7e-4 relative here).
    k, em = 8000.0, 0.05
    e = np.linspace(0, em, 51)
    loop = kes.tensile_loop(np.concatenate([e, e[::-1][1:]]), np.concatenate([k * e, (k * e * e / em)[::-1][1:]]))
    values = kes.tensile_summary(loop)
    assert values.emt_percent == pytest.approx(5.0, rel=1e-12)
    assert values.fm_gf_per_cm == pytest.approx(400.0, rel=1e-12)
    assert values.wt_gf_cm_per_cm2 == pytest.approx(0.5 * k * em**2, rel=1e-12)
    assert values.lt == pytest.approx(1.0, rel=1e-12)
    assert values.rt_percent == pytest.approx(100 * 2 / 3, rel=3e-4)
    assert kes.tensile_summary(kes.tensile_loop(e, k * e)).rt_percent is None  # no unloading branch


def test_bending_kes_values_of_hand_made_loops():
    k = kes_cycle()
    elastic = kes.bending_summary(kes.bending_loop(k, 0.08 * k))
    assert elastic.b_gf_cm2_per_cm == pytest.approx(0.08, rel=1e-12)
    assert abs(elastic.hb2_gf_cm_per_cm) < 1e-15
    # a parallelogram: M = D K + H rising, D K − H falling → B = D, 2HB = 2H
    rising = np.concatenate([[1.0], np.sign(np.diff(k))])
    loop = kes.bending_loop(k, 0.08 * k + 0.015 * rising)
    values = kes.bending_summary(loop)
    assert values.b_gf_cm2_per_cm == pytest.approx(0.08, rel=1e-12)
    assert values.hb2_gf_cm_per_cm == pytest.approx(0.03, rel=1e-12)
    # the purely elastic loop fits D1 = 0 and says that α means nothing then
    fit = kes.fit_bending(kes.bending_loop(k, 0.08 * k))
    assert fit.rigidity_gf_cm2_per_cm == pytest.approx(0.08, rel=1e-12) and fit.d1_gf_cm_per_cm < 1e-15
    # a loop that stays within |K| ≤ 1.2 has a 2HB but no B (its slope window is 0.5…1.5)
    small = kes.bending_summary(kes.bending_loop(kes_cycle(1.2), 0.08 * kes_cycle(1.2)))
    assert small.b_gf_cm2_per_cm is None and small.hb2_gf_cm_per_cm is not None


# ------------------------------------------------------------------------------- reading


def test_tensile_units_from_header_argument_or_data(tmp_path):
    strain = np.linspace(0, 0.05, 11)
    force = 9000 * strain + 1e8 * strain**4
    rows = list(zip(strain, force, strict=True))
    forms = {
        "percent.csv": "strain_percent,force_gf_per_cm\n" + "".join(f"{e * 100},{t}\n" for e, t in rows),
        "pct.csv": "Strain (%);Force (gf/cm)\n" + "".join(f"{e * 100};{t}\n".replace(".", ",") for e, t in rows),
        "fraction.txt": "strain_fraction force\n" + "".join(f"{e} {t}\n" for e, t in rows),
        "auto_pct.csv": "# no header\n" + "".join(f"{e * 100}, {t},\n" for e, t in rows),
        "auto_frac.csv": "strain\tT_gf_per_cm\n" + "".join(f"{e}\t{t}\n" for e, t in rows),
        "mm.csv": "extension_mm,force_gf_per_cm\n" + "".join(f"{e * 50},{t}\n" for e, t in rows),
    }
    for name, text in forms.items():
        loop = kes.read_tensile_csv(write(tmp_path / name, text))
        np.testing.assert_allclose(loop.strain, strain, rtol=1e-12, atol=1e-15, err_msg=name)
        np.testing.assert_allclose(loop.force, force, rtol=1e-12, err_msg=name)
    assert list(kes.read_tensile_csv(tmp_path / "percent.csv").rows) == list(range(2, 13))  # file lines
    # extension with another gauge length; the argument when the header does not say
    ext = write(tmp_path / "ext20.csv", "".join(f"{e * 20},{t}\n" for e, t in rows))
    np.testing.assert_allclose(kes.read_tensile_csv(ext, "mm", gauge_length_mm=20).strain, strain, atol=1e-15)
    np.testing.assert_allclose(kes.read_tensile_csv(tmp_path / "auto_frac.csv", "percent").strain, strain / 100)


def test_bending_reader_forms(tmp_path):
    k = kes_cycle(step=0.5)
    m = 0.1 * k
    a = kes.read_bending_csv(
        write(tmp_path / "a.csv", "K (1/cm),M (gf·cm/cm)\n" + "".join(f"{x},{y}\n" for x, y in zip(k, m, strict=True)))
    )
    b = kes.read_bending_csv(write(tmp_path / "b.txt", "".join(f"{x}  {y}\n" for x, y in zip(k, m, strict=True))))
    np.testing.assert_array_equal(a.curvature, b.curvature)
    np.testing.assert_array_equal(a.moment, m)


@pytest.mark.parametrize(
    "text, strain_unit, message",
    [
        (
            "strain_percent,force\n" + "".join(f"{i},{i * 10}\n" for i in range(5)),
            None,
            "the loading branch (first row to the maximum strain) has 5 point(s); fitting the quartic needs at least 6",
        ),
        (
            "strain_percent,force\n0,0\n1,10\n2,20\n1.5,30\n3,40\n4,50\n5,60\n6,70\n",
            None,
            "line 5: strain 0.015 after 0.02 (line 4): the loading branch must be monotonic in strain",
        ),
        (
            "strain_percent,force\n0,0\n1,10\n2,20\n3,30\n4,40\n5,50\n3,20\n4,10\n0,0\n",
            None,
            "line 9: strain 0.04 after 0.03 (line 8): the unloading branch must be monotonic in strain",
        ),
        ("strain_percent,force\n0,0\n1,10\n2,nan\n3,30\n", None, "line 4: force is nan; every value must be finite"),
        ("strain_percent,force\n0,0\n1,ten\n", None, "line 3: 'ten' is not a number"),
        ("strain_percent,force\n0,0,1\n", None, "line 2: expected 2 columns, got 3"),
        (
            "strain_percent,force_N_per_m\n0,0\n",
            None,
            "header: column 2 is 'force_N_per_m'; expected force per width in gf/cm",
        ),
        ("curvature_per_cm,moment\n0,0\n", None, "header: column 1 is 'curvature_per_cm'; expected strain_percent"),
        ("extension_cm,force\n0,0\n", None, "header: column 1 is 'extension_cm'"),
        ("extension,force\n0,0\n", None, "say its unit (extension_mm) or give strain_unit='mm'"),
        ("strain_percent,force\n0,0\n", "fraction", "says percent, but the strain unit was given as fraction"),
        ("Strain (%) Force (gf/cm)\n0 0\n", None, "the header 'Strain (%) Force (gf/cm)' has 4 column names"),
    ],
)
def test_bad_tensile_data_is_named(tmp_path, text, strain_unit, message):
    path = write(tmp_path / "fb1.csv", text)
    with pytest.raises(DataFileError, match="fb1.csv") as err:
        kes.read_tensile_csv(path, strain_unit)
    assert message in str(err.value)


def test_bad_tensile_options_are_named(tmp_path):
    path = write(tmp_path / "fb1.csv", "0,0\n")
    with pytest.raises(ArgumentError, match="strain_unit: must be one of percent, fraction, mm; got 'inch'"):
        kes.read_tensile_csv(path, "inch")
    with pytest.raises(ArgumentError, match="gauge_length_mm: must be a positive length in mm, got -5"):
        kes.read_tensile_csv(path, gauge_length_mm=-5)
    with pytest.raises(DataFileError, match="missing.csv: cannot read the KES-FB1 tensile file"):
        kes.read_tensile_csv(tmp_path / "missing.csv")


def bending_text(k, m=None):
    m = 0.1 * np.asarray(k) if m is None else m
    return "curvature_per_cm,moment_gf_cm_per_cm\n" + "".join(f"{x:.4f},{y:.5f}\n" for x, y in zip(k, m, strict=True))


@pytest.mark.parametrize(
    "k, message",
    [
        (
            kes_cycle(step=1.25),
            "the loop has 9 point(s); fitting D, D1 and α along 0 → +K0 → −K0 → 0 needs at least 12",
        ),
        (
            kes_cycle()[:450],
            "the loop does not close: it starts at K = 0 1/cm (line 2) and ends at K = -1.02 1/cm (line 451)",
        ),
        (
            np.concatenate([np.linspace(0, 2.5, 20), np.linspace(2.5, -0.5, 20), np.linspace(-0.5, 0, 5)]),
            "the loop does not reach both signs of curvature: K runs from -0.5 to 2.5 1/cm",
        ),
    ],
)
def test_bad_bending_loops_are_named(tmp_path, k, message):
    path = write(tmp_path / "fb2.csv", bending_text(k))
    with pytest.raises(DataFileError, match="fb2.csv") as err:
        kes.read_bending_csv(path)
    assert message in str(err.value)


@pytest.mark.parametrize(
    "header, message",
    [
        ("curvature_1_per_m,moment", "header: column 1 is 'curvature_1_per_m'; expected curvature in 1/cm"),
        ("curvature,moment_N", "header: column 2 is 'moment_N'; expected moment per width in gf·cm/cm"),
        ("strain_percent,force_gf_per_cm", "expected curvature in 1/cm (e.g. curvature_per_cm; a KES-FB1 tensile file"),
    ],
)
def test_bad_bending_header_is_named(tmp_path, header, message):
    path = write(tmp_path / "fb2.csv", header + "\n0,0\n1,0.1\n")
    with pytest.raises(DataFileError, match="fb2.csv") as err:
        kes.read_bending_csv(path)
    assert message in str(err.value)


def test_bending_non_finite_value_is_named(tmp_path):
    k = kes_cycle(step=0.25)
    m = 0.1 * k
    m[7] = np.inf
    with pytest.raises(DataFileError, match=r"fb2.csv, line 9: moment is inf; every value must be finite"):
        kes.read_bending_csv(write(tmp_path / "fb2.csv", bending_text(k, m)))


# ------------------------------------------------------------------------------- material files


def fitted_material_file(path, density=2.03e-2):
    fit = kes.fit_kes(kes.read_tensile_csv(FB1), kes.read_bending_csv(FB2))
    data = kes.material_file_data(fit, "wool-fitted", density, "fitted to the bundled examples")
    return fit, kes.write_material_file(path, data)


def test_material_file_round_trip_and_scene_by_relative_path(tmp_path, monkeypatch):
    fit, path = fitted_material_file(tmp_path / "mats" / "wool.toml")
    data = read_material_file(path)
    assert data["material"] == {
        "name": "wool-fitted",
        "source": "fitted to the bundled examples",
        **{k: v for k, v in fit.material("wool-fitted", 2.03e-2).items() if k != "name"},
    }
    assert data["fit"]["tensile_rms_gf_per_cm"] == fit.tensile.rms_gf_per_cm
    assert data["fit"]["2hb_gf_cm_per_cm"] == fit.bending_kes.hb2_gf_cm_per_cm
    # a scene two directories away refers to it relative to itself, run from elsewhere
    scene_dir = tmp_path / "scenes" / "mine"
    scene_dir.mkdir(parents=True)
    text = (ROOT / "scenes" / "damped_swing.toml").read_text()
    start = text.index("[material]")
    text = (
        text[:start]
        + '[material]\nfrom_file = "../../mats/wool.toml"\nhysteresis_alpha_cm = 4.0\n'
        + text[text.index("[damping]") :]
    )
    write(scene_dir / "scene.toml", text)
    monkeypatch.chdir(tmp_path / "mats")
    scene = wc.load_scene(scene_dir / "scene.toml")
    expected = {**fit.material("wool-fitted", 2.03e-2), "hysteresis_alpha_cm": 4.0}  # the scene's own value wins
    assert {k: getattr(scene.material, k) for k in [*material_fields("tagawa2003"), "bending_law"]} == expected
    assert scene.material.from_file == str(path.resolve())
    # the resolved scene re-reads to the same scene, even once the material file is gone
    resolved = write(tmp_path / "resolved.toml", tomli_w.dumps(scene.to_dict()))
    path.unlink()
    assert wc.load_scene(resolved) == scene
    with pytest.raises(SceneError, match="material.from_file: cannot read material file"):
        wc.load_scene(scene_dir / "scene.toml")


def test_a_material_file_parsed_once_is_still_read_as_it_stands(tmp_path, monkeypatch):
    # a sweep reads its material file once per variant and parses it once: the parse is
    # keyed by the file's text, so an edit between two reads is seen, and a caller that
    # changes what it got changes no later read
    import warpcloth.scene.materials as materials
    from warpcloth.scene.parse import parse_toml

    _fit, path = fitted_material_file(tmp_path / "wool.toml")
    parses = []
    monkeypatch.setattr(materials, "parse_toml", lambda *a: parses.append(a) or parse_toml(*a))
    first = read_material_file(path)
    first["material"]["name"] = "changed by a caller"
    assert read_material_file(path)["material"]["name"] == "wool-fitted"
    assert len(parses) == 1  # the second read of the same text parsed nothing
    write(path, path.read_text().replace('name = "wool-fitted"', 'name = "wool-edited"'))
    assert read_material_file(path)["material"]["name"] == "wool-edited"
    assert len(parses) == 2
    good = path.read_text()
    write(path, good.replace('name = "wool-edited"', "name = 3"))
    line = 1 + good.splitlines().index('name = "wool-edited"')
    with pytest.raises(SceneError, match=rf"{re.escape(str(path))}, line {line}: .*material.name"):
        read_material_file(path)
    write(path, good)  # mended, it reads again
    assert read_material_file(path)["material"]["name"] == "wool-edited"


def test_scene_by_bundled_name_set_override_and_sweep():
    assert {"wool90-nylon10", "cotton-broadcloth", "polyester-taffeta"} <= set(bundled_materials())
    for name in bundled_materials():
        # each says where its numbers come from: chosen to be typical, or a paper's published values
        source = read_material_file(name)["material"]["source"]
        assert "illustrative" in source or ("published" in source and "Table" in source), (name, source)
        wc.scene_from_dict({"material": {"from_file": name}})  # each is a valid material
    # the bundled default is the default material, field for field
    default = read_material_file("wool90-nylon10")["material"]
    # a file without bending_law is the paper's law
    assert {k: default[k] for k in material_fields("tagawa2003")} == DEFAULT_MATERIAL
    cotton = read_material_file("cotton-broadcloth")["material"]
    # --set material.from_file replaces the scene's own material values (damped_swing
    # writes them all out); other material overrides win wherever they stand
    scene = wc.load_scene("damped_swing", ["material.hysteresis_alpha_cm=3.0", "material.from_file=cotton-broadcloth"])
    assert scene.material.density_g_per_cm2 == cotton["density_g_per_cm2"]
    assert scene.material.name == cotton["name"] and scene.material.hysteresis_alpha_cm == 3.0
    assert scene.damping.gamma_per_s == 0.3  # the rest of the scene stays
    # a sweep over materials
    raw = read_scene_file("damped_swing")
    raw["sweep"] = {"grid": {"material.from_file": ["cotton-broadcloth", "polyester-taffeta"]}}
    sweep = wc.expand(copy.deepcopy(raw))
    assert [s.material.bending_rigidity_gf_cm2_per_cm for s in sweep.scenes] == [0.07, 0.03]
    # other swept material fields land on top of the file, listed before or after it
    raw["sweep"] = {"grid": {"material.hysteresis_alpha_cm": [3.0], "material.from_file": ["cotton-broadcloth"]}}
    (scene,) = wc.expand(copy.deepcopy(raw)).scenes
    assert scene.material.hysteresis_alpha_cm == 3.0
    assert scene.material.bending_rigidity_gf_cm2_per_cm == 0.07


COTTON = read_material_file("cotton-broadcloth")["material"]


@pytest.mark.parametrize(
    "text, message",
    [
        ('[material]\nname = "x"\nsource = "s"\n', "[material] lacks density_g_per_cm2, tensile_gf_per_cm"),
        (
            tomli_w.dumps({"material": {**COTTON, "density_g_per_cm2": -1.0}}),
            "material.density_g_per_cm2: must be > 0, got -1",
        ),
        (
            tomli_w.dumps({"material": {**COTTON, "source": " "}}),
            "material.source must say where the numbers come from",
        ),
        (tomli_w.dumps({"material": {**COTTON, "from_file": "wool90-nylon10"}}), "cannot refer to another"),
        (  # a field in another unit is named beside the one missing
            tomli_w.dumps(
                {
                    "material": {
                        **{k: v for k, v in COTTON.items() if k != "bending_rigidity_gf_cm2_per_cm"},
                        "bending_rigidity_N_m": 7e-7,
                    }
                }
            ),
            "lacks bending_rigidity_gf_cm2_per_cm (it has bending_rigidity_N_m, which no field is called",
        ),
        ("[material]\n[extra]\n", "unknown top-level entry 'extra'"),
        ("[material\n", "is not valid TOML"),
    ],
)
def test_bad_material_file_is_named(tmp_path, text, message):
    path = write(tmp_path / "bad.toml", text)
    with pytest.raises(SceneError, match="material.from_file") as err:
        scene_from_dict({"material": {"from_file": str(path)}})
    assert str(path) in str(err.value) and message in str(err.value)


def test_unknown_material_reference_lists_the_bundled_ones():
    with pytest.raises(SceneError, match="no bundled material 'cotton' .bundled: cotton-broadcloth, "):
        wc.load_scene("damped_swing", ["material.from_file=cotton"])


# ------------------------------------------------------------------------------- CLI


def warpcloth_cli(*args, cwd):
    return run_cli(*args, cwd=cwd)


def test_cli_fit_kes_on_the_example_data(tmp_path):
    # the bundled examples by name (a path works as well: the other tests read FB1, FB2 by path)
    done = warpcloth_cli(
        "material",
        "fit-kes",
        "--tensile",
        "kes_fb1_example",
        "--bending",
        "kes_fb2_example",
        "-o",
        "wool.toml",
        "--density-g-per-cm2",
        "2.03e-2",
        "--plot",
        "fit.png",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "D 0.100093 ± 8.2e-05 gf·cm²/cm, D1 0.0398362 ± 0.00022 gf·cm/cm, α 5.05015 ± 0.15 cm, K0 2.5 1/cm" in out
    assert "KES: EMT 6.001 %, WT 8.169 gf·cm/cm², LT 0.5421, RT 52.7 %" in out
    assert "KES: B 0.09949 gf·cm²/cm, 2HB 0.03825 gf·cm/cm" in out
    assert (tmp_path / "fit.png").stat().st_size > 10_000
    scene = wc.load_scene("damped_swing", [f"material.from_file={tmp_path / 'wool.toml'}"])
    assert scene.material.name == "wool" and scene.material.density_g_per_cm2 == 2.03e-2
    listed = warpcloth_cli("material", "list", cwd=tmp_path)
    assert listed.returncode == 0 and "cotton-broadcloth: illustrative" in listed.stdout


def test_cli_fit_kes_requires_the_density(tmp_path):
    done = warpcloth_cli(
        "material", "fit-kes", "--tensile", str(FB1), "--bending", str(FB2), "-o", "m.toml", cwd=tmp_path
    )
    assert done.returncode == 2
    assert "--density-g-per-cm2: the mass per area is not part of KES-FB1/FB2 data" in done.stderr
    assert not (tmp_path / "m.toml").exists()


def test_material_paths_in_sweeps_and_overrides_and_list_items(tmp_path, monkeypatch):
    # A path among a [sweep]'s values is relative to the scene file, one given with --set
    # to the working directory; both are recorded absolute. A list item of a material
    # that comes from a file starts from the file's list. An empty reference is refused.
    (tmp_path / "proj" / "mats").mkdir(parents=True)
    cotton = read_material_file("cotton-broadcloth")
    write(tmp_path / "proj" / "mats" / "c.toml", tomli_w.dumps({"material": cotton["material"]}))
    text = (ROOT / "scenes" / "damped_swing.toml").read_text()
    text += '\n[sweep.grid]\n"material.from_file" = ["mats/c.toml", "polyester-taffeta"]\n'
    write(tmp_path / "proj" / "sweep.toml", text)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    sweep = wc.load_sweep(tmp_path / "proj" / "sweep.toml")
    assert sweep.scenes[0].material.from_file == str((tmp_path / "proj" / "mats" / "c.toml").resolve())
    assert sweep.scenes[0].material.density_g_per_cm2 == cotton["material"]["density_g_per_cm2"]
    monkeypatch.chdir(tmp_path / "proj")
    scene = wc.load_scene("damped_swing", ["material.from_file=mats/c.toml", "material.tensile_gf_per_cm.3=1e8"])
    assert scene.material.from_file == str((tmp_path / "proj" / "mats" / "c.toml").resolve())
    assert scene.material.tensile_gf_per_cm == [*cotton["material"]["tensile_gf_per_cm"][:3], 1e8]
    with pytest.raises(SceneError, match="names no material file"):
        wc.load_scene("damped_swing", ['material.from_file=""'])


def test_instrument_exports_are_read(tmp_path):
    # A Latin-1 comment (µ from Windows software), tab separation with spaces in the
    # names, and the unit decision recorded.
    strain = np.linspace(0, 0.05, 11)
    force = 9000 * strain + 1e8 * strain**4
    body = "".join(f"{e * 100}\t{t}\n" for e, t in zip(strain, force, strict=True))
    path = tmp_path / "fb1.txt"
    path.write_bytes(("# sample 12 µm\nStrain (%)\tForce (gf/cm)\n" + body).encode("latin-1"))
    loop = kes.read_tensile_csv(path)
    np.testing.assert_allclose(loop.strain, strain, atol=1e-15)
    assert loop.strain_unit == "strain in percent (from the header)"
    bare = write(tmp_path / "bare.csv", body)
    assert kes.read_tensile_csv(bare).strain_unit == "strain in percent (guessed: the column's maximum is above 1)"


def test_a_bending_loop_must_start_from_rest(tmp_path):
    k = kes_cycle()
    start = int(np.argmax(k))  # the same cycle, begun at +K0
    path = write(tmp_path / "fb2.csv", bending_text(np.concatenate([k[start:], k[1 : start + 1]])))
    with pytest.raises(DataFileError, match="not from rest"):
        kes.read_bending_csv(path)


def test_a_loop_the_law_cannot_describe_is_not_reported_as_a_fit(tmp_path):
    # A "bending loop" that is a sine: the fit ends hundreds of times the data's noise
    # away; the material file records that, and the command exits 6 unless --accept.

    k = np.concatenate([np.linspace(0, 2.5, 100), np.linspace(2.5, -2.5, 200), np.linspace(-2.5, 0, 100)])
    moment = 0.3 * np.sin(5 * k) + np.random.default_rng(0).normal(0, 0.001, len(k))
    (tmp_path / "fb2.csv").write_text(
        "curvature_per_cm,moment_gf_cm_per_cm\n" + "\n".join(f"{a:.5f},{b:.6f}" for a, b in zip(k, moment, strict=True))
    )

    def cli(*extra):
        return run_cli(
            "material",
            "fit-kes",
            "--tensile",
            "kes_fb1_example",
            "--bending",
            "fb2.csv",
            "--density-g-per-cm2",
            "0.02",
            "-o",
            "m.toml",
            "--overwrite",
            *extra,
            cwd=tmp_path,
        )

    done = cli()
    assert done.returncode == 6 and "not a fit (poor_fit): the bending RMS" in done.stderr, done.stderr
    import tomllib

    fit_table = tomllib.loads((tmp_path / "m.toml").read_text())["fit"]
    assert fit_table["status"] == "poor_fit" and "× the noise of the data" in fit_table["problems"][0]
    assert cli("--accept").returncode == 0
