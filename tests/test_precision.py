"""float32 is offered only where it agrees with float64 (docs/model.md §9.4)."""

import numpy as np
import pytest
from conftest import overrides

import warpcloth as wc


@pytest.mark.parametrize("name, duration", [("damped_swing", 1.0), ("impulsive_rotation", 0.5)])
def test_float32_agrees_with_float64_at_the_default_dt(name, duration):
    # Measured at the scenes' default dt: the float32 tip path differs by 0.18 mm (swing,
    # 0.19 % of the motion) and 0.30 mm (rotation, 0.84 %), the swing period by 5e-6. At the paper's 1e-7 s a
    # float32 position update keeps only a few bits (docs/model.md §9.4), so float32 is documented
    # for the default dt only. Bound: 1 % of the tip's excursion.
    f64 = wc.simulate(wc.load_scene(name, overrides(run__duration_s=duration)))
    f32 = wc.simulate(wc.load_scene(name, overrides(run__duration_s=duration, integrator__precision="float32")))
    excursion = np.ptp(f64.probe("tip_x", 0))
    assert np.max(np.abs(f32.probe("tip_x", 0) - f64.probe("tip_x", 0))) < 0.01 * excursion
    if name == "damped_swing":
        p64 = wc.first_period(f64.t, f64.probe("laser_x", 0), 0.0)
        p32 = wc.first_period(f32.t, f32.probe("laser_x", 0), 0.0)
        assert p32 == pytest.approx(p64, rel=1e-3)
