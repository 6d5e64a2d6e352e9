"""Sphinx configuration of the warpcloth documentation site.

Build it with ``sphinx-build -W --keep-going -b html docs docs/_build/html`` (what
tests/test_docs_site.py does, in a copy). The example gallery (``examples/plot_*.py``)
is executed by sphinx-gallery during the build; ``WARPCLOTH_EXAMPLES_QUICK=1`` makes
every example short (the CI build), ``-D plot_gallery=0`` skips running them.
"""

from __future__ import annotations

import os
import sys
from importlib.metadata import version as package_version
from pathlib import Path

from sphinx_gallery.sorting import ExplicitOrder

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")  # examples draw headless

project = "warpcloth"
author = "the warpcloth authors"
copyright = "the warpcloth authors, MIT licence"
release = version = package_version("warpcloth")

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "scene_reference",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip"]

# Markdown pages (the model reference is docs/model.md, written for GitHub too)
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]

# API reference from the docstrings
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"members": True, "show-inheritance": False}
napoleon_google_docstring = True
napoleon_numpy_docstring = True

sphinx_gallery_conf = {
    "examples_dirs": str(DOCS.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": ExplicitOrder(
        [
            "plot_damped_swing.py",
            "plot_impulsive_rotation.py",
            "plot_kes_fit.py",
            "plot_bending_laws.py",
            "plot_calibration.py",
            "plot_track_video.py",
            "plot_set_and_grip.py",
            "plot_sweep_heatmap.py",
            "plot_usd_export.py",
            "plot_sheet_shear_swing.py",
        ]
    ),
    "download_all_examples": False,
    "min_reported_time": 1,
    "show_memory": False,
}

html_theme = "alabaster"
html_title = f"warpcloth {release}"
html_theme_options = {"description": "Batched Warp simulation of hanging fabric strips", "fixed_sidebar": True}
