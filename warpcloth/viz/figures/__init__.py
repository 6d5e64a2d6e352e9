"""2D figures, one module per subject: :mod:`.traces` (a run: displacement, clamp angle,
shapes, energy, and :func:`~.traces.plot_run`), :mod:`.kes` (the bending loop, KES fits,
bending laws compared), :mod:`.sweeps` (a metric over swept parameters), :mod:`.fits`
(motion and clamp-motion fits), and :mod:`.common` (the backend, the writer, labels and
colours they share). Headless, as PNG (or PDF, SVG: :data:`warpcloth.viz.FORMATS`).

Import them from :mod:`warpcloth.viz.plots`, the public path.
"""
