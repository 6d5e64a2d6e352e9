"""One contract, both bodies: the strip and the sheet run in the core's one loop
(warpcloth/core), so every promise the runner makes is tested over both. The drifts the
two copies had before issue 37 (a divergence's kept sample, ``threads < 1``, the steps
counted, the reversal memory's default) each have a test here that fails on either body.
"""

import json

import numpy as np
import pytest
from warpcloth.kernels import STATUS_BUDGET, STATUS_STRAIN
from warpcloth.kernels.bending_masing import DEFAULT_CAPACITY
from warpcloth.kernels.force_terms import LinearDrag, RigidFloor

import warpcloth as wc
from warpcloth import bodies
from warpcloth.core.divergence import DivergenceMonitor
from warpcloth.core.runner import simulate_batch
from warpcloth.sheet import SheetDivergence
from warpcloth.strip import Divergence

SCENES = {
    "strip": ("impulsive_rotation", ["run.duration_s=0.06"]),
    "sheet": (
        "shear_swing",
        ["run.duration_s=0.06", "release.settle_time_s=0.01", "sheet.spacing_warp_mm=10", "sheet.spacing_weft_mm=10"],
    ),
}
PER_THREAD = {"strip": 8, "sheet": 4}  # the solvers' bodies_per_thread: a split needs two ranges of them


@pytest.fixture(params=list(SCENES))
def body(request):
    return request.param


def scene(body, *more):
    name, overrides = SCENES[body]
    return wc.load_scene(name, [*overrides, *more])


def test_every_body_has_every_hook_and_each_resolves():
    for body in bodies.BODIES.values():
        assert set(body.hooks) == set(bodies.HOOKS), body.name
        for hook in bodies.HOOKS:
            assert body.hook(hook) is not None, (body.name, hook)


def test_either_body_loads_runs_streams_and_names_itself(body, tmp_path):
    s = scene(body)
    assert bodies.of_scene(s).name == body
    out = tmp_path / "run"
    result = wc.simulate(s, out=out, threads=1)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["kind"] == body and meta["complete"] and result.body == body
    assert bodies.of_run(out).name == body
    assert meta["body_steps"] == result.body_steps and meta["node_steps"] == result.node_steps
    assert bodies.named(body)("read_run", out) is not None  # its own reader takes it back


def test_a_batch_mixing_bodies_is_refused():
    with pytest.raises(wc.ArgumentError, match="scenes: a batch is of one body; these mix sheet and strip"):
        wc.simulate([scene("strip"), scene("sheet")])


def test_the_thread_count_changes_no_bit(body):
    n = 2 * PER_THREAD[body]
    batch = [scene(body, f"damping.gamma_per_s={0.05 + 0.05 * i}") for i in range(n)]
    one = wc.simulate(batch, threads=1)
    two = wc.simulate(batch, threads=2)
    assert one.probes.tobytes() == two.probes.tobytes()
    assert one.frames.tobytes() == two.frames.tobytes()
    assert all(one.tables[k].tobytes() == two.tables[k].tobytes() for k in one.tables)


@pytest.mark.parametrize("threads", [0, -1])
def test_threads_below_one_are_one_argument_error_for_both(body, threads):
    with pytest.raises(wc.ArgumentError, match=f"threads: must be at least 1, got {threads}"):
        wc.simulate(scene(body), threads=threads)


def test_a_stop_keeps_the_sample_of_its_step_alike_for_both_bodies():
    """A strain stop is caught before the step that would make it: the sample at its step is
    the last good one, for a sheet as for a strip (the sheet dropped it before issue 37); a
    budget stop loses it."""

    class Model:
        probes = None
        n_bodies = 2

        def budget_floor(self):
            return np.ones(2)

    from warpcloth.kernels.probes import STRIP_PROBES

    Model.probes = STRIP_PROBES
    steps = np.array([10, 20, 30, 40])
    strip = dict(phase="record", quantity="", where=0, value=0.0, limit=0.25, scheme="", advice="")
    for code, keeps in ((STATUS_STRAIN, True), (STATUS_BUDGET, False)):
        reports = [
            Divergence(strip=1, code=code, step=30, time_s=0.0, precision="float64", dt_s=1e-5, **strip),
            SheetDivergence(sheet=1, code=code, step=30, time_s=0.0, element=0, value=0.0, dt_s=1e-5, stable_step_s=1),
        ]
        for report in reports:
            monitor = DivergenceMonitor(Model(), None, None)
            monitor.diverged = [report]
            valid = monitor.valid(steps)
            assert valid[:, 0].all(), type(report).__name__
            assert list(valid[:, 1]) == [True, True, keeps, False], type(report).__name__


def diverging(body):
    """A batch of two in which variant 1 stops after t = 0: a strip whose clamp turns a
    thousand times faster overstretches, a sheet jerked sideways shears a cell past 10°."""
    if body == "strip":
        wild = "clamp.segments=[{t_start_s=0.0, t_end_s=0.05, theta_coefficients_si=[0.0, 0.0, 0.0, 0.0, 3.2e7]}]"
        return [scene("strip"), scene("strip", wild)]
    jerk = "clamp.translation_segments=[{t_start_s = 0.0, t_end_s = 0.05, d_coefficients_mm = [0.0, 0.0, 40000.0]}]"
    calm = "clamp.translation_segments=[{t_start_s = 0.0, t_end_s = 0.05, d_coefficients_mm = [0.0, 0.0, 400.0]}]"
    limit = "integrator.divergence_shear_deg=10"
    return [scene("sheet", calm, limit, "run.duration_s=0.1"), scene("sheet", jerk, limit, "run.duration_s=0.1")]


def test_a_diverged_body_keeps_its_samples_to_its_stop_and_counts_its_own_steps(body):
    result = wc.simulate(diverging(body), on_divergence="record", threads=1)
    (report,) = result.diverged
    assert report.body == 1 and report.time_s >= 0
    finite = np.isfinite(result.probes[:, 0, 1])
    kept = result.t < report.time_s if report.sample_lost else result.t <= report.time_s
    assert np.array_equal(finite, kept) and kept.any() and not kept.all()
    assert np.isfinite(result.probes[:, 0, 0]).all()  # the other runs to the end
    # each body's own steps: the stopped one's to its stop, not to the end of the run
    full = result.body_steps - report.step
    assert report.step < full and result.body_steps == full + report.step
    text = report.describe()
    assert "\n" not in text and f"{'strip' if body == 'strip' else 'sheet'} 1 diverged" in text
    assert report.as_dict()["step"] == report.step


def test_the_reversal_memory_default_is_the_laws_for_both():
    assert scene("strip").integrator.reversal_memory == DEFAULT_CAPACITY
    assert scene("sheet").integrator.reversal_memory == DEFAULT_CAPACITY


def run_with_terms(body, terms, *more):
    batch = bodies.named(body)("build", [scene(body, *more)], None, terms)
    return simulate_batch(batch.model, batch.control, batch.solver, batch.recorder, threads=1)


def budget_drift(result):
    total = result.energy_total()[:, 0]
    scale = np.nanmax(result.probe("kinetic", 0))
    return float(np.nanmax(np.abs(total - total[0])) / scale)


def test_a_force_term_is_one_place_and_its_channel_closes_the_budget(body):
    """Linear drag −r m v is the bodies' own damping γ = r as a term of its own: the motion
    is the damped one to rounding, the work against it is the damping's, and the budget
    closes only with the term's channel in it. (The drag acts while a sheet settles too,
    so its settling damping is lower by r.)"""
    rate = 2.0
    damped = run_with_terms(body, (), f"damping.gamma_per_s={rate}")
    settle = [f"release.settle_damping_per_s={20.0 - rate}"] if body == "sheet" else []
    dragged = run_with_terms(body, (LinearDrag(rate),), "damping.gamma_per_s=0", *settle)
    assert dragged.probe_set.fields[-1] == "drag_work" and dragged.probe_set.fields[:-1] == damped.probe_set.fields
    np.testing.assert_allclose(dragged.frames, damped.frames, rtol=0, atol=1e-12)
    work = damped.probe("damping_work", 0)
    np.testing.assert_allclose(dragged.probe("drag_work", 0), work, rtol=1e-9, atol=1e-12 * work.max())
    assert np.all(dragged.probe("damping_work", 0) == 0)
    assert budget_drift(dragged) < 1e-3
    without = dragged.energy_total()[:, 0] - dragged.probe("drag_work", 0)
    assert np.nanmax(np.abs(without - without[0])) > 100 * np.nanmax(np.abs(dragged.energy_total()[:, 0] - without[0]))


def test_a_rigid_floor_holds_the_strip_and_its_work_closes_the_budget():
    """The strip's free end swings down onto a floor 5 mm above its hanging tip: the floor
    holds it within the penetration its stiffness allows (g/ω² at rest, 2.5e-7 m at
    ω = 1e4 rad/s; a few µm at impact), and the energy its spring holds and returns closes
    the budget, to an error that halves with dt (first order: the contact force has a
    kink at the surface, which the centred work rule integrates to O(dt))."""
    free = wc.load_scene("damped_swing").strip.free_length_mm * 1e-3
    height = -(free - 0.005)
    floor = RigidFloor(height=height, omega=1e4)
    drift = []
    for dt in (1e-5, 5e-6):
        s = wc.load_scene("damped_swing", ["run.duration_s=0.3", f"integrator.dt_s={dt}"])
        batch = bodies.named("strip")("build", [s], None, (floor,))
        result = simulate_batch(batch.model, batch.control, batch.solver, batch.recorder, threads=1)
        assert result.probe_set.fields[-1] == "floor_work"
        assert np.nanmax(result.probe("floor_work", 0)) > 0
        lowest = np.nanmin(result.frames[..., 1])
        assert height - 2e-5 < lowest < height  # pressed in by less than 0.02 mm
        drift.append(budget_drift(result))
    assert drift[0] < 2e-3 and 1.6 < drift[0] / drift[1] < 2.6, drift


def test_each_force_term_compiles_to_a_kernel_of_its_own():
    """Warp caches a kernel by a hash of its code; two configurations that differ only in
    their force terms (or a term's constants) must never share one (a loop's wp.static
    lookup is not hashed, so the terms are chained by name: kernels/force_terms.py)."""
    import warp as wp
    from warpcloth.kernels import build_strip

    configurations = [(), (LinearDrag(2.0),), (RigidFloor(-0.095, 2e3),), (RigidFloor(-0.095, 1e4),)]
    hashes = {build_strip(wp.float64, "semi_implicit", t).advance.module.hash_module() for t in configurations}
    assert len(hashes) == len(configurations)


def test_an_edited_law_changes_the_kernels_hash(monkeypatch):
    """The laws' dispatch names each law's functions (kernels/laws.py), so Warp's kernel
    hash, and with it the kernel cache, sees a change to any law, not only the first: a
    loop's wp.static lookup, which the dispatch used before, is not hashed."""
    import dataclasses

    import warp as wp
    from warpcloth.kernels import laws

    def follow_hash(law_list):
        monkeypatch.setattr(laws, "LAWS", law_list)
        dispatch = laws.build.__wrapped__(wp.float64)  # past the cache: a dispatch of these laws
        Parameters, Memory, History = dispatch.Parameters, dispatch.Memory, dispatch.History
        follow = dispatch.follow

        @wp.kernel(module="unique")
        def probe(p: wp.array(dtype=Parameters), m: wp.array(dtype=Memory), history: History):
            m[0] = follow(wp.float64(1.0), m[0], p[0], history, 0, 0)

        return probe.module.hash_module()

    original = laws.LAWS
    # the last law built as the first one is: same count, same names, other code
    edited = (*original[:-1], dataclasses.replace(original[-1], build=original[0].build))
    assert follow_hash(original) != follow_hash(edited)


SWEEPS = {
    "strip": ("damped_swing_sweep", ["sweep.random.samples=4", "run.duration_s=0.05", "release.settle_time_s=0.01"]),
    "sheet": ("shear_swing_sweep", ["run.duration_s=0.05", "release.settle_time_s=0.02"]),
}


def test_a_run_directory_holds_a_batch_of_either_body(body, tmp_path):
    out = tmp_path / "batch"
    batch = [scene(body, f"damping.gamma_per_s={g}") for g in (0.1, 0.5)]
    result = wc.simulate(batch, out=out, threads=1)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["kind"] == body and sorted(p.name for p in (out / "variants").iterdir()) == ["0000.toml", "0001.toml"]
    assert np.load(out / "frames.npy").shape[1] == 2
    run = bodies.of_run(out)("read_run", out)
    assert run.complete and len(run.probes) == 2 * len(result.t)  # one row per (t, variant)


def test_an_interrupted_run_of_either_body_reads_as_incomplete(body, tmp_path, monkeypatch):
    from warpcloth.io.run_dir import StreamedRun

    original = StreamedRun.write_frames

    def interrupt_after_the_first(self, first, frames):
        original(self, first, frames)
        raise KeyboardInterrupt

    monkeypatch.setattr(StreamedRun, "write_frames", interrupt_after_the_first)
    out = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):
        wc.simulate(scene(body), out=out, threads=1)
    assert json.loads((out / "meta.json").read_text())["complete"] is False
    run = bodies.of_run(out)("read_run", out)
    assert not run.complete and len(run.probes) > 0 and np.isfinite(run.probes.to_numpy()).all()


def test_a_resumed_sweep_of_either_body_gives_the_same_summary(body, tmp_path):
    import shutil

    import pandas as pd

    name, overrides = SWEEPS[body]
    reference = tmp_path / "whole"
    whole = wc.run_sweep(wc.load_sweep(name, overrides), reference, workers=0, max_batch=2)
    resumed = tmp_path / "resumed"
    shutil.copytree(reference, resumed)
    # what a kill after the first batch leaves: the others' summaries never written, nothing merged
    for batch in sorted((resumed / "summary").glob("batch-*.parquet"))[1:]:
        batch.unlink()
    for merged in ("summary.parquet", "summary.csv"):
        (resumed / merged).unlink()
    again = wc.run_sweep(wc.load_sweep(name, overrides), resumed, workers=0, max_batch=2)
    pd.testing.assert_frame_equal(again, whole, check_exact=True)
    assert json.loads((resumed / "sweep.json").read_text())["kind"] == body


def test_a_healthy_run_of_either_body_closes_its_budget(body):
    """The budget derived from the probes' descriptions stays within 1e-3 of the peak
    kinetic energy on a healthy run of either body (docs/model.md §10)."""
    result = wc.simulate(scene(body), threads=1)
    assert budget_drift(result) < 1e-3


def test_a_run_writer_refuses_a_model_whose_probes_it_has_no_columns_for(body, tmp_path):
    """A run directory stores the body's own probes: a model with a force term's channel is
    refused before it runs, instead of writing rows wider than their header."""
    from warpcloth.io.run_dir import RunWriter
    from warpcloth.io.sheet_run_dir import SheetRunWriter

    s = scene(body)
    batch = bodies.named(body)("build", [s], None, (LinearDrag(1.0),))
    frame_times = batch.recorder.schedule(batch.control, batch.solver).frame_times
    if body == "strip":
        sink = RunWriter(tmp_path / "run", [s], batch.model.n_nodes, frame_times)
    else:
        sink = SheetRunWriter(tmp_path / "run", [s], batch.model.geometry, batch.recorder.markers, frame_times)
    with pytest.raises(wc.ArgumentError, match="sink: its probe table has columns for .* drag_work"):
        simulate_batch(batch.model, batch.control, batch.solver, batch.recorder, sink=sink, threads=1)
