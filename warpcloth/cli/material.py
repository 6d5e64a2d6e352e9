"""``warpcloth material fit-kes | compare | list``: material files from KES-FB data, and
the laws compared on a KES-FB2 bending or a KES-FB1 shear loop."""

from __future__ import annotations

import argparse
import csv
import io
import sys
from typing import TYPE_CHECKING, Any

from warpcloth.errors import OptionError
from warpcloth.kernels import BENDING_LAWS, DEFAULT_BENDING_LAW
from warpcloth.scene.materials import ONE_PER_FABRIC

from .options import EXIT_FIT_STATUS, add_overwrite, figure_path, new_file, path_text, positive

if TYPE_CHECKING:
    from warpcloth.calibrate.kes import LawComparison, ShearFit

BENDING_HELP = "KES-FB2 loop: curvature (1/cm), moment per width (gf·cm/cm)"
SHEAR_HELP = "KES-FB1 shear loop: shear angle (degree), shear force per width (gf/cm)"
DEFAULT_SHEAR_LAW = "masing"
"""The shear law fit-kes fits without --shear-law: the paper's loop shape with return-point
memory, which converges as a sheet's mesh and step are refined (docs/model.md §17.1)."""


def add_shear_geometry(parser: argparse.ArgumentParser) -> None:
    """``--shear-geometry``: what a KES-FB1 shear file's columns are."""
    parser.add_argument(
        "--shear-geometry",
        choices=("fabric", "chuck"),
        default="fabric",
        help="what --shear's columns are: fabric (default): the fabric's shear angle and shear force per width; "
        "chuck: the chuck's displacement over the gauge length as a small angle in degrees and its lateral "
        "force per width, converted by φ = arctan(d/L), Fs = F / cos²φ (virtual work at a fixed gauge; "
        "which one an instrument records is in its manual; docs/model.md §17.1)",
    )


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``material fit-kes``, ``material compare`` and ``material list``."""
    material_p = sub.add_parser("material", help="material files: fit one to KES-FB data, list the bundled ones")
    material_sub = material_p.add_subparsers(dest="material_command", required=True)
    kes_p = material_sub.add_parser(
        "fit-kes", help="fit a material file to a KES-FB1 tensile and a KES-FB2 bending loop (CSV, KES units)"
    )
    kes_p.add_argument(
        "--tensile",
        required=True,
        metavar="FB1.csv",
        help="KES-FB1 loop: strain (%% or fraction) or extension (mm), force per width (gf/cm)",
    )
    kes_p.add_argument("--bending", required=True, metavar="FB2.csv", help=BENDING_HELP)
    kes_p.add_argument(
        "--law",
        default=DEFAULT_BENDING_LAW,
        metavar="NAME|all",
        help="the bending law to fit: "
        + ", ".join(f"{law.name} ({law.summary})" for law in BENDING_LAWS.values())
        + "; or all: fit every one, print their comparison and write the material of the one with "
        f"the lowest AIC (default: {DEFAULT_BENDING_LAW})",
    )
    kes_p.add_argument(
        "--shear",
        metavar="FB1S.csv",
        help=f"also fit the fabric's in-plane shear: {SHEAR_HELP}; "
        "the material file gains a [shear] table (for the woven sheet being built, docs/model.md §17; "
        "strips ignore it)",
    )
    kes_p.add_argument(
        "--weft-tensile",
        metavar="FB1.csv",
        help="also the weft's KES-FB1 tensile loop (with --weft-bending): --tensile and --bending are then the "
        "warp's, and the material file gains a [weft] table (the woven sheet's second direction; strips ignore it)",
    )
    kes_p.add_argument(
        "--weft-bending", metavar="FB2.csv", help="the weft's KES-FB2 bending loop (with --weft-tensile)"
    )
    add_shear_geometry(kes_p)
    kes_p.add_argument(
        "--shear-law",
        default=None,
        choices=tuple(BENDING_LAWS),
        help=f"the law to fit to --shear (default: {DEFAULT_SHEAR_LAW})",
    )
    kes_p.add_argument("-o", "--output", type=path_text, required=True, help="the material file to write (.toml)")
    kes_p.add_argument(
        "--density-g-per-cm2",
        type=positive,
        default=None,
        help="mass per area ρ_A (required: KES-FB1/FB2 data do not contain it)",
    )
    kes_p.add_argument("--name", help="material name (default: the output file's stem)")
    kes_p.add_argument(
        "--strain-unit",
        choices=("percent", "fraction", "mm"),
        default=None,
        help="unit of the tensile file's first column when its header does not say "
        "(default: percent if its maximum exceeds 1, else fraction)",
    )
    kes_p.add_argument(
        "--gauge-length-mm",
        type=positive,
        default=None,
        help="gauge length for extension in mm (default: 50, the KES-FB1 standard)",
    )
    kes_p.add_argument(
        "--divergence-strain",
        type=positive,
        default=None,
        help="T(ε) must increase up to this strain (default: the scenes' default, 0.25)",
    )
    kes_p.add_argument(
        "--plot",
        help="also write a PNG of the data against the fit (tagawa2003: tensile and "
        "bending; another law or all: the bending laws' comparison figure)",
    )
    kes_p.add_argument("--accept", action="store_true", help="exit 0 even when the fit is not trusted")
    add_overwrite(kes_p, "material file")
    compare_p = material_sub.add_parser(
        "compare",
        help="fit every law to a KES-FB2 bending or a KES-FB1 shear loop "
        "and compare them by information criterion (writes no material)",
    )
    loop_p = compare_p.add_mutually_exclusive_group(required=True)
    loop_p.add_argument("--bending", metavar="FB2.csv", help=BENDING_HELP)
    loop_p.add_argument("--shear", metavar="FB1S.csv", help=f"{SHEAR_HELP} (--plot and --csv: bending only)")
    add_shear_geometry(compare_p)
    compare_p.add_argument(
        "--plot", metavar="FIG.png", help="write a PNG of each law's fit over the loop and its residuals"
    )
    compare_p.add_argument("--csv", type=path_text, metavar="TABLE.csv", help="write the comparison table as CSV")
    compare_p.add_argument(
        "--accept", action="store_true", help="exit 0 even when the recommended law's fit is not trusted"
    )
    add_overwrite(compare_p, "figure or table")
    material_sub.add_parser("list", help="list the bundled materials and where their numbers come from")
    material_p.set_defaults(handler=material_command)


def material_command(args: argparse.Namespace) -> int:
    """Fit a material file to KES-FB data, compare the bending laws on a loop, or list the bundled materials."""
    from warpcloth.scene import bundled_materials, read_material_file

    if args.material_command == "list":
        for name in bundled_materials():
            print(f"{name}: {read_material_file(name)['material']['source']}")
        return 0
    if args.material_command == "compare":
        if args.shear_geometry != "fabric" and not args.shear:
            raise OptionError("--shear-geometry", f"{args.shear_geometry}: there is no --shear loop to read that way")
        return _compare_shear(args) if args.shear else _compare(args)
    return _fit_kes(args)


def _print_comparison(comparison: LawComparison, source: str) -> None:
    # the table and the recommendation with its caveats
    n = len(comparison.loop.curvature)
    print(
        f"bending laws fitted to {source} ({n} points); AIC = n ln(SSE/n) + 2k, BIC = n ln(SSE/n) + k ln n "
        f"(n = {n} points, k free parameters); B and 2HB of each law along 0 → +K0 → −K0 → 0:"
    )
    print(comparison.table())
    for line in comparison.caveats():
        print(f"  {line}")


def _kes_value(value: float | None, unit: str) -> str:
    return "n/a" if value is None else f"{value:.4g} {unit}"


def _finish(command: str, status: str, problems: list[str], accept: bool, what: str) -> int:
    # the status line, and the exit status of a fit that is not trusted
    print(f"status: {status}")
    if status == "converged":
        return 0
    print(
        f"warpcloth material {command}: not a fit ({status}): "
        + "; ".join(problems)
        + (" (accepted with --accept)" if accept else f" ({what}; --accept to exit 0 anyway)"),
        file=sys.stderr,
    )
    return 0 if accept else EXIT_FIT_STATUS[status]


def _print_shear(fit: ShearFit, source: str) -> None:
    n = len(fit.loop.angle)
    print(f"shear ({source}, {n} points), law {fit.shear.law}: {fit.describe()}")
    print(
        f"  RMS {fit.rms_gf_per_cm:.4g} gf/cm, AIC {fit.law_fit.aic():.2f}, BIC {fit.law_fit.bic():.2f} "
        f"({fit.law_fit.free_parameters} free parameters)"
    )
    if fit.law_fit.note:
        print(f"  note: {fit.law_fit.note}")
    units = {"G": "gf/(cm·°)", "2HG": "gf/cm", "2HG5": "gf/cm"}
    print(
        "  KES: "
        + ", ".join(
            f"{name} {_kes_value(data, units[name])} (the law's {_kes_value(law, units[name])}{_difference(data, law)})"
            for name, data, law in fit.kes_comparison()
        )
        + " along 0 → +φ0 → −φ0 → 0"
    )


def _number(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.4g}"


def _difference(data: float | None, law: float | None) -> str:
    return f", {100 * (law - data) / data:+.1f} %" if data and law is not None else ""


def _compare_shear(args: argparse.Namespace) -> int:
    from warpcloth.calibrate import kes

    if args.plot or args.csv:
        raise OptionError(
            "--plot" if args.plot else "--csv",
            "the comparison figure and table are of bending loops; with --shear the comparison is printed",
        )
    loop = kes.read_shear_csv(args.shear, argument="--shear", geometry=args.shear_geometry)
    fits = {law: kes.fit_shear(loop, law) for law in BENDING_LAWS}
    best = min(f.law_fit.aic() for f in fits.values())
    ranking = sorted(fits, key=lambda law: (fits[law].law_fit.aic(), fits[law].law_fit.free_parameters))
    print(f"shear laws fitted to {args.shear} ({len(loop.angle)} points); AIC = n ln(SSE/n) + 2k:")
    for law in ranking:
        fit = fits[law]
        status, _ = fit.verdict()
        print(
            f"  {law}: ΔAIC {fit.law_fit.aic() - best:.1f}, "
            + ", ".join(
                f"{name} {_number(law_value)}{_difference(data, law_value)}"
                for name, data, law_value in fit.kes_comparison()
            )
            + f" — {status}"
        )
    print(f"recommended: {ranking[0]} (the lowest AIC)")
    _print_shear(fits[ranking[0]], args.shear)
    status, problems = fits[ranking[0]].verdict()
    return _finish(
        "compare",
        status,
        [f"the recommended {ranking[0]} fit: {p}" for p in problems],
        args.accept,
        "the table shows it",
    )


def _compare(args: argparse.Namespace) -> int:
    from warpcloth.calibrate import kes
    from warpcloth.io.atomic import write_text_atomically

    plot = figure_path(args.plot, args.overwrite) if args.plot else None
    table = new_file(args.csv, args.overwrite, "--csv") if args.csv else None
    if table is not None and (table.suffix.lower() != ".csv" or table.is_dir()):
        raise OptionError("--csv", f"{table} must be a file ending in .csv")
    comparison = kes.compare_laws(kes.read_bending_csv(args.bending, argument="--bending"))
    _print_comparison(comparison, args.bending)
    if plot is not None:
        from warpcloth.viz.plots import plot_bending_law_comparison

        print(f"wrote {plot_bending_law_comparison(comparison, plot)}")
    if table is not None:
        rows = comparison.rows()
        text = io.StringIO()
        writer = csv.DictWriter(text, fieldnames=list(rows[0]), restval="", lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: "" if v is None else v for k, v in row.items()} for row in rows)
        table.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomically(table, text.getvalue())
        print(f"wrote {table}")
    status, problems = comparison.status(comparison.recommended)
    return _finish(
        "compare",
        status,
        [f"the recommended {comparison.recommended} fit: {p}" for p in problems],
        args.accept,
        "the table shows it",
    )


def _fit_direction(
    tensile_path: str,
    bending_path: str,
    flags: tuple[str, str],
    laws: list[str],
    max_strain: float,
    gauge: float,
    strain_unit: str | None,
) -> tuple[Any, Any, str]:
    """One yarn direction's KES fit: its tensile quartic and its bending law (the lowest
    AIC of ``laws``), with the comparison it came from."""
    from warpcloth.calibrate import kes

    tensile = kes.read_tensile_csv(tensile_path, strain_unit, gauge, argument=flags[0])
    comparison = kes.compare_laws(kes.read_bending_csv(bending_path, argument=flags[1]), laws)
    law = comparison.recommended
    return kes.fit_kes(tensile, comparison.loop, max_strain, bending_fit=comparison.fits[law]), comparison, law


def _print_direction(
    label: str, tensile: str, bending: str, fit: Any, comparison: Any, law: str, compared: bool
) -> None:
    """What a direction's fit prints: the tensile quartic and its KES values, the bending
    law and its (``label``: "" for the one direction or the warp, "weft")."""
    from warpcloth.calibrate import kes
    from warpcloth.calibrate.uncertainty import DETERMINED_CORRELATION, DETERMINED_SIGMAS

    prefix = f"{label} " if label else ""
    print(f"{prefix}tensile file's first column read as {fit.tensile_loop.strain_unit}")
    t, tk, b, bk = fit.tensile, fit.tensile_kes, fit.bending, fit.bending_kes
    rt = f", RT {tk.rt_percent:.1f} %" if tk.rt_percent is not None else " (no unloading branch: no RT)"
    print(
        f"{prefix}tensile ({tensile}, {fit.summary_table()['tensile_loading_points']} loading points): T(ε) = "
        f"a1 ε + a2 ε² + a3 ε³ + a4 ε⁴; determined: T(ε) itself, within RMS {t.rms_gf_per_cm:.4g} gf/cm "
        f"({t.rms_relative:.3%} of the force range); its coefficients (± 1σ; not determined: within "
        f"{DETERMINED_SIGMAS:g}σ of 0, or a multiple correlation beyond {DETERMINED_CORRELATION:g}):"
    )
    for value in t.values():
        print(f"  {value.text()}")
    if t.note:
        print(f"  note: {t.note}")
    print(
        f"  KES: EMT {tk.emt_percent:.4g} %, WT {tk.wt_gf_cm_per_cm2:.4g} gf·cm/cm², LT {tk.lt:.4g}{rt} "
        f"(Fm {tk.fm_gf_per_cm:.4g} gf/cm)"
    )
    if compared:
        _print_comparison(comparison, bending)
    print(
        f"{prefix}bending ({bending}, {len(fit.bending_loop.curvature)} points), law {law}: "
        f"{kes.LAW_FITTERS[law].describe(b)}"
    )
    print(
        f"  RMS {b.rms_gf_cm_per_cm:.4g} gf·cm/cm ({b.rms_relative:.3%} of the moment range), AIC {b.aic():.2f}, "
        f"BIC {b.bic():.2f} ({b.free_parameters} free parameters)"
    )
    if b.note:
        print(f"  note: {b.note}")
    model = comparison.reproduced[law]
    print(
        f"  KES: B {_kes_value(bk.b_gf_cm2_per_cm, 'gf·cm²/cm')}, 2HB {_kes_value(bk.hb2_gf_cm_per_cm, 'gf·cm/cm')} "
        f"(the data's; the fitted law along 0 → +K0 → −K0 → 0: B {_kes_value(model.b_gf_cm2_per_cm, 'gf·cm²/cm')}, "
        f"2HB {_kes_value(model.hb2_gf_cm_per_cm, 'gf·cm/cm')})"
    )


def _fit_kes(args: argparse.Namespace) -> int:
    from warpcloth.calibrate import kes

    laws = kes.selected_laws(args.law)
    if args.density_g_per_cm2 is None:
        raise OptionError(
            "--density-g-per-cm2",
            "the mass per area is not part of KES-FB1/FB2 data; weigh a "
            "sample and give it in g/cm² (e.g. 2.03e-2 for the illustrative wool/nylon)",
        )
    out = new_file(args.output, args.overwrite, "--output")
    plot = figure_path(args.plot, args.overwrite) if args.plot else None
    if out.suffix != ".toml":
        raise OptionError("--output", f"{out} must end in .toml (scenes refer to material files by such a path)")
    max_strain = kes.DIVERGENCE_STRAIN if args.divergence_strain is None else args.divergence_strain
    if not max_strain > 0:
        raise OptionError("--divergence-strain", f"must be > 0, got {max_strain:g}")
    gauge = kes.KES_FB1_GAUGE_MM if args.gauge_length_mm is None else args.gauge_length_mm
    if (args.weft_tensile is None) != (args.weft_bending is None):
        given, missing = (
            ("--weft-tensile", "--weft-bending") if args.weft_bending is None else ("--weft-bending", "--weft-tensile")
        )
        raise OptionError(given, f"the weft is fitted from both its loops: give {missing} too")
    if args.shear_law is not None and not args.shear:
        raise OptionError("--shear-law", f"{args.shear_law}: there is no --shear loop to fit it to")
    shear_law = args.shear_law or DEFAULT_SHEAR_LAW
    if args.shear_geometry != "fabric" and not args.shear:
        raise OptionError("--shear-geometry", f"{args.shear_geometry}: there is no --shear loop to read that way")
    shear = (
        kes.fit_shear(kes.read_shear_csv(args.shear, argument="--shear", geometry=args.shear_geometry), shear_law)
        if args.shear
        else None
    )
    directions = [("", args.tensile, args.bending, "--tensile", "--bending")]
    if args.weft_tensile is not None:
        directions.append(("weft", args.weft_tensile, args.weft_bending, "--weft-tensile", "--weft-bending"))
    fits = [
        _fit_direction(tensile, bending, (t_flag, b_flag), laws, max_strain, gauge, args.strain_unit)
        for _label, tensile, bending, t_flag, b_flag in directions
    ]
    fit, comparison, law = fits[0]
    chosen = f"; bending law {law}, the lowest AIC of {', '.join(laws)}" if len(laws) > 1 else ""
    source = (
        f"fitted by warpcloth material fit-kes to {args.tensile} (KES-FB1) and {args.bending} (KES-FB2)"
        f"{chosen}; density {args.density_g_per_cm2:g} g/cm² given on the command line"
    )
    if len(fits) > 1:
        source += f"; the weft to {args.weft_tensile} and {args.weft_bending}"
    if shear is not None:
        read = "; its columns read as the chuck's, converted to the fabric's" if args.shear_geometry == "chuck" else ""
        source += f"; shear ({shear_law}) fitted to {args.shear} (KES-FB1 shear{read})"
    data = kes.material_file_data(fit, args.name or out.stem, args.density_g_per_cm2, source, max_strain, shear)
    if len(laws) > 1:
        data["fit"] |= comparison.fit_table()
    if len(fits) > 1:
        weft_fit = fits[1][0]
        weft = kes.material_file_data(weft_fit, args.name or out.stem, args.density_g_per_cm2, source, max_strain)
        data["weft"] = {k: v for k, v in weft["material"].items() if k not in (*ONE_PER_FABRIC, "source")}
        data["fit"] |= {f"weft_{k}": v for k, v in weft["fit"].items()}
        if len(laws) > 1:
            data["fit"] |= {f"weft_{k}": v for k, v in fits[1][1].fit_table().items()}
    for (label, tensile, bending, _t, _b), (direction_fit, direction_comparison, direction_law) in zip(
        directions, fits, strict=True
    ):
        _print_direction(label, tensile, bending, direction_fit, direction_comparison, direction_law, len(laws) > 1)
    if shear is not None:
        _print_shear(shear, args.shear)
    which = f" with the {law} bending law, the one AIC recommends" if len(laws) > 1 else ""
    if len(fits) > 1 and len(laws) > 1:
        which += f" (the weft's: {fits[1][2]})"
    print(
        f'wrote {kes.write_material_file(out, data)}{which} (a scene uses it with from_file = "{out}" in its '
        f"[material], or --set material.from_file={out})"
    )
    if plot is not None:
        from warpcloth.viz.plots import plot_bending_law_comparison, plot_kes_fit

        figure = plot_kes_fit(fit, plot) if laws == ["tagawa2003"] else plot_bending_law_comparison(comparison, plot)
        print(f"wrote {figure}")
    status, problems = fit.verdict()
    if len(fits) > 1:
        weft_status, weft_problems = fits[1][0].verdict()
        problems += [f"weft: {p}" for p in weft_problems]
        status = kes.worst_status(status, weft_status)
    if shear is not None:
        shear_status, shear_problems = shear.verdict()
        problems += [f"shear: {p}" for p in shear_problems]
        status = kes.worst_status(status, shear_status)
    return _finish("fit-kes", status, problems, args.accept, "the material file records it")
