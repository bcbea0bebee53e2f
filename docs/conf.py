# The fvm user guide and man pages (sphinx-build -b html / -b man), from the Markdown pages beside this file.
# Built by docs/CMakeLists.txt with PYTHONPATH at the built module (the Python page reads its docstrings).
import re
from pathlib import Path

project = "fvm"
author = "the fvm authors"
copyright = "2026, the fvm authors"
# The release, read from the one place it is set (project() in CMakeLists.txt).
release = re.search(r"project\(fvm VERSION ([0-9.]+)",
                    (Path(__file__).parent.parent / "CMakeLists.txt").read_text()).group(1)
version = release

extensions = ["myst_parser", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
# The generated option tables are included by the command pages, not pages of their own.
exclude_patterns = ["_build", "commands/reference/*"]
myst_heading_anchors = 3
myst_enable_extensions = ["deflist"]
# Markdown's own syntax only: `$` stays a dollar sign in shell examples.
html_theme = "alabaster"
html_theme_options = {"description": "stage calibration for focus-variation microscopes", "fixed_sidebar": True}
html_static_path = []
autodoc_member_order = "bysource"
# Options are written as typed: "--help" must not become an en dash, nor quotes curly.
smartquotes = False

# One man page per command (fvm-calibrate(1), ...) and fvm(1) for the program as a whole, from the same pages.
_commands = {
    "calibrate": "identify the stage model from a batch of placements or from stitched scans",
    "correct": "compensate stitching-free exports, point clouds, height maps and machine tables",
    "compare": "every model order side by side, validated on held-out placements",
    "diff": "per-calotte and distance differences between two exports of one artefact",
    "diagnose": "the discrepancy workflow: what the model misses, named and added",
    "simulate": "synthetic batches, scans, tracker data and test pieces with a recorded truth",
    "info": "what a surface or cloud file holds",
    "fit": "find calottes and fit spheres; fit a sphere or a plane to any point set",
    "focus": "height map, its uncertainty and the all-in-focus image from a focus stack",
    "tiles": "tile planning, stitching-strategy simulation and synthetic tiles",
    "stitch": "register the tiles of a stitched measurement",
    "verify": "volumetric verification of a machine tool with a laser tracker",
    "multilaterate": "points from the ranges of several tracker stations",
    "uncertainty": "Monte Carlo uncertainty of a calibration or verification",
    "testpiece": "the machined test piece: design and verification",
}
man_pages = [("commands/index", "fvm", "stage calibration for focus-variation microscopes", [author], 1)] + [
    (f"commands/{name}", f"fvm-{name}", summary, [author], 1) for name, summary in _commands.items()
]
man_show_urls = False
