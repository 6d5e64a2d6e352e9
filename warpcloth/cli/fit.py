"""``warpcloth fit`` and ``warpcloth clamp fit-angle``: calibrate against measured motion."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from warpcloth.calibrate.motion_fit.report import FitResult
from warpcloth.calibrate.noise import POOR_FIT_FACTOR
from warpcloth.errors import OptionError
from warpcloth.scene import scene_from_dict

from .options import (
    EXIT_FIT_STATUS,
    add_device,
    add_no_progress,
    add_overrides,
    add_overwrite,
    at_least,
    figure_path,
    new_file,
    new_result,
    non_negative,
    path_text,
    positive,
)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``fit`` and ``clamp fit-angle``."""
    fit_p = sub.add_parser("fit", help="fit free scene parameters to a measured motion (batched runs)")
    fit_p.add_argument("scene", help="scene file or bundled scene whose experiment was measured")
    fit_p.set_defaults(handler=fit_command)
    fit_p.add_argument(
        "--measured",
        required=True,
        help="CSV: laser trace 't_s, x_mm' or tracked shapes 'frame, t_s, s_mm, x_mm, y_mm'; for a sheet "
        "scene, tracked sheet markers headed 't_s, marker' and one to three of 'x_mm, y_mm, z_mm'",
    )
    fit_p.add_argument(
        "--free",
        required=True,
        help="parameters to fit, e.g. gamma,rotation_centre_dy_mm,D1 "
        "(aliases: gamma D D1 alpha K0 density rotation_centre_dx_mm rotation_centre_dy_mm "
        "hold_x_mm hold_y_mm; or any per-strip field by dotted name; a sheet scene: gamma G D D_weft "
        "density centre_dx_mm centre_dy_mm centre_dz_mm, or any per-sheet field, e.g. "
        "shear.hysteresis_d1_gf_per_cm)",
    )
    fit_p.add_argument(
        "--bounds",
        help="name=LOW:HIGH,... (default: a rotation centre or hold position ± 10 mm "
        "around the scene's value; gamma 0 to max(4× the scene's, 2 /s); a hysteresis amplitude D1, Ms "
        "or Mf 0 to 4×; any other ¼× to 4×; a parameter that is 0 in the scene needs its bounds)",
    )
    fit_p.add_argument(
        "--align-start",
        type=non_negative,
        default=0.0,
        metavar="SECONDS",
        help="also fit a clock offset between measurement and simulation, within ± this (default: 0, the clocks agree)",
    )
    add_overrides(fit_p, "a field of the scene first")
    fit_p.add_argument("--out", type=path_text, help="fit directory (default: runs/fit-<scene name>)")
    fit_p.add_argument(
        "--space-filling",
        type=at_least(0),
        default=None,
        help="variants in the first, space-filling batch (default: max(16, 8 × the free parameters))",
    )
    fit_p.add_argument(
        "--max-iterations", type=at_least(0), default=25, help="local refinement launches at most (default: 25)"
    )
    fit_p.add_argument("--seed", type=at_least(0), default=0, help="seed of the space-filling sample (default: 0)")
    fit_p.add_argument(
        "--bootstrap",
        type=at_least(0),
        default=0,
        metavar="N",
        help="also a moving-block bootstrap σ from N resamples, for time-correlated errors (default: 0, none)",
    )
    fit_p.add_argument(
        "--noise",
        type=positive,
        default=None,
        metavar="MM",
        help="measurement noise σ in mm the RMS is judged against (default: estimated from the data)",
    )
    fit_p.add_argument(
        "--at-spacing",
        action="store_true",
        help="report the values fitted at the scene's spacing, without the continuum estimate "
        "(default: extrapolated to h → 0 from runs at 2h, h/2 and, if needed, h/4, the mesh's "
        "share in σ); such values are the mesh's as much as the fabric's: status spacing_limited (exit 9)",
    )
    fit_p.add_argument("--check-spacing", action="store_true", help=argparse.SUPPRESS)  # gone: said so below
    add_device(fit_p)
    add_no_progress(fit_p)
    add_overwrite(fit_p, "fit directory --out")
    clamp_p = sub.add_parser("clamp", help="clamp motion tools")
    clamp_sub = clamp_p.add_subparsers(dest="clamp_command", required=True)
    angle_p = clamp_sub.add_parser("fit-angle", help="fit rest, a quartic, lines and a stop to an encoder series")
    angle_p.set_defaults(handler=clamp_fit_angle_command)
    angle_p.add_argument("encoder", metavar="ENCODER", help="CSV 't_s, theta' (rad, or the header's unit: theta_deg)")
    angle_p.add_argument("--scene", required=True, help="scene to write the fitted motion into")
    angle_p.add_argument("-o", "--output", type=path_text, required=True, help="the new scene file (TOML)")
    angle_p.add_argument(
        "--angle-unit",
        choices=("rad", "deg"),
        default=None,
        help="override the header's unit (default: the header's, else rad)",
    )
    angle_p.add_argument("--plot", help="also write a PNG of the encoder data and the fit")
    angle_p.add_argument(
        "--accept",
        action="store_true",
        help=f"exit 0 even when the fit is poor (RMS above {POOR_FIT_FACTOR:g}× the encoder's noise)",
    )
    add_overwrite(angle_p, "scene file -o")


def fit_command(args: argparse.Namespace) -> int:
    """Fit the free parameters and write the fit directory."""
    from warpcloth import bodies
    from warpcloth.calibrate.motion_fit import fit_motion, write_fit
    from warpcloth.io.measured import bundled_data
    from warpcloth.io.provenance import file_checksum
    from warpcloth.scene import apply_overrides, load_scene, read_scene_file

    if args.check_spacing:
        raise OptionError(
            "--check-spacing",
            "is gone: every fit now runs its best point at 2h and h/2 and reports the values extrapolated to "
            "h → 0, the mesh's share in σ (--at-spacing skips that)",
        )
    base = apply_overrides(read_scene_file(args.scene), args.overrides)
    base.pop("sweep", None)
    # a bad field is named with its file and line, or --set (a sweep's own options do not apply to a fit)
    scene = load_scene(args.scene, [o for o in args.overrides if not o.strip().startswith("sweep.")])
    body = bodies.of_scene(scene)  # a strip is fitted to a laser trace or shapes, a sheet to its markers
    measurement = body("read_measurement", args.measured, argument="--measured")
    free = body("free_parameters", args.free, scene, args.bounds)
    out = new_result(args.out or Path("runs") / f"fit-{Path(args.scene).stem}", args.overwrite, "--out")
    fit = fit_motion(
        base,
        measurement,
        free,
        align_start_s=args.align_start,
        space_filling=args.space_filling,
        max_iterations=args.max_iterations,
        seed=args.seed,
        device=args.device,
        progress=not args.no_progress,
        noise=None if args.noise is None else args.noise * 1e-3,
        bootstrap=args.bootstrap,
        continuum=not args.at_spacing,
    )
    inputs = {
        "scene": str(args.scene),
        "overrides": args.overrides,
        "measured": file_checksum(bundled_data(args.measured)),
        "free": [p.field for p in free],
        "align_start_s": args.align_start,
        "space_filling": args.space_filling,
        "max_iterations": args.max_iterations,
        "seed": args.seed,
        "bootstrap": args.bootstrap,
        "at_spacing": args.at_spacing,
    }
    write_fit(fit, base, measurement, out, args.device, inputs)
    at_h = (
        f" on the finest level's mesh, h = {next(iter(fit.spacing.values())):g} mm (at the scene's spacing "
        f"{fit.rms_at_spacing * 1e3:.4g} mm; extrapolated to h → 0 {fit.continuum['rms_extrapolated_mm']:.4g} mm)"
        if fit.sigma_mesh
        else ""
    )
    mesh_share = f"; the mesh's share of the RMS {fit.rms_mesh * 1e3:.3g} mm" if fit.rms_mesh else ""
    print(
        f"RMS {fit.rms * 1e3:.4g} mm{at_h} over {fit.n_residuals} residuals (noise {fit.noise * 1e3:.3g} mm, "
        f"{fit.noise_source}{mesh_share}); {fit.launches} launches, {fit.variants} variants, {fit.wall_time_s:.1f} s"
    )
    print(continuum_line(fit))
    for name, value in fit.parameters.items():
        boot = (
            f" (block bootstrap ± {fit.sigma_bootstrap[name]:.2g}, blocks of {fit.bootstrap_block})"
            if fit.sigma_bootstrap
            else ""
        )
        if fit.sigma_frames and fit.sigma_frames[name] > fit.sigma_gauss_newton[name]:
            boot += (
                f" (its noise share robust to the errors a frame's points share: Gauss–Newton's alone "
                f"± {fit.sigma_gauss_newton[name]:.2g})"
            )
        shares = (
            f" (noise {fit.sigma_noise[name]:.2g}, mesh {fit.sigma_mesh[name]:.2g}; at the scene's spacing "
            f"{fit.at_spacing[name]:.6g})"
            if fit.sigma_mesh
            else ""
        )
        print(
            f"  {name} = {value:.6g} ± {fit.sigma[name]:.2g}{shares}{boot}"
            f"{'  (on a bound)' if name in fit.at_bound else ''}"
        )
    for other in fit.other_minima:
        where = ", ".join(f"{k} = {v:.5g}" for k, v in other.items() if not k.endswith("rms_mm"))
        print(
            f"note: the space-filling stage also found a separate basin at {where} (RMS {other['rms_mm']:.4g} mm "
            f"there, a ridge of {other['ridge_rms_mm']:.4g} mm between); the result above refined the lowest"
        )
    if fit.mesh_note:
        print(f"note: {fit.mesh_note}")
    print(f"status: {fit.status}")
    print(f"wrote {out}/ (best.toml reruns the best fit: warpcloth run {out / 'best.toml'})")
    if fit.status != "converged":
        print(
            f"warpcloth fit: not a fit ({fit.status}): " + "; ".join(fit.problems) + " — the values and σ above "
            "are not estimates to report (fit.json has status and problems)",
            file=sys.stderr,
        )
    return EXIT_FIT_STATUS[fit.status]


def continuum_line(fit: FitResult) -> str:
    """What the fit's values are the limit of: the levels, the observed order and the method."""
    c = fit.continuum
    spacing = ", ".join(f"{name} = {value:g}" for name, value in c.get("fitted_at_mm", fit.spacing).items())
    if c.get("status") == "extrapolated":
        orders = "; ".join(
            f"{o['order']:.2f} from h = {'/'.join(f'{h:g}' for h in o['levels_mm'])} mm" for o in c["observed_orders"]
        )
        pair = "/".join(f"{h:g}" for h in c["extrapolated_from_mm"])
        return (
            f"continuum limit h → 0 (fitted at {spacing}; observed order {orders}, the law's {c['law_order']:g}; "
            f"extrapolated from h = {pair} mm, {c['runs']} runs, {c['wall_time_s']:.1f} s"
            + (f"; {c['note']}" if c["note"] else "")
            + "); ± is σ_total = √(σ_noise² + σ_mesh²):"
        )
    return f"at {spacing} (not the continuum limit: the status says why):"


def clamp_fit_angle_command(args: argparse.Namespace) -> int:
    """Fit θ(t) to an encoder series and write a scene with that clamp motion."""
    import tomli_w

    from warpcloth.calibrate.clamp_fit import fit_clamp_motion, parameter_uncertainties, scene_with_clamp_motion
    from warpcloth.calibrate.uncertainty import DETERMINED_CORRELATION, DETERMINED_SIGMAS
    from warpcloth.io.atomic import write_text_atomically
    from warpcloth.io.measured import read_encoder
    from warpcloth.scene import load_scene, read_scene_file
    from warpcloth.scene.step import AUTO

    until = load_scene(args.scene).run.duration_s  # a bad field is named with its file and line
    out = new_file(args.output, args.overwrite, "-o")
    plot = figure_path(args.plot, args.overwrite) if args.plot else None
    t, theta = read_encoder(args.encoder, args.angle_unit, argument="ENCODER")
    fit = fit_clamp_motion(t, theta)
    raw = read_scene_file(args.scene)
    data = scene_with_clamp_motion(raw, fit, until_s=until)
    data.pop("sweep", None)
    scene = scene_from_dict(data)  # validates before anything is written
    written = scene.to_dict()
    if scene.integrator.dt_chosen_by == AUTO:  # a fit of this scene chooses its own step over its box
        written["integrator"].update(dt_s=AUTO, dt_chosen_by="scene")
    write_text_atomically(out, tomli_w.dumps(written))
    end = (
        f"stopped at {fit.stop_s:.4f} s"
        if fit.stop_s is not None
        else f"still moving at the end of the record ({t[-1]:.4f} s): the scene continues the last line to "
        f"{scene.run.duration_s:g} s (run.duration_s)"
    )
    print(
        f"form: {fit.form} (lowest BIC; RMS of each form: "
        + ", ".join(f"{f} {r:.3g} rad" for f, r in fit.candidates.items())
        + f"); {end}"
    )
    start = (
        f"moving from the first sample ({fit.onset_s:.4f} s, the onset there), θ0 fitted: the record has no rest "
        "before the motion"
        if fit.moving_at_start
        else "θ0 is the encoder at rest, the mean before the onset"
    )
    # What is determined is the curve; its parameters only where their σ says so (issue 40:
    # an onset of 8 ms and a4 = 6213 against a true 0 and 3.2e4 were printed as if measured).
    print(
        f"determined: θ(t) itself, within the noise (RMS {fit.rms_rad:.3g} rad over {fit.n_samples} samples, "
        f"noise {fit.noise_rad:.2g} rad, {fit.noise_source}); the scene's θ is measured from θ0; {start}"
    )
    print(
        f"its parameters, ± 1σ from the fit's Jacobian scaled by the residual RMS (not determined: within "
        f"{DETERMINED_SIGMAS:g}σ of 0, or trading with the others beyond a multiple correlation of "
        f"{DETERMINED_CORRELATION:g}):"
    )
    for value in parameter_uncertainties(fit, t, theta):
        print(f"  {value.text()}")
    turned = float(fit.theta(0.0)[0] - fit.rest_rad)
    if fit.moving_at_start and fit.onset_s < 0 and abs(turned) > 3 * fit.noise_rad:
        print(
            f"note: the record is in motion from {fit.onset_s:g} s, so at the scene's t = 0 the clamp has already "
            f"turned {turned:.4g} rad while the strip starts from its hanging rest shape; put the record's t = 0 at "
            "the start of the motion",
            file=sys.stderr,
        )
    print(f"status: {fit.status}")
    print(f"wrote {out}")
    if args.plot:
        from warpcloth.viz.plots import plot_clamp_fit

        print(f"wrote {plot_clamp_fit(t, theta, fit, plot)}")
    if fit.status != "converged":
        print(
            f"warpcloth clamp fit-angle: not a fit ({fit.status}): "
            + "; ".join(fit.problems)
            + (
                " (accepted with --accept)"
                if args.accept
                else "; a scene driven by it is wrong for the whole record (--accept to use it anyway)"
            ),
            file=sys.stderr,
        )
        return 0 if args.accept else EXIT_FIT_STATUS[fit.status]
    return 0
