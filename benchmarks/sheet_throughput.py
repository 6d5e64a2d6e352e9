"""Node-steps per second of the woven sheet against the strip's, on the CPU (run by hand).

    python benchmarks/sheet_throughput.py [--sheets 32] [--sim-time 0.02]
                                          [--laws masing tagawa2003] [--precisions float64 float32]
                                          [--threads 1 2] [--repeats 3] [--only sheet|strip]

The sheet is a realistic one: a 50 mm square at 5 mm spacing in warp and weft (11 × 11
free nodes and one clamped row of cells, 132 nodes), the illustrative wool of every
scene along warp and weft with the law under test for bending, and the same law for
shear with the [shear] table's illustrative numbers (warpcloth/scene/shear.py), driven
by the impulsive rotation's clamp (a rotation about the weft, so every hinge and cell
moves from the first step). The baseline, measured in the same run and at the same
thread count, is the strip: the impulsive rotation scene's batch of as many strips
through warpcloth.strip.simulate_batch, its per-node rate strip-steps/s × nodes, over as
many node-steps as the sheet's run. Sheet and strip run in turn ``--repeats`` times; each
row prints both median per-node rates and the median of the pairwise ratios (robust to
the machine's drift); the thread table prints each one's scaling against one thread.
``--only`` runs one side, for timing whole processes against each other. Kernels are
compiled (and cached) before timing.

A sheet node costs more than a strip node because it carries more elements: an
interior node has 2 segments (2 nodes each), 2 hinges (3 line nodes and the 2 nodes of
the axis across, 5 each) and 1 cell (4 nodes), so 3 law evaluations and 2·2 + 2·5·2 +
1·4·2 = 32 three-vector force scatters per substep (bending and shear scatter an elastic
and a hysteretic part), against the strip's 1 segment and 1 hinge of 3 nodes: 1 law
evaluation and 2 + 3·2 = 8 two-vector scatters.
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
import warp as wp

import warpcloth as wc
from warpcloth import units
from warpcloth.core.runner import available_cores
from warpcloth.scene import ShearMaterial, build_batch
from warpcloth.sheet import (
    SheetBuilder,
    SheetClampMotion,
    SheetGeometry,
    SheetMaterialSI,
    SheetModel,
    SheetRecorder,
    SheetSolver,
    rectangle,
    simulate_sheets,
)
from warpcloth.strip import simulate_batch
from warpcloth.strip.model import init_warp_quietly

SIDE_MM = 50.0
SPACING_MM = 5.0
SHEAR_KES = {"hysteresis_d1_gf_per_cm": 0.8, "hysteresis_alpha_per_deg": 0.6, "hysteresis_phi0_deg": 8.0}
SHEAR_RIGIDITY_KES = 0.6  # G, gf/(cm·degree): the [shear] table's illustrative numbers


def square_sheet() -> SheetGeometry:
    """The 50 mm square at 5 mm, one row of cells held above the clamp edge."""
    h = SPACING_MM * units.LENGTH_MM
    return rectangle(SIDE_MM * units.LENGTH_MM, SIDE_MM * units.LENGTH_MM, h, (h, h))


def strip_scene(law: str, precision: str, sim_time: float) -> wc.Scene:
    """The impulsive rotation scene with ``law`` for bending, in ``precision``."""
    return wc.load_scene(
        "impulsive_rotation",
        [f"run.duration_s={sim_time}", f"integrator.precision={precision}", f"material.bending_law={law}"],
    )


def sheet_batch(
    law: str, precision: str, sheets: int, device: str = "cpu", sim_time: float = 0.02
) -> tuple[SheetModel, SheetSolver, SheetRecorder]:
    """``sheets`` copies of the 50 mm square sheet under the impulsive rotation's clamp, its
    bending and shear of ``law``, with the strip scene's dt and output interval."""
    scene = strip_scene(law, precision, sim_time)
    strip = build_batch([scene]).model.strips[0]
    g, shear = ShearMaterial(law, SHEAR_RIGIDITY_KES, SHEAR_KES).si()
    material = SheetMaterialSI(warp=strip.material, weft=strip.material, shear_rigidity=g, shear=shear)
    geometry = square_sheet()
    centre = (float(strip.rotation_centre[0]), float(strip.rotation_centre[1]), 0.0)
    builder = SheetBuilder(geometry, scene.run.gravity_m_per_s2)
    for _ in range(sheets):
        builder.add_sheet(material, damping=strip.damping, clamp=SheetClampMotion(strip.clamp, centre=centre))
    model = builder.finalize(device=device, precision=precision)
    recorder = SheetRecorder(scene.output_interval, scene.output.probes_per_frame, sim_time)
    return model, SheetSolver(model, scene.integrator.dt_s), recorder


def sheet_rate(law: str, precision: str, sheets: int, sim_time: float, threads: int, device: str = "cpu") -> float:
    """Sheet node-steps/s of a batch of ``sheets``, after a warm-up run of the same build."""
    for batch in (1, sheets):  # the first compiles
        model, solver, recorder = sheet_batch(law, precision, batch, device, sim_time)
        result = simulate_sheets(model, model.control(), solver, recorder, keep_frames=False, threads=threads)
    return result.node_steps / result.wall_time_s


def strip_rate(law: str, precision: str, strips: int, sim_time: float, threads: int) -> float:
    """Strip node-steps/s (strip-steps/s × nodes) of the impulsive rotation, ``strips`` at once."""
    scene = strip_scene(law, precision, sim_time)
    for batch in (1, strips):
        b = build_batch([scene] * batch, device="cpu")
        result = simulate_batch(b.model, b.control, b.solver, b.recorder, keep_frames=False, threads=threads)
    return result.strip_steps * scene.n_nodes / result.wall_time_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sheets", type=int, default=32, help="sheets (and strips) per batch")
    parser.add_argument("--sim-time", type=float, default=0.02, help="simulated seconds per sheet run")
    parser.add_argument("--laws", nargs="+", default=["masing", "tagawa2003"])
    parser.add_argument("--precisions", nargs="+", default=["float64"], choices=["float64", "float32"])
    parser.add_argument("--threads", type=int, nargs="+", default=sorted({1, available_cores()}))
    parser.add_argument("--repeats", type=int, default=3, help="sheet and strip runs in turn; medians are printed")
    parser.add_argument("--only", choices=["sheet", "strip"], help="run one side alone (to time whole processes)")
    args = parser.parse_args()
    init_warp_quietly()
    # the strip's run does as many node-steps as the sheet's, so both take about as long
    sheet_nodes = square_sheet().n_nodes
    strip_time = args.sim_time * sheet_nodes / strip_scene("masing", "float64", 0.01).n_nodes
    print(
        f"machine: {platform.processor() or platform.machine()}, {platform.system()}, "
        f"{available_cores()} cores, warp {wp.__version__}"
    )
    print(
        f"{args.sheets} sheets of {SIDE_MM:g} mm square at {SPACING_MM:g} mm ({sheet_nodes} nodes), "
        f"{args.sim_time} s simulated, against as many impulsive-rotation strips, {strip_time:.4f} s simulated; "
        f"medians of {args.repeats} runs each"
    )
    header = ("law", "precision", "threads", "sheet node-steps/s", "strip node-steps/s", "sheet/strip")
    print("{:11s} {:9s} {:>7} {:>19} {:>19} {:>11}".format(*header))
    scaling = []
    for law in args.laws:
        for precision in args.precisions:
            one = None
            for threads in args.threads:
                sheet, strip = [], []
                for _ in range(args.repeats):
                    if args.only != "strip":
                        sheet.append(sheet_rate(law, precision, args.sheets, args.sim_time, threads))
                    if args.only != "sheet":
                        strip.append(strip_rate(law, precision, args.sheets, strip_time, threads))
                a = float(np.median(sheet)) if sheet else np.nan
                b = float(np.median(strip)) if strip else np.nan
                ratio = float(np.median(np.array(sheet) / np.array(strip))) if sheet and strip else np.nan
                print(f"{law:11s} {precision:9s} {threads:>7} {a:19.3e} {b:19.3e} {ratio:10.3f}x")
                one = one or (threads, a, b)
                scaling.append((law, precision, threads, a / one[1], b / one[2], one[0]))
    print("\nthread scaling (median rate against the first thread count's, same law and precision)")
    for law, precision, threads, sheet, strip, base in scaling:
        print(f"{law:11s} {precision:9s} {threads:>2} vs {base} threads: sheet {sheet:.2f}x, strip {strip:.2f}x")


if __name__ == "__main__":
    main()
