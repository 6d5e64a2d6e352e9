"""The public API type-checks: mypy on the modules below is clean (configuration in
pyproject.toml, [tool.mypy]; what they import is read, not reported on). Its cache lives
under the system's temporary directory, so a rerun takes seconds."""

import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODULES = [
    "warpcloth/errors.py",
    "warpcloth/metrics.py",
    "warpcloth/runs.py",
    "warpcloth/sweeps.py",
    "warpcloth/cli/flags.py",
    "warpcloth/calibrate/motion_fit",
    "warpcloth/viz/plots.py",
    "warpcloth/viz/figures",
    "warpcloth/viz/usd.py",
]
"""The public API checked: errors, the swing metrics, simulate/run, run_sweep, the
argument → option map, the motion fit, the figures (whose protocols type the fit and KES
results they draw) and the USD export."""


def test_the_public_api_type_checks():
    cache = Path(tempfile.gettempdir()) / "warpcloth-mypy-cache"
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--cache-dir", str(cache), *MODULES],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr
