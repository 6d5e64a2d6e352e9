"""Looking at results: 2D figures (:mod:`.plots`), off-screen 3D renders (:mod:`.render`), USD export
(:mod:`.usd`) and the drawable geometry they share (:mod:`.geometry`)."""

FORMATS = ("png", "pdf", "svg")
"""Figure file formats (``plot --format``): PNG for screens, PDF and SVG (vector) for papers."""

DPI = 120
"""Default resolution of raster figures (``plot --dpi``)."""
