"""The command line's name for each argument the library can name in an
:class:`~warpcloth.errors.ArgumentError`, and the one conversion to an
:class:`~warpcloth.errors.OptionError` (at the error boundary, :mod:`warpcloth.cli.app`).

The library names its own arguments (``variants``, ``t_from``), so a Python caller reads
the keyword it wrote; the command line shows the option that supplied it (``--variants``,
``--from``), with the same message. Converting at the boundary, rather than making the
library's error an OptionError, keeps the library free of the command line's spelling;
OptionError is an ArgumentError, so code that catches ArgumentError catches both.
``tests/test_errors.py`` checks that every argument the library names is here or in
:data:`LIBRARY_ONLY`.
"""

from __future__ import annotations

from warpcloth.errors import ArgumentError, OptionError

FLAGS = {
    "align_start_s": "--align-start",
    "angle_unit": "--angle-unit",
    "bounds": "--bounds",
    "clamp_edge_px": "--clamp-edge-px",
    "density_g_per_cm2": "--density-g-per-cm2",
    "diameter_mm": "--marker-diameter-mm",
    "device": "--device",
    "dpi": "--dpi",
    "fmt": "--format",
    "frames_per_clip": "--frames-per-clip",
    "free": "--free",
    "gauge_length_mm": "--gauge-length-mm",
    "geometry": "--shear-geometry",
    "inner": "--board",
    "law": "--law",
    "max_batch": "--max-batch",
    "max_variants": "--max-variants",
    "measured": "--measured",
    "measurement": "--measured",
    "metric": "--metric",
    "movie": "--movie",
    "name_or_path": "SCENE",
    "noise": "--noise",
    "origin_corner": "--origin-corner",
    "names": "--free",
    "out": "--out",
    "out_file": "-o",
    "overlay_video": "--overlay-video",
    "overrides": "--set",
    "paths": "IMAGE",
    "ribbon": "--ribbon",
    "s_mm": "--marker-s",
    "scheduler": "--scheduler",
    "source": "INPUT",
    "space_filling": "--space-filling",
    "square_mm": "--square-mm",
    "bootstrap": "--bootstrap",
    "spans": "INPUT",  # the records compared: the run and the measured file
    "strain_unit": "--strain-unit",
    "stride": "--stride",
    "t": "ENCODER",
    "t_from": "--from",
    "t_to": "--to",
    "theta": "ENCODER",
    "times": "--times",
    "probes": "--probes",
    "variants": "--variants",
    "where": "--where",
    "workers": "--workers",
    "x": "--x",
    "y": "--y",
}
"""Library argument → the option (or positional argument) that supplies it."""

LIBRARY_ONLY = frozenset(
    {
        "(i, j)",  # SheetGeometry.node/cell/hinge(i, j): a scene's output.markers_ij, checked as a scene field
        "areal_density",  # calibrate.fabric_dataset.bending_length(...) and kin: no command calls them
        "bending_factor",  # Grip(...): a scene's clamp.grip_* fields, checked as fields
        "bending_poisson_ratio",  # SheetMaterialSI(...): a scene's bias.bending_poisson_ratio, checked as a field
        "bias",  # SheetMaterialSI(bias=...): a scene's [bias], checked field by field
        "compression_fraction",  # SheetBuilder(...): a scene's sheet.yarn_compression_fraction, checked as a field
        "count",  # sheet_shapes_figure(count=): plot draws six frames
        "bending_length",  # rigidity_from_bending_length(bending_length, ...): as areal_density
        "body",  # warpcloth.bodies.named(name): a scene or run names its body, read by the registry
        "blocks",  # identifiability(blocks): the benchmarks' comparison of experiments
        "clamp_edge",  # grid_geometry(clamp_edge=): bias_strip passes it at a scene's oblique sheet.bias_angle_deg
        "clamp_length",  # rectangle(...): a scene's sheet.* lengths, checked as fields (sheet.cut for the rest)
        "dotted",  # sheet_value(scene, dotted): fit --free names it as "names"
        "edge_hinge",  # rectangle/bias_strip(edge_hinge=): a scene's sheet.edge_hinge, a choice field
        "edge_hinge_length",  # StripBuilder.add_strip(): a scene's clamp.edge_hinge, a choice field
        "family",  # SheetGeometry.hinge(family, ...)
        "fit",  # fit_search_figure(fit): the command line draws no search figure
        "forms",  # clamp-motion forms: the command tries every one
        "free_length",  # rectangle(...): as clamp_length
        "h",  # least_squares_above(a, b, g, h): the tensile fit's, which names the loop's file
        "hysteresis_factor",  # Grip(...): as bending_factor
        "initial_positions",  # simulate()'s start state: no option sets it
        "initial_velocities",
        "is_clamped",  # grid_geometry(is_clamped=): a scene's cut, reported as sheet.cut
        "j",  # Recording.probe(name, j): the command line selects variants by --variants
        "kept_cells",  # grid_geometry(kept_cells): a scene's cut, reported as sheet.cut
        "laser",  # swing_summary(t, laser, tip): analyse reads them from one file, one row per time
        "lambda_max",  # two_section_beam_mode(): the tests' and benchmarks' reference solution
        "length",  # Grip(length): as bending_factor
        "markers",  # SheetRecorder(markers=): a scene's output.markers_mm, checked as a scene field first
        "on_divergence",  # simulate(on_divergence=): the command line records or raises as each command needs
        "n_clamped",  # StripBuilder(n_clamped): a scene's strip.clamp_length_mm and spacing_mm, checked as fields
        "name",  # RunResult.probe(name)
        "overhang",  # bending_length_from_overhang(overhang): as areal_density
        "path",  # a measured-data reader called directly
        "precision",  # SheetBuilder.finalize(precision=): a scene's integrator.precision, checked as a field
        "release_time",  # SheetBuilder(release_time=): a scene's release.settle_time_s, checked as a field
        "rest_positions",  # StripBuilder(rest_positions): a scene's straight chain
        "result",  # a run without frames passed to the tracked-marker residual or figure: fit keeps them
        "reversal_memory",  # StripBuilder(reversal_memory=): a scene's integrator.reversal_memory, a field
        "rigidity",  # bending_length(rigidity, ...): as areal_density
        "root_factor",  # two_section_beam_mode(): as lambda_max
        "root_length",
        "run",  # sheet_shapes_figure(run): plot_sheet_run draws it only when frames were kept
        "scene",  # simulate_sheet(scene): the command line passes the scene it loaded
        "scenes",  # simulate(scenes): the command line passes the scenes it loaded
        "shear_rigidity",  # SheetMaterialSI(shear_rigidity): a scene's shear.rigidity_gf_per_cm_deg, a field
        "sink",  # simulate_batch(sink=): a run writer made by the library for the model it runs
        "solver",  # FusedStripSolver(...) itself: the base of the strip's solvers, never one a scene names
        "sheets",  # SheetBuilder.finalize() with none added: a scene always adds its sheet
        "strips",  # StripBuilder.finalize() with none added: a scene always adds its strips
        "terms",  # StripBuilder/SheetBuilder.finalize(terms=): force terms are added in Python
        "table_s",  # FabricSet(table_s): a scene's strip.rest_curvature_table_*, checked as fields
        "threads",  # simulate_sheets(threads=): the command line uses every core
        "values",  # LawParameters.of(law, values): a scene's material fields, checked as fields
        "variant",  # RunResult.probe(..., variant=)
        "width",  # rectangle(...): as clamp_length
        "weft",  # SheetMaterialSI(warp, weft): a scene has one density, material.density_g_per_cm2
    }
)
"""Arguments the command line never passes: an error about one is the library caller's."""


def flag_of(argument: str) -> str:
    """The command line's name for ``argument``; an argument the command line named
    itself (a flag it passed down as the name to blame, e.g. ``--out``) is kept."""
    return FLAGS.get(argument, argument)


def as_option(error: ArgumentError) -> OptionError:
    """``error`` as the command line says it: the same message, naming the option."""
    if isinstance(error, OptionError):
        return error
    option = OptionError(flag_of(error.argument), error.message)
    option.__cause__ = error
    return option
