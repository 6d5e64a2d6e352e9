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
    "device": "--device",
    "dpi": "--dpi",
    "fmt": "--format",
    "frames_per_clip": "--frames-per-clip",
    "free": "--free",
    "gauge_length_mm": "--gauge-length-mm",
    "law": "--law",
    "max_batch": "--max-batch",
    "max_variants": "--max-variants",
    "measured": "--measured",
    "measurement": "--measured",
    "metric": "--metric",
    "movie": "--movie",
    "name_or_path": "SCENE",
    "origin_corner": "--origin-corner",
    "names": "--free",
    "out": "--out",
    "out_file": "-o",
    "overlay_video": "--overlay-video",
    "paths": "IMAGE",
    "ribbon": "--ribbon",
    "scheduler": "--scheduler",
    "source": "INPUT",
    "space_filling": "--space-filling",
    "spans": "INPUT",  # the records compared: the run and the measured file
    "strain_unit": "--strain-unit",
    "stride": "--stride",
    "t": "ENCODER",
    "t_from": "--from",
    "t_to": "--to",
    "theta": "ENCODER",
    "times": "--times",
    "variants": "--variants",
    "where": "--where",
    "workers": "--workers",
    "x": "--x",
    "y": "--y",
}
"""Library argument → the option (or positional argument) that supplies it."""

LIBRARY_ONLY = frozenset(
    {
        "fit",  # fit_search_figure(fit): the command line draws no search figure
        "forms",  # clamp-motion forms: the command tries every one
        "initial_positions",  # simulate()'s start state: no option sets it
        "initial_velocities",
        "j",  # Recording.probe(name, j): the command line selects variants by --variants
        "markers",  # SheetRecorder(markers=): a scene's output.markers_mm, checked as a scene field first
        "name",  # RunResult.probe(name)
        "path",  # a measured-data reader called directly
        "precision",  # SheetBuilder.finalize(precision=): a scene's integrator.precision, checked as a field
        "release_time",  # SheetBuilder(release_time=): a scene's release.settle_time_s, checked as a field
        "sheets",  # SheetBuilder.finalize() with none added: a scene always adds its sheet
        "threads",  # simulate_sheets(threads=): the command line uses every core
        "variant",  # RunResult.probe(..., variant=)
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
