"""Sphinx configuration of shadelab's documentation site (docs/site/build.sh builds it).

The pages are docs/*.md as they are (MyST Markdown, the GitHub flavour they are written in),
with README.md as the front page and CHANGELOG.md; a link to a page or heading that does not
exist is a warning, and the build turns warnings into errors.
"""

import os
import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent

project = "shadelab"
author = "The shadelab developers"
copyright = "the shadelab developers, MIT OR Apache-2.0"
# The one version: the root Cargo.toml's (docs/releasing.md).
release = version = re.search(
    r'^version = "([^"]+)"', (ROOT / "Cargo.toml").read_text(encoding="utf-8"), re.M
).group(1)

extensions = ["myst_parser"]
source_suffix = {".md": "markdown"}
root_doc = "index"
# docs/site is this configuration; docs/benchmark/ holds a generated record beside its data.
exclude_patterns = ["site", "_build", "benchmark"]
# GitHub's heading slugs, so that `page.md#a-heading` links resolve as they do on GitHub.
myst_heading_anchors = 6
myst_enable_extensions = ["strikethrough"]
suppress_warnings = []
nitpicky = False

html_theme = "furo"
html_title = f"shadelab {release}"
html_static_path = []
html_show_sourcelink = False
# The gallery rendered by `shadelab gallery` (docs/site/build.sh), served as gallery/index.html.
gallery = os.environ.get("SHADELAB_SITE_GALLERY")
html_extra_path = [gallery] if gallery else []


def _readme_for_the_site(app, relative_path, parent_docname, content):
    """README.md links files by their path from the repository's root: on the site the
    changelog is a page (docs/changelog.md), docs/ pages are pages (`:relative-docs:`), and any
    other file (the citation, the notebook, an example) a file to download."""
    if relative_path.name == "README.md":
        text = content[0].replace("](CHANGELOG.md)", "](changelog.md)")
        content[0] = re.sub(
            r"\]\((?!docs/|changelog\.md|[a-z]+:|#)([^)\s]+)\)", r"](path:../\1)", text
        )


def setup(app):
    app.connect("include-read", _readme_for_the_site)
