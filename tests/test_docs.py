"""The user guide's scene reference covers every scene field (docs cannot silently drift),
and the README is the landing page that starts with the two commands."""

import dataclasses
import typing
from pathlib import Path

from warpcloth.scene import Scene

README = Path(__file__).resolve().parents[1] / "README.md"
GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide.md"


def test_every_scene_field_is_documented():
    text = GUIDE.read_text()
    missing = []
    for section, tp in typing.get_type_hints(Scene).items():
        for f in dataclasses.fields(tp):
            if f"{section}.{f.name}" not in text:
                missing.append(f"{section}.{f.name}")
    assert not missing, f"undocumented scene fields: {missing}"


def test_readme_starts_with_the_two_commands():
    lines = README.read_text().splitlines()
    assert lines[:4] == [
        "```bash",
        "pip install . && warpcloth run damped_swing",
        "pip install -e '.[test]' && pytest",
        "```",
    ]


def test_the_readme_is_a_landing_page():
    # install, the two commands, what it does, where the docs are: the reference lives in docs/
    text = README.read_text()
    assert len(text.splitlines()) < 120
    assert "docs/guide.md" in text and "## Documentation" in text


def test_every_sheet_scene_field_is_documented():
    # in the guide's own section for sheets; a [material] field is the strip's, documented there
    from warpcloth.scene.sheet import sheet_scene_fields

    text = GUIDE.read_text()
    section = text[text.index("### Sheet scene files") :]
    section = section[: section.index("\n## ")]
    missing = [
        name
        for name in sheet_scene_fields()
        if name not in section and not (name.startswith("material.") and name in text)
    ]
    assert not missing, f"undocumented sheet scene fields: {missing}"


def test_every_sheet_sweep_summary_column_is_documented():
    # the guide's table of a sheet sweep's summary names every column sheet_metrics gives
    import numpy as np
    from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS

    from warpcloth.metrics import sheet_metrics

    series = np.linspace(0.0, 1.0, 5)
    metrics = sheet_metrics(
        np.zeros((5, 1, 3)), series, (0.0, 0.0, 1.0), dict.fromkeys(SHEET_PROBE_FIELDS, series), series
    )
    text = GUIDE.read_text()
    section = text[text.index("### Sweeps of sheets") :]
    section = section[: section.index("\n## ")]
    columns = [name.replace("marker_0_", "marker_K_") for name in metrics]
    missing = [c for c in [*columns, "diverged_quantity", "reversal_overflows"] if f"`{c}`" not in section]
    assert not missing, f"undocumented sheet sweep summary columns: {missing}"
