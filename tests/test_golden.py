"""Refactor guard: today's code reproduces the saved golden outputs bitwise.

The goldens (tests/golden/, written by tests/golden/make_goldens.py, which says where each
came from) are the probes and frames of both bundled scenes, of forward Euler through a
divergence, float32, a cubic encoder table, a full tensile quartic with a wrapping hold,
and a small sweep's summaries. A change that is meant to
alter results regenerates them and says why in its commit; any other change must leave
every bit as it was (restructuring code is not allowed to reorder floating-point work).
"""

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

GOLDEN = Path(__file__).parent / "golden"
sys.path.insert(0, str(GOLDEN))
from make_goldens import CASES, SHEET_CASES, scene_outputs, sheet_outputs, sweep_summary  # noqa: E402
from warpcloth.kernels.exp_lanes import ENVIRONMENT  # noqa: E402

TURNING_POINT_COLUMNS = (
    "first_period_s",
    "first_amplitude_m",
    "mean_log_decrement",
    "half_cycle_amplitude_m",
    "log_decrement",
)
"""Summary columns read off turning points fitted by NumPy's ``lstsq`` (warpcloth/metrics.py):
OpenBLAS picks its kernel by the CPU it runs on (DYNAMIC_ARCH), and a Haswell kernel puts
the last bit of one amplitude elsewhere than the CPU the golden was written on (1.6e-16 of
it). The simulation's outputs stay bitwise; these are held to 4 ulps."""


@pytest.fixture(autouse=True)
def one_hinge_at_a_time(monkeypatch):
    """The goldens guard the arithmetic of a hinge at a time, which every device can take
    (kernels/exp_lanes.py); the CPU's groups of hinges differ from it by libmvec's
    rounding, within the tolerance tests/test_exp_lanes.py states."""
    monkeypatch.setenv(ENVIRONMENT, "1")


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("name", CASES)
def test_scene_is_bitwise_golden(name):
    expected = np.load(GOLDEN / f"{name}.npz")
    actual = scene_outputs(name)
    assert set(actual) == set(expected.files)
    for key, value in actual.items():
        assert same_bits(value, expected[key]), f"{name}: {key} differs from the golden output"


@pytest.mark.parametrize("name", SHEET_CASES)
def test_sheet_scene_is_bitwise_golden(name):
    expected = np.load(GOLDEN / f"{name}.npz")
    actual = sheet_outputs(name)
    assert set(actual) == set(expected.files)
    for key, value in actual.items():
        assert same_bits(value, expected[key]), f"{name}: {key} differs from the golden output"


def test_sweep_summary_is_bitwise_golden(tmp_path):
    expected = pd.read_parquet(GOLDEN / "sweep_summary.parquet")
    actual = sweep_summary(tmp_path / "sweep")
    actual = actual.reset_index(drop=True)
    pd.testing.assert_frame_equal(
        actual.drop(columns=list(TURNING_POINT_COLUMNS)),
        expected.drop(columns=list(TURNING_POINT_COLUMNS)),
        check_exact=True,
    )
    for column in TURNING_POINT_COLUMNS:  # per variant: a number, or a list of one per half cycle
        for a, e in zip(actual[column], expected[column], strict=True):
            np.testing.assert_array_max_ulp(np.asarray(a, float), np.asarray(e, float), maxulp=4)
    for column in expected.select_dtypes("number"):
        if column not in TURNING_POINT_COLUMNS:
            assert same_bits(actual[column].to_numpy(), expected[column].to_numpy()), column
