"""Sphinx configuration of the motion-envs documentation (MyST Markdown, furo, gallery)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("MUJOCO_GL", "egl")

project = "motion-envs"
author = "motion-envs developers"
copyright = "2026, motion-envs developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "env_pages",
    "docstring_sections",
    "external_types",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
exclude_patterns = ["_build", "README.md", "**/README.txt"]
templates_path = ["_templates"]
# A name re-exported by its package (``motion_envs.datasets.OrientationDataset`` and
# ``motion_envs.datasets.orientation.OrientationDataset``) is one object with two paths;
# type-hint cross-references to it are ambiguous but resolve to the same page.
suppress_warnings = ["ref.python"]

autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
# a method without its own docstring shows none (Gymnasium's step/reset docstrings are
# Google-style text that napoleon's numpy parser would misread)
autodoc_inherit_docstrings = False
autodoc_typehints = "description"
autodoc_mock_imports: list[str] = []
# shown by their names instead of numpy's expansion of the alias (a dozen union members)
autodoc_type_aliases = {
    "ArrayLike": "numpy.typing.ArrayLike",
    "FloatArray": "numpy.typing.NDArray[numpy.float64]",
    "IntArray": "numpy.typing.NDArray[numpy.int64]",
}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# Attributes sections as fields of the class, not second descriptions of its members
napoleon_use_ivar = True

# Frames of each environment page's animation (a GIF rendered once and cached, see
# docs/_ext/env_pages.py); 0 shows the first frame only (the docs test builds so).
env_pages_animation_frames = int(os.environ.get("MOTION_ENVS_DOCS_ANIMATION_FRAMES", "60"))

html_theme = "furo"
html_title = "motion-envs"

sphinx_gallery_conf = {
    "examples_dirs": [str(ROOT / "examples")],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_|/[a-z]",
    "plot_gallery": os.environ.get("MOTION_ENVS_DOCS_RUN_EXAMPLES", "1") == "1",
    "download_all_examples": False,
    "remove_config_comments": True,
}
