"""``warpcloth material fit-kes | list``: material files from KES-FB data."""

from __future__ import annotations

import argparse
import sys

from warpcloth.errors import OptionError

from .options import EXIT_FIT_STATUS, add_overwrite, figure_path, new_result, path_text, positive


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``material fit-kes`` and ``material list``."""
    material_p = sub.add_parser("material", help="material files: fit one to KES-FB data, list the bundled ones")
    material_sub = material_p.add_subparsers(dest="material_command", required=True)
    kes_p = material_sub.add_parser("fit-kes", help="fit a material file to a KES-FB1 tensile and a KES-FB2 "
                                    "bending loop (CSV, KES units)")
    kes_p.add_argument("--tensile", required=True, metavar="FB1.csv",
                       help="KES-FB1 loop: strain (%% or fraction) or extension (mm), force per width (gf/cm)")
    kes_p.add_argument("--bending", required=True, metavar="FB2.csv",
                       help="KES-FB2 loop: curvature (1/cm), moment per width (gf·cm/cm)")
    kes_p.add_argument("-o", "--output", type=path_text, required=True, help="the material file to write (.toml)")
    kes_p.add_argument("--density-g-per-cm2", type=positive, default=None,
                       help="mass per area ρ_A (required: KES-FB1/FB2 data do not contain it)")
    kes_p.add_argument("--name", help="material name (default: the output file's stem)")
    kes_p.add_argument("--strain-unit", choices=("percent", "fraction", "mm"), default=None,
                       help="unit of the tensile file's first column when its header does not say "
                       "(default: percent if its maximum exceeds 1, else fraction)")
    kes_p.add_argument("--gauge-length-mm", type=positive, default=None,
                       help="gauge length for extension in mm (default: 50, the KES-FB1 standard)")
    kes_p.add_argument("--divergence-strain", type=positive, default=None,
                       help="T(ε) must increase up to this strain (default: the scenes' default, 0.25)")
    kes_p.add_argument("--plot", help="also write a PNG of the data against the fit")
    kes_p.add_argument("--accept", action="store_true", help="exit 0 even when the fit is not trusted")
    add_overwrite(kes_p, "material file")
    material_sub.add_parser("list", help="list the bundled materials and where their numbers come from")
    material_p.set_defaults(handler=material_command)


def material_command(args: argparse.Namespace) -> int:
    """Fit a material file to KES-FB data, or list the bundled materials."""
    from warpcloth.calibrate import kes
    from warpcloth.scene import bundled_materials, read_material_file

    if args.material_command == "list":
        for name in bundled_materials():
            print(f"{name}: {read_material_file(name)['material']['source']}")
        return 0
    if args.density_g_per_cm2 is None:
        raise OptionError("--density-g-per-cm2", "the mass per area is not part of KES-FB1/FB2 data; weigh a "
                         "sample and give it in g/cm² (e.g. 2.03e-2 for the illustrative wool/nylon)")
    out = new_result(args.output, args.overwrite, "--output")
    plot = figure_path(args.plot, args.overwrite) if args.plot else None
    if out.suffix != ".toml":
        raise OptionError("--output", f"{out} must end in .toml (scenes refer to material files by such a path)")
    max_strain = kes.DIVERGENCE_STRAIN if args.divergence_strain is None else args.divergence_strain
    if not max_strain > 0:
        raise OptionError("--divergence-strain", f"must be > 0, got {max_strain:g}")
    gauge = kes.KES_FB1_GAUGE_MM if args.gauge_length_mm is None else args.gauge_length_mm
    fit = kes.fit_kes(kes.read_tensile_csv(args.tensile, args.strain_unit, gauge, flag="--tensile"),
                      kes.read_bending_csv(args.bending, flag="--bending"), max_strain)
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
        from warpcloth.viz.plots import plot_kes_fit

        print(f"wrote {plot_kes_fit(fit, plot)}")
    status, problems = fit.verdict()
    print(f"status: {status}")
    if status != "converged":
        print(f"warpcloth material fit-kes: not a fit ({status}): " + "; ".join(problems)
              + (" (accepted with --accept)" if args.accept else " (the material file records it; --accept to "
                 "exit 0 anyway)"), file=sys.stderr)
        return 0 if args.accept else EXIT_FIT_STATUS[status]
    return 0
