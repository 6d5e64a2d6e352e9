"""Bad input is refused before any kernel runs, with the field and value named."""

import importlib.resources
import math
import re

import pytest
from conftest import overrides

import warpcloth as wc
from warpcloth.scene import apply_overrides, read_scene_file, scene_from_dict


def load(**fields):
    return wc.load_scene("damped_swing", overrides(**fields))


@pytest.mark.parametrize(
    "fields, field, text",
    [
        (dict(strip__spacing_mm=-5.0), "strip.spacing_mm", "must be > 0, got -5"),
        (dict(strip__spacing_mm=3.0), "strip.spacing_mm", "does not divide strip.free_length_mm"),
        (dict(strip__spacing_mm=60.0), "strip.spacing_mm", "does not divide"),
        (dict(strip__free_length_mm=0.0), "strip.free_length_mm", "must be > 0"),
        (
            dict(material__tensile_gf_per_cm=[2000.0, -3e4, 0.0, 0.0]),
            "material.tensile_gf_per_cm",
            "not increasing at ε = 0.25",
        ),
        # interior minimum of dT/dε (where T'' = 0), found exactly
        (
            dict(material__tensile_gf_per_cm=[2000.0, 0.0, -2e5, 5e5]),
            "material.tensile_gf_per_cm",
            "not increasing at ε = 0.2 (dT/dε = -6000 gf/cm)",
        ),
        (
            dict(material__tensile_gf_per_cm=[0.0, 0.0, 0.0, 1e7]),
            "material.tensile_gf_per_cm",
            "at ε = 0 (dT/dε = 0 gf/cm)",
        ),
        (dict(material__tensile_gf_per_cm=[2000.0, 0.0]), "material.tensile_gf_per_cm", "needs the 4"),
        (
            dict(material__bending_rigidity_gf_cm2_per_cm=-0.1),
            "material.bending_rigidity_gf_cm2_per_cm",
            "must be ≥ 0, got -0.1",
        ),
        (dict(material__hysteresis_d1_gf_cm_per_cm=-0.01), "material.hysteresis_d1_gf_cm_per_cm", "must be ≥ 0"),
        (dict(material__hysteresis_alpha_cm=0.0), "material.hysteresis_alpha_cm", "must be > 0, got 0"),
        (dict(material__hysteresis_k0_per_cm=-2.0), "material.hysteresis_k0_per_cm", "must be > 0"),
        (dict(material__density_g_per_cm2=0.0), "material.density_g_per_cm2", "must be > 0"),
        (dict(damping__gamma_per_s=-1.0), "damping.gamma_per_s", "must be ≥ 0"),
        (dict(integrator__dt_s=0.0), "integrator.dt_s", "must be > 0"),
        (dict(integrator__dt_s=0.01), "integrator.dt_s", "longer than the probe interval"),
        (dict(integrator__scheme="rk4"), "integrator.scheme", "must be one of semi_implicit, forward"),
        (dict(integrator__precision="float16"), "integrator.precision", "must be one of"),
        (dict(output__probes_per_frame=0), "output.probes_per_frame", "must be ≥ 1"),
        (dict(output__probes_per_frame=2.5), "output.probes_per_frame", "expected an integer"),
        (dict(release__hold_x_mm=150.0), "release.hold_x_mm", "the free end reaches between"),
        (dict(run__duration_s=1e9), "run.duration_s", "steps of each strip, more than integrator.max_steps"),
        (dict(strip__width_mm="wide"), "strip.width_mm", "expected a number, got 'wide'"),
        (dict(release__enabled=1), "release.enabled", "expected true or false"),
        (dict(clamp__motion="wobble"), "clamp.motion", "must be one of fixed, piecewise, table"),
        (dict(clamp__motion="piecewise"), "clamp.segments", "needs at least one segment"),
        (
            dict(clamp__motion="table", clamp__table_t_s=[0.0, 0.1], clamp__table_theta_rad=[0.0]),
            "clamp.table_theta_rad",
            "needs as many samples",
        ),
        (
            dict(clamp__motion="table", clamp__table_t_s=[0.0, 0.1, 0.1], clamp__table_theta_rad=[0.0, 1.0, 2.0]),
            "clamp.table_t_s[2]",
            "must be after",
        ),
        (
            dict(
                strip__rest_curvature_per_cm=0.1,
                strip__rest_curvature_table_s_mm=[0.0, 100.0],
                strip__rest_curvature_table_per_cm=[0.1, 0.1],
            ),
            "strip.rest_curvature_per_cm",
            "= 0.1 1/cm and a table strip.rest_curvature_table_per_cm are both given",
        ),
        (
            dict(strip__rest_curvature_table_s_mm=[0.0, 100.0], strip__rest_curvature_table_per_cm=[0.1]),
            "strip.rest_curvature_table_per_cm",
            "needs as many values as strip.rest_curvature_table_s_mm, at least 2 (got 2 arc lengths and 1 curvatures)",
        ),
        (
            dict(strip__rest_curvature_table_s_mm=[5.0, 100.0], strip__rest_curvature_table_per_cm=[0.1, 0.2]),
            "strip.rest_curvature_table_s_mm[0]",
            "5 mm must be 0",
        ),
        (
            dict(
                strip__rest_curvature_table_s_mm=[0.0, 50.0, 50.0, 100.0],
                strip__rest_curvature_table_per_cm=[0.1, 0.2, 0.2, 0.1],
            ),
            "strip.rest_curvature_table_s_mm[2]",
            "50 mm must be after 50 mm",
        ),
        (
            dict(strip__rest_curvature_table_s_mm=[0.0, 80.0], strip__rest_curvature_table_per_cm=[0.1, 0.2]),
            "strip.rest_curvature_table_s_mm[1]",
            "80 mm ends above the free end; the profile must reach strip.free_length_mm = 100 mm",
        ),
        (
            dict(strip__rest_curvature_per_cm=-2.5),
            "strip.rest_curvature_per_cm",
            "-2.5 1/cm curls the strip by more than one radian per segment (1/h = 2 1/cm",
        ),
        (
            dict(strip__rest_curvature_table_s_mm=[0.0, 100.0], strip__rest_curvature_table_per_cm=[0.1, 3.0]),
            "strip.rest_curvature_table_per_cm[1]",
            "3 1/cm curls the strip",
        ),
        (dict(strip__rest_curvature_per_cm="curly"), "strip.rest_curvature_per_cm", "expected a number"),
        (
            dict(release__hold_free_end=False, release__hold_x_mm=30.0),
            "release.hold_x_mm",
            "= 30 mm but release.hold_free_end = false leaves the free end free",
        ),
        (dict(clamp__grip_length_mm=120.0), "clamp.grip_length_mm", "120 mm is longer than the free strip"),
        (dict(clamp__grip_length_mm=-1.0), "clamp.grip_length_mm", "must be ≥ 0"),
        (dict(clamp__grip_bending_factor=0.0), "clamp.grip_bending_factor", "must be > 0, got 0"),
        (dict(clamp__grip_hysteresis_factor=-1.0), "clamp.grip_hysteresis_factor", "must be ≥ 0"),
    ],
)
def test_field_errors_name_field_and_value(fields, field, text):
    with pytest.raises(wc.SceneError) as info:
        load(**fields)
    assert info.value.field == field
    assert str(info.value).startswith(field + ":")
    assert text in str(info.value)


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_non_finite_numbers_are_refused(value):
    with pytest.raises(wc.SceneError, match=r"damping.gamma_per_s: must be a finite number"):
        wc.load_scene("damped_swing", [f"damping.gamma_per_s={value}"])


def test_unknown_fields_and_sections():
    with pytest.raises(wc.SceneError, match=r"^strip.spacing: unknown field; known fields here: free_length_mm"):
        wc.load_scene("damped_swing", ["strip.spacing=5"])
    with pytest.raises(wc.SceneError, match=r"^solver: unknown field"):
        wc.load_scene("damped_swing", ["solver.dt_s=1e-5"])


def test_clamp_segments_must_be_contiguous_and_continuous():
    base = read_scene_file("impulsive_rotation")
    with pytest.raises(wc.SceneError, match=r"clamp.segments\[1\].theta_coefficients_si: θ jumps by 0.1 rad"):
        scene_from_dict(apply_overrides(base, ["clamp.segments.1.theta_coefficients_si=[0.3, 16.0]"]))
    with pytest.raises(wc.SceneError, match=r"clamp.segments\[1\].t_start_s: 0.06 s must equal"):
        scene_from_dict(apply_overrides(base, ["clamp.segments.1.t_start_s=0.06"]))
    with pytest.raises(wc.SceneError, match=r"clamp.segments\[0\].t_end_s: 0 must be after"):
        scene_from_dict(apply_overrides(base, ["clamp.segments.0.t_end_s=0.0"]))
    with pytest.raises(wc.SceneError, match=r"theta_coefficients_si: needs 1 to 5"):
        scene_from_dict(apply_overrides(base, ["clamp.segments.0.theta_coefficients_si=[0,0,0,0,0,1.0]"]))


@pytest.mark.parametrize("reference", ["exp/damped_swing.toml", "damped_swing.toml", "exp/damped_swing"])
def test_a_path_is_a_path_never_the_bundled_scene_of_its_stem(tmp_path, monkeypatch, reference):
    # A reference with a directory part or a .toml suffix is a file that must exist: it
    # used to fall back silently on the bundled scene of the same stem and run that.
    monkeypatch.chdir(tmp_path)
    with pytest.raises(wc.DataFileError, match=f"{reference}: no such scene file .a path, because it"):
        wc.load_scene(reference)
    with pytest.raises(wc.DataFileError, match="no such scene file"):
        wc.load_sweep(reference)
    (tmp_path / "damped_swing.toml").write_text("[damping]\ngamma_per_s = 0.7\n")
    assert wc.load_scene(tmp_path / "damped_swing.toml").damping.gamma_per_s == 0.7  # the file, not the bundle
    assert wc.load_scene("damped_swing").damping.gamma_per_s == 0.3  # a bare name is the bundled scene


def test_malformed_scene_files(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[strip\nspacing_mm = 5\n")
    with pytest.raises(wc.SceneError, match="is not valid TOML"):
        wc.load_scene(bad)
    with pytest.raises(
        wc.ArgumentError, match="name_or_path: no bundled scene .no_such_scene. .bundled: bias_strip, damped_swing"
    ):
        wc.load_scene("no_such_scene")
    with pytest.raises(wc.SceneError, match="strip: expected a table"):
        scene_from_dict({"strip": 5})
    with pytest.raises(wc.SceneError, match="an override must look like"):
        wc.load_scene("damped_swing", ["integrator.dt_s"])
    with pytest.raises(wc.SceneError, match="no list item '7'"):
        wc.load_scene("impulsive_rotation", ["clamp.segments.7.t_end_s=1.0"])


def test_empty_file_gives_the_documented_defaults(tmp_path):
    empty = tmp_path / "empty.toml"
    empty.write_text("")
    scene = wc.load_scene(empty)
    assert scene.strip.spacing_mm == 5.0 and scene.integrator.precision == "float64"
    assert "illustrative" in scene.material.name


@pytest.mark.parametrize(
    "content, message",
    [
        (b"\x00\x01\x02\xff\xfe binary", "is not UTF-8 text"),
        ("[damping]\ngamma_per_s = 0.5  # réglé\n".encode("latin-1"), r"is not UTF-8 text \(byte 0xe9"),
    ],
)
def test_a_scene_file_that_is_not_utf8_text_is_named(tmp_path, content, message):
    path = tmp_path / "scene.toml"
    path.write_bytes(content)
    with pytest.raises(wc.DataFileError, match=message):
        wc.load_scene(path)
    material = tmp_path / "fabric.toml"
    material.write_bytes(content)
    with pytest.raises(wc.DataFileError, match=message):
        wc.load_scene("damped_swing", [f"material.from_file={str(material)!r}"])


def test_a_motion_given_to_a_fixed_clamp_is_refused():
    import warpcloth as wc

    segment = "[{t_start_s = 0.0, t_end_s = 0.1, theta_coefficients_si = [0.0, 1.0]}]"
    with pytest.raises(wc.SceneError, match="clamp.segments: is given but clamp.motion = 'fixed' ignores it"):
        wc.load_scene("damped_swing", [f"clamp.segments={segment}"])


def test_scene_errors_say_where_the_value_was_set(tmp_path):
    from warpcloth.scene.files import scene_source
    from warpcloth.scene.locate import field_line, where_set

    text, _ = scene_source("damped_swing")
    scene = tmp_path / "swing.toml"
    scene.write_text(text.replace("dt_s = 1e-5 ", "dt_s = 0.01 "))
    line = 1 + next(i for i, row in enumerate(text.splitlines()) if row.startswith("dt_s"))
    with pytest.raises(
        wc.SceneError,
        match=rf"^integrator.dt_s: 0.01 s is longer than the probe interval .* "
        rf"\({re.escape(str(scene))}, line {line}\)$",
    ):
        wc.load_scene(scene)
    with pytest.raises(wc.SceneError, match=r"\(set by the override integrator.dt_s=1e-4\)$"):
        wc.load_scene("damped_swing", ["integrator.dt_s=1e-4"])
    with pytest.raises(wc.SceneError, match=r"\(set by the override damping.gamma_per_s=-1.0\)$"):
        wc.load_scene("damped_swing", {"damping.gamma_per_s": -1.0})
    # an array of tables: the second [[clamp.segments]]'s key, not the first's
    rotation, _ = scene_source("impulsive_rotation")
    bad = tmp_path / "rotation.toml"
    bad.write_text(rotation.replace("t_start_s = 0.05", "t_start_s = 0.06"))
    second = 1 + next(i for i, row in enumerate(rotation.splitlines()) if row.startswith("t_start_s = 0.05"))
    with pytest.raises(wc.SceneError, match=rf"clamp.segments\[1\].t_start_s: .*, line {second}\)$"):
        wc.load_scene(bad)
    # a sweep variant's bad value: the line that sweeps it
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(text + '\n[sweep.grid]\n"damping.gamma_per_s" = [0.5, -1.0]\n')
    swept = len(sweep.read_text().splitlines())
    with pytest.raises(wc.SceneError, match=rf"in sweep variant 1 .*, line {swept}\)$"):
        wc.load_sweep(sweep)
    # dotted keys, quoted keys and comments
    assert field_line('# dt_s = 1\nintegrator.dt_s = 2  # x = 3\n[strip]\n"spacing_mm" = 5\n', "integrator.dt_s") == 2
    assert field_line('[strip]\n"spacing_mm" = 5\n', "strip.spacing_mm") == 2
    # the override that won (the last), one that replaced the list holding the field, the
    # material file that replaced the material, a cross-field check's other field
    with pytest.raises(wc.SceneError, match=r"got -2 \(set by the override damping.gamma_per_s=-2.0\)$"):
        wc.load_scene("damped_swing", ["damping.gamma_per_s=-1.0", "damping.gamma_per_s=-2.0"])
    segments = (
        "clamp.segments=[{t_start_s = 0.0, t_end_s = 0.1, theta_coefficients_si = [0.0, 1.0]}, "
        "{t_start_s = 0.2, t_end_s = 0.3, theta_coefficients_si = [0.1]}]"
    )
    with pytest.raises(wc.SceneError, match=r"clamp.segments\[1\].t_start_s: .*\(set by the override clamp.segments="):
        wc.load_scene("impulsive_rotation", [segments])
    wool_text = (importlib.resources.files("warpcloth.scenes") / "materials" / "wool90-nylon10.toml").read_text()
    soft = tmp_path / "soft.toml"  # a2 so negative that T' < 0 within the strain range: the scene check refuses
    soft.write_text(wool_text.replace("[2000.0, 0.0, 0.0, 2.93e7]", "[2000.0, -1e6, 0.0, 0.0]"))
    with pytest.raises(
        wc.SceneError,
        match=rf"^material.tensile_gf_per_cm: .*\(set by the override "
        rf"material.from_file=\"{re.escape(str(soft))}\"\)$",
    ):
        wc.load_scene("damped_swing", [f'material.from_file="{soft}"'])
    with pytest.raises(
        wc.SceneError,
        match=r"^release.hold_x_mm: .*\(bundled scene damped_swing, line 26; and the "
        r"override release.hold_y_mm=-500\)$",
    ):
        wc.load_scene("damped_swing", ["release.hold_y_mm=-500"])
    # a sweep variant's value comes from its sweep line even when the base field is overridden too
    with pytest.raises(wc.SceneError, match=rf"in sweep variant 1 .*, line {swept}\)$"):
        wc.load_sweep(sweep, ["damping.gamma_per_s=0.4"])
    # multi-line strings, nested arrays of tables, a U+2028 in a comment
    assert field_line('note = """\n[integrator]\ndt_s = 1\n"""\n[integrator]\ndt_s = 2\n', "integrator.dt_s") == 6
    assert field_line("[[a]]\n[[a.b]]\nx = 1\n[[a]]\n[[a.b]]\nx = 2\n", "a[1].b[0].x") == 6
    assert field_line("# \u2028 comment\n[integrator]\ndt_s = 1\n", "integrator.dt_s") == 3
    # a value nobody set (a default) is not located
    assert where_set(wc.SceneError("integrator.dt_s", "x"), "[strip]\nspacing_mm = 5\n", "f.toml") is None
    # an inline table, a table written with dotted keys
    assert field_line("damping = { gamma_per_s = -3 }\n", "damping.gamma_per_s") == 1
    assert field_line("[release]\nenabled = true\ndamping.gamma_per_s = 1\n", "release.damping") == 3
    # a bad value in a material file: its own line
    material = tmp_path / "mat.toml"
    material.write_text(wool_text.replace("density_g_per_cm2 = 2.03e-2", "density_g_per_cm2 = -0.007"))
    line = 1 + wool_text.split("\n").index("density_g_per_cm2 = 2.03e-2")
    with pytest.raises(wc.SceneError, match=rf"{re.escape(str(material))}, line {line}: material.density_g_per_cm2: "):
        wc.load_scene("damped_swing", [f'material.from_file="{material}"'])


def test_override_keys_index_lists_and_quote_dotted_names():
    # list items by [i] as by .i; a quoted key keeps its dots (a swept field's range)
    rotation = wc.load_scene("impulsive_rotation", ["clamp.segments[1].t_end_s=0.13"])
    assert rotation.clamp.segments[1].t_end_s == 0.13
    sweep = wc.load_sweep(
        "damped_swing_sweep", ["sweep.random.samples=5", 'sweep.random.ranges."damping.gamma_per_s"=[0.1, 0.2]']
    )
    assert all(0.1 <= s.damping.gamma_per_s <= 0.2 for s in sweep.scenes)
    # an item of a list the scene does not have; a list item that is a number
    with pytest.raises(wc.SceneError, match=r"clamp.table_t_s: has no list item '0': it is not set here"):
        wc.load_scene("damped_swing", ["clamp.table_t_s.0=1.0"])
    with pytest.raises(wc.SceneError, match=r"^material.tensile_gf_per_cm.1: is a value, not a section"):
        wc.load_scene("damped_swing", ["material.tensile_gf_per_cm.1.0.0=3"])
    # a typo is an error naming it as written, never another field
    for typo in (
        "damping:gamma_per_s",
        "damping..gamma_per_s",
        "damping.gamma_per_s,",
        ".damping.gamma_per_s",
        "damping.gamma_per_s.",
        "dämping.gamma_per_s",
        "damping.gamma per_s",
    ):
        with pytest.raises(wc.SceneError, match=rf"^{re.escape(typo)}: is not a field name"):
            wc.load_scene("damped_swing", [f"{typo}=1"])
    with pytest.raises(wc.SceneError, match=r"^sweep.random..samples: is not a field name"):
        wc.load_sweep("damped_swing_sweep", ["sweep.random..samples=5"])
    # a quoted dotted name is a swept field's, nowhere else
    with pytest.raises(wc.SceneError, match=r"in quotes is a swept field's name, which only sweep.grid"):
        wc.load_scene("damped_swing", ['"integrator.dt_s"=1e-4'])
    # material.from_file however spelled goes first, so that it cannot undo a field override
    scene = wc.load_scene("damped_swing", ["material.density_g_per_cm2=0.05", 'material."from_file"=cotton-broadcloth'])
    assert scene.material.density_g_per_cm2 == 0.05
    assert scene.material.tensile_gf_per_cm[0] == 5000.0
    # a sweep variant's value from an override of its sweep entry; a base scene's step for every variant
    with pytest.raises(wc.SceneError, match=r"in sweep variant 0 .*\(set by the override sweep.random.ranges."):
        wc.load_sweep(
            "damped_swing_sweep", ["sweep.random.samples=5", 'sweep.random.ranges."damping.gamma_per_s"=[-2.0, -1.0]']
        )
    with pytest.raises(
        wc.SceneError,
        match=r"^integrator.dt_s: .*\(the base scene: every variant\) \(set by the "
        r"override integrator.dt_s=1e-4\)$",
    ):
        wc.load_sweep("damped_swing_sweep", ["sweep.random.samples=5", "integrator.dt_s=1e-4"])
    # a dict with a key that is not a string: an error, not a traceback
    with pytest.raises(wc.SceneError, match=r"^1: unknown field"):
        wc.load_scene("damped_swing", {1: 2})


def test_a_hanging_chain_sags_as_the_catenary_says():
    from warpcloth.scene.validate import hanging_sag

    # taut or with its lowest point at an end: no sag (the bundled swing, 100 mm held 94.3 mm away)
    assert hanging_sag(50.0, -80.0, 100.0) == 0.0 and hanging_sag(60.0, -80.0, 100.0) == 0.0
    # held straight below: the slack folds down and back up, half of it below the end
    assert hanging_sag(0.0, -80.0, 100.0) == pytest.approx(10.0)
    # a level chain: the textbook catenary, sag a(cosh(x/2a) − 1) with 2a·sinh(x/2a) = L
    span, length = 100.0, 120.0
    from scipy.optimize import brentq

    a = brentq(lambda a: 2 * a * math.sinh(span / (2 * a)) - length, 1.0, 1e4)
    assert hanging_sag(span, 0.0, length) == pytest.approx(a * (math.cosh(span / (2 * a)) - 1), rel=1e-9)
    # mirror images sag alike
    assert hanging_sag(-50.0, -80.0, 150.0) == pytest.approx(hanging_sag(50.0, -80.0, 150.0))


def test_a_longer_strip_held_where_the_shorter_one_was_is_refused_not_folded():
    # issue 39: 150 mm held at the 100 mm strip's (50, -80) mm was released from a U and
    # printed a first period of 0.318 s without a word
    with pytest.raises(
        wc.SceneError, match=r"release.hold_x_mm: .* sags 26.2 mm below the held end .*\(74.73, -119.6\)"
    ):
        wc.load_scene("damped_swing", ["strip.free_length_mm=150"])
    # the position it suggests is taken, in any direction (level or above the clamp too,
    # where 0.94 of the length would still sag: it goes as far out as it must)
    wc.load_scene("damped_swing", ["strip.free_length_mm=150", "release.hold_x_mm=74.73", "release.hold_y_mm=-119.6"])
    for hold in ((80.0, 0.0), (30.0, 40.0), (-60.0, -30.0)):
        with pytest.raises(wc.SceneError) as refused:
            wc.load_scene("damped_swing", [f"release.hold_x_mm={hold[0]}", f"release.hold_y_mm={hold[1]}"])
        x, y = re.search(r"e\.g\. at \(([-\d.]+), ([-\d.]+)\) mm", str(refused.value)).groups()
        wc.load_scene("damped_swing", [f"release.hold_x_mm={x}", f"release.hold_y_mm={y}"])
