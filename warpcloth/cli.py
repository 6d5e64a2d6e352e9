"""Command line: ``warpcloth run | sweep | export-usd | plot | render | fit | clamp | material``
(``--help`` on each)."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path

import warp as wp

from .analysis import first_period
from .errors import DivergenceError, SceneError
from .runner import simulate
from .scene import bundled_scenes, load_scene, scene_from_dict


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``warpcloth`` command; returns the exit status."""
    parser = argparse.ArgumentParser(prog="warpcloth", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run_p = sub.add_parser("run", help="simulate a scene and write a run directory")
    run_p.add_argument("scene", help=f"scene file, or a bundled scene: {', '.join(bundled_scenes())}")
    run_p.add_argument("--out", help="run directory (default: runs/<scene name>)")
    run_p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene field by dotted name, e.g. integrator.dt_s=1e-7")
    run_p.add_argument("--device", default=None, help="cpu or cuda (default: Warp's preferred device)")
    run_p.add_argument("--no-progress", action="store_true", help="no progress bar")
    run_p.add_argument("--usd", metavar="FILE", help="also export the run as a USD stage (.usd, .usda or .usdc)")
    sweep_p = sub.add_parser("sweep", help="run (or resume) the [sweep] of a scene into a sweep directory")
    sweep_p.add_argument("scene", help="scene file with a [sweep] section, or a bundled one")
    sweep_p.add_argument("--out", help="sweep directory (default: runs/<scene name>); rerun to resume")
    sweep_p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                         help="override a field of the base scene")
    sweep_p.add_argument("--max-batch", type=int, default=None,
                         help="strips per batch (default: from the memory per strip and the worker count)")
    sweep_p.add_argument("--workers", type=int, default=None,
                         help="local Dask worker processes (default: one per core; 0 = run in this process)")
    sweep_p.add_argument("--scheduler", default=None, help="address of a running Dask scheduler to use instead")
    sweep_p.add_argument("--device", default=None, help="cpu or cuda, on every worker")
    sweep_p.add_argument("--frames", action="store_true", help="also store shape frames (large)")
    sweep_p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_view_commands(sub)
    _add_fit_commands(sub)
    _add_material_commands(sub)
    args = parser.parse_args(argv)
    wp.config.log_level = logging.WARNING  # no init banner or module-load lines

    if args.command == "sweep":
        return _sweep(args)
    if args.command in COMMANDS:
        try:
            return COMMANDS[args.command](args)
        except SceneError as exc:
            print(f"warpcloth {args.command}: {exc}", file=sys.stderr)
            return 2
    try:
        scene = load_scene(args.scene, args.overrides)
    except SceneError as exc:
        print(f"warpcloth: error in scene: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    try:
        result = simulate(scene, device=args.device, out=out, progress=not args.no_progress)
    except DivergenceError as exc:
        print(f"warpcloth: {exc}\nRecorded up to the divergence: {out}", file=sys.stderr)
        return 3
    tip = result.probe("tip_x", 0)
    print(f"wrote {out}/ (probes.csv, frames.npy, frame_times.npy, scene.toml, meta.json)")
    print(f"{result.strip_steps:.3g} strip-steps in {result.wall_time_s:.2f} s "
          f"({result.strip_steps / result.wall_time_s:.3g} strip-steps/s)")
    print(f"final free end ({tip[-1] * 1e3:.2f}, {result.probe('tip_y', 0)[-1] * 1e3:.2f}) mm, "
          f"clamp angle {result.probe('clamp_angle', 0)[-1]:.4f} rad")
    if scene.release.enabled:
        period = first_period(result.t, result.probe("laser_x", 0), level=0.0)
        print(f"first swing period (laser line crossing x = 0): {period:.4f} s")
    if args.usd:
        from .recording import load_recording
        from .usd import export_usd

        print(f"wrote {export_usd(load_recording(out), args.usd)}")
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import load_sweep
    from .sweep_runner import run_sweep

    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    try:
        sweep = load_sweep(args.scene, args.overrides)
        summary = run_sweep(sweep, out, max_batch=args.max_batch, workers=args.workers, scheduler=args.scheduler,
                            device=args.device, frames=args.frames, progress=not args.no_progress)
    except SceneError as exc:
        print(f"warpcloth: error in sweep: {exc}", file=sys.stderr)
        return 2
    n_div = int(summary["diverged"].sum())
    print(f"wrote {out}/ ({len(summary)} variants: summary.csv, summary.parquet, probes/, variants.csv); "
          f"{n_div} diverged")
    return 0


def _add_view_commands(sub: argparse._SubParsersAction) -> None:
    def selection(p: argparse.ArgumentParser) -> None:
        p.add_argument("run_dir", metavar="RUN_DIR", help="a run directory, or a sweep directory run with --frames")
        p.add_argument("--variants", help="which variants: 3, 1,4,9 or 0:50 (default: all)")
        p.add_argument("--where", help="parameter filter: 'field OP value[,...]', e.g. 'damping.gamma_per_s<0.5'")

    usd_p = sub.add_parser("export-usd", help="write a run (or sweep variants) as an animated USD stage")
    selection(usd_p)
    usd_p.add_argument("-o", "--output", required=True, help="stage file: .usd or .usdc (binary), .usda (text)")
    usd_p.add_argument("--ribbon", action="store_true", help="also write each strip as a mesh of its real width")
    usd_p.add_argument("--frames-per-clip", type=int, default=None,
                       help="split frames into value-clip layers of this many frames (default: only when large)")
    plot_p = sub.add_parser("plot", help="PNG figures of a run, or a sweep metric against parameters")
    selection(plot_p)
    plot_p.add_argument("--out", help="figure directory (default: RUN_DIR/figures)")
    plot_p.add_argument("--measured", help="CSV of a measured displacement: t (s), x (mm); overlaid on amplitude.png")
    plot_p.add_argument("--times", type=float, nargs="+", help="shape-overlay times, s after release")
    plot_p.add_argument("--metric", help="sweep: summary column to plot (e.g. first_period_s)")
    plot_p.add_argument("--x", help="sweep: parameter on the x axis (a swept field, e.g. damping.gamma_per_s)")
    plot_p.add_argument("--y", help="sweep: second parameter (heat map)")
    render_p = sub.add_parser("render", help="3D PNG frames and an animation of a run (pyvista, off screen)")
    selection(render_p)
    render_p.add_argument("--out", help="image directory (default: RUN_DIR/render)")
    render_p.add_argument("--times", type=float, nargs="+", help="times of the PNG frames, s after release")
    render_p.add_argument("--movie", default="motion.gif", help="animation file name, .gif or .mp4; 'none' for none")
    render_p.add_argument("--stride", type=int, default=1, help="animate every n-th frame (at real speed)")


def _export_usd(args: argparse.Namespace) -> int:
    from .recording import load_recording
    from .usd import export_usd

    recording = load_recording(args.run_dir, args.variants, args.where)
    out = export_usd(recording, args.output, ribbon=args.ribbon, frames_per_clip=args.frames_per_clip)
    print(f"wrote {out} ({len(recording.variants)} variants, {len(recording.frame_times)} frames)")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from .plots import plot_run, plot_sweep, read_sweep_summary
    from .recording import load_recording

    out = Path(args.out or Path(args.run_dir) / "figures")
    if args.metric or args.x:
        if not (args.metric and args.x):
            raise SceneError("--metric", "a sweep plot needs both --metric and --x")
        out.mkdir(parents=True, exist_ok=True)
        name = f"{args.metric}_vs_{args.x}" + (f"_{args.y}" if args.y else "")
        path = plot_sweep(read_sweep_summary(args.run_dir), out / f"{name}.png", args.metric, args.x, args.y)
        print(f"wrote {path}")
        return 0
    recording = load_recording(args.run_dir, args.variants, args.where)
    for path in plot_run(recording, out, measured=args.measured, times=args.times):
        print(f"wrote {path}")
    return 0


def _render(args: argparse.Namespace) -> int:
    from .recording import load_recording
    from .render import render_run

    recording = load_recording(args.run_dir, args.variants, args.where)
    movie = None if args.movie == "none" else args.movie
    out = Path(args.out or Path(args.run_dir) / "render")
    for path in render_run(recording, out, times=args.times, movie=movie, stride=args.stride):
        print(f"wrote {path}")
    return 0


def _add_fit_commands(sub: argparse._SubParsersAction) -> None:
    fit_p = sub.add_parser("fit", help="fit free scene parameters to a measured motion (batched runs)")
    fit_p.add_argument("scene", help="scene file or bundled scene whose experiment was measured")
    fit_p.add_argument("--measured", required=True,
                       help="CSV: laser trace 't_s, x_mm' or tracked shapes 'frame, t_s, s_mm, x_mm, y_mm'")
    fit_p.add_argument("--free", required=True, help="parameters to fit, e.g. gamma,rotation_centre_dy_mm,D1 "
                       "(aliases: gamma D D1 alpha K0 density rotation_centre_dx_mm rotation_centre_dy_mm "
                       "hold_x_mm hold_y_mm; or any per-strip field by dotted name)")
    fit_p.add_argument("--bounds", help="name=LOW:HIGH,... (default: see README)")
    fit_p.add_argument("--align-start", type=float, default=0.0, metavar="SECONDS",
                       help="also fit a clock offset between measurement and simulation, within ± this")
    fit_p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                       help="override a field of the scene first")
    fit_p.add_argument("--out", help="fit directory (default: runs/fit-<scene name>)")
    fit_p.add_argument("--space-filling", type=int, default=None, help="variants in the first, space-filling batch")
    fit_p.add_argument("--max-iterations", type=int, default=25, help="local refinement launches at most")
    fit_p.add_argument("--seed", type=int, default=0, help="seed of the space-filling sample")
    fit_p.add_argument("--device", default=None, help="cpu or cuda")
    fit_p.add_argument("--no-progress", action="store_true", help="no progress bar")
    clamp_p = sub.add_parser("clamp", help="clamp motion tools")
    clamp_sub = clamp_p.add_subparsers(dest="clamp_command", required=True)
    angle_p = clamp_sub.add_parser("fit-angle", help="fit the quartic-then-line θ(t) to an encoder series")
    angle_p.add_argument("encoder", metavar="ENCODER", help="CSV 't_s, theta' (rad; deg if the header says deg)")
    angle_p.add_argument("--scene", required=True, help="scene to write the fitted motion into")
    angle_p.add_argument("-o", "--output", required=True, help="the new scene file (TOML)")
    angle_p.add_argument("--angle-unit", choices=("rad", "deg"), default=None, help="override the header's unit")
    angle_p.add_argument("--plot", help="also write a PNG of the encoder data and the fit")


def _fit(args: argparse.Namespace) -> int:
    from .fit import fit_motion, free_parameters, write_fit
    from .measured import read_measurement
    from .scene import apply_overrides, read_scene_file

    base = apply_overrides(read_scene_file(args.scene), args.overrides)
    base.pop("sweep", None)
    measurement = read_measurement(args.measured)
    free = free_parameters(args.free, scene_from_dict(base), args.bounds)
    out = Path(args.out or Path("runs") / f"fit-{Path(args.scene).stem}")
    fit = fit_motion(base, measurement, free, align_start_s=args.align_start, space_filling=args.space_filling,
                     max_iterations=args.max_iterations, seed=args.seed, device=args.device,
                     progress=not args.no_progress)
    write_fit(fit, base, measurement, out, args.device)
    print(f"RMS {fit.rms * 1e3:.4g} mm over {fit.n_residuals} residuals; {fit.launches} launches, "
          f"{fit.variants} variants, {fit.wall_time_s:.1f} s{'' if fit.converged else ' (iteration limit reached)'}")
    for name, value in fit.parameters.items():
        print(f"  {name} = {value:.6g} ± {fit.sigma[name]:.2g}")
    print(f"wrote {out}/ (best.toml reruns the best fit: warpcloth run {out / 'best.toml'})")
    return 0


def _clamp(args: argparse.Namespace) -> int:
    import tomli_w

    from .clamp_fit import fit_clamp_motion, scene_with_clamp_motion
    from .measured import read_encoder
    from .scene import read_scene_file

    t, theta = read_encoder(args.encoder, args.angle_unit)
    fit = fit_clamp_motion(t, theta)
    data = scene_with_clamp_motion(read_scene_file(args.scene), fit)
    data.pop("sweep", None)
    scene = scene_from_dict(data)  # validates before anything is written
    out = Path(args.output)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(tomli_w.dumps(scene.to_dict()))
    os.replace(tmp, out)
    print(f"encoder at rest {fit.theta0_rad:.4g} rad (the scene's θ is measured from it); "
          f"onset {fit.onset_s:.4f} s, quartic {fit.quartic_rad_per_s4:.5g} rad/s⁴ to {fit.break_s:.4f} s, "
          f"then {fit.speed_rad_per_s:.5g} rad/s to {fit.stop_s:.4f} s (slope jump at the break "
          f"{fit.slope_jump_rad_per_s:+.3g} rad/s); RMS {fit.rms_rad:.3g} rad over {fit.n_samples} samples")
    print(f"wrote {out}")
    if args.plot:
        from .plots import plot_clamp_fit

        print(f"wrote {plot_clamp_fit(t, theta, fit, Path(args.plot))}")
    return 0


def _add_material_commands(sub: argparse._SubParsersAction) -> None:
    material_p = sub.add_parser("material", help="material files: fit one to KES-FB data, list the bundled ones")
    material_sub = material_p.add_subparsers(dest="material_command", required=True)
    kes_p = material_sub.add_parser("fit-kes", help="fit a material file to a KES-FB1 tensile and a KES-FB2 "
                                    "bending loop (CSV, KES units)")
    kes_p.add_argument("--tensile", required=True, metavar="FB1.csv",
                       help="KES-FB1 loop: strain (%% or fraction) or extension (mm), force per width (gf/cm)")
    kes_p.add_argument("--bending", required=True, metavar="FB2.csv",
                       help="KES-FB2 loop: curvature (1/cm), moment per width (gf·cm/cm)")
    kes_p.add_argument("-o", "--output", required=True, help="the material file to write (.toml)")
    kes_p.add_argument("--density-g-per-cm2", type=float, default=None,
                       help="mass per area ρ_A (required: KES-FB1/FB2 data do not contain it)")
    kes_p.add_argument("--name", help="material name (default: the output file's stem)")
    kes_p.add_argument("--strain-unit", choices=("percent", "fraction", "mm"), default=None,
                       help="unit of the tensile file's first column when its header does not say "
                       "(default: percent if its maximum exceeds 1, else fraction)")
    kes_p.add_argument("--gauge-length-mm", type=float, default=None,
                       help="gauge length for extension in mm (default: 50, the KES-FB1 standard)")
    kes_p.add_argument("--divergence-strain", type=float, default=None,
                       help="T(ε) must increase up to this strain (default: the scenes' default, 0.25)")
    kes_p.add_argument("--plot", help="also write a PNG of the data against the fit")
    material_sub.add_parser("list", help="list the bundled materials and where their numbers come from")


def _material(args: argparse.Namespace) -> int:
    from . import kes
    from .scene import bundled_materials, read_material_file

    if args.material_command == "list":
        for name in bundled_materials():
            print(f"{name}: {read_material_file(name)['material']['source']}")
        return 0
    if args.density_g_per_cm2 is None:
        raise SceneError("--density-g-per-cm2", "the mass per area is not part of KES-FB1/FB2 data; weigh a "
                         "sample and give it in g/cm² (e.g. 2.03e-2 for MODEL.md's wool/nylon)")
    out = Path(args.output)
    if out.suffix != ".toml":
        raise SceneError("--output", f"{out} must end in .toml (scenes refer to material files by such a path)")
    max_strain = kes.DIVERGENCE_STRAIN if args.divergence_strain is None else args.divergence_strain
    if not max_strain > 0:
        raise SceneError("--divergence-strain", f"must be > 0, got {max_strain:g}")
    gauge = kes.KES_FB1_GAUGE_MM if args.gauge_length_mm is None else args.gauge_length_mm
    fit = kes.fit_kes(kes.read_tensile_csv(args.tensile, args.strain_unit, gauge), kes.read_bending_csv(args.bending),
                      max_strain)
    source = (f"fitted by warpcloth material fit-kes to {args.tensile} (KES-FB1) and {args.bending} (KES-FB2); "
              f"density {args.density_g_per_cm2:g} g/cm² given on the command line")
    data = kes.material_file_data(fit, args.name or out.stem, args.density_g_per_cm2, source, max_strain)
    print(f"tensile file's first column read as {fit.tensile_loop.strain_unit}")
    t, tk, b, bk = fit.tensile, fit.tensile_kes, fit.bending, fit.bending_kes
    rt = f", RT {tk.rt_percent:.1f} %" if tk.rt_percent is not None else " (no unloading branch: no RT)"
    print(f"tensile ({args.tensile}, {data['fit']['tensile_loading_points']} loading points): T(ε) = a1 ε + a2 ε² "
          f"+ a3 ε³ + a4 ε⁴, a = ({', '.join(f'{a:.6g}' for a in t.coefficients)}) gf/cm")
    print(f"  RMS {t.rms_gf_per_cm:.4g} gf/cm ({t.rms_relative:.3%} of the force range)")
    if t.note:
        print(f"  note: {t.note}")
    print(f"  KES: EMT {tk.emt_percent:.4g} %, WT {tk.wt_gf_cm_per_cm2:.4g} gf·cm/cm², LT {tk.lt:.4g}{rt} "
          f"(Fm {tk.fm_gf_per_cm:.4g} gf/cm)")
    print(f"bending ({args.bending}, {len(fit.bending_loop.curvature)} points): D {b.rigidity_gf_cm2_per_cm:.6g} "
          f"gf·cm²/cm, D1 {b.d1_gf_cm_per_cm:.6g} gf·cm/cm, α {b.alpha_cm:.6g} cm, K0 {b.k0_per_cm:.6g} 1/cm")
    print(f"  RMS {b.rms_gf_cm_per_cm:.4g} gf·cm/cm ({b.rms_relative:.3%} of the moment range)")
    if b.note:
        print(f"  note: {b.note}")
    kes_b = "n/a" if bk.b_gf_cm2_per_cm is None else f"{bk.b_gf_cm2_per_cm:.4g} gf·cm²/cm"
    kes_hb = "n/a" if bk.hb2_gf_cm_per_cm is None else f"{bk.hb2_gf_cm_per_cm:.4g} gf·cm/cm"
    print(f"  KES: B {kes_b}, 2HB {kes_hb}")
    print(f"wrote {kes.write_material_file(out, data)} (a scene uses it with from_file = \"{out}\" in its "
          f"[material], or --set material.from_file={out})")
    if args.plot:
        print(f"wrote {kes.plot_kes_fit(fit, args.plot)}")
    return 0


COMMANDS = {"export-usd": _export_usd, "plot": _plot, "render": _render, "fit": _fit, "clamp": _clamp,
            "material": _material}


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
