"""The README's scene reference covers every scene field (docs cannot silently drift)."""

import dataclasses
import typing
from pathlib import Path

from warpcloth.scene import Scene

README = Path(__file__).resolve().parents[1] / "README.md"


def test_every_scene_field_is_documented():
    text = README.read_text()
    missing = []
    for section, tp in typing.get_type_hints(Scene).items():
        for f in dataclasses.fields(tp):
            if f"{section}.{f.name}" not in text:
                missing.append(f"{section}.{f.name}")
    assert not missing, f"undocumented scene fields: {missing}"


def test_readme_starts_with_the_two_commands():
    lines = README.read_text().splitlines()
    assert lines[:4] == ["```bash", "pip install . && warpcloth run damped_swing",
                         "pip install -e '.[test]' && pytest", "```"]
