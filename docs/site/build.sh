#!/usr/bin/env bash
# The documentation as a searchable site: docs/*.md with README.md as the front page, the
# changelog, and the gallery that `shadelab gallery` renders (gallery/index.html and its
# pictures), built by Sphinx with MyST into target/docs-site/html/. Any warning fails the build:
# a link to a page, heading, image or file that does not exist is one. Needs Python >= 3.9 with
# venv and pip (the tools go into target/docs-site/venv) and a Rust toolchain for the gallery.
# Usage: docs/site/build.sh [OUT]   (default target/docs-site/html)
set -euo pipefail
cd "$(dirname "$0")/../.."
site=target/docs-site
out=${1:-$site/html}
if [[ ! -x $site/venv/bin/python ]]; then
  python3 -m venv "$site/venv"
fi
"$site/venv/bin/python" -m pip install --quiet --disable-pip-version-check -r docs/site/requirements.txt

# The gallery, as the README's first command renders it; its links to the pages point at the
# site's HTML pages instead of the repository's Markdown files.
rm -rf "$site/extra"
mkdir -p "$site/extra"
cargo run --release --quiet -- --quiet gallery --out "$site/extra/gallery" --docs-base ../
# The teaching page is built by web/build.sh (wasm32); on the site its link goes to its page.
sed -i -E -e 's#href="\.\./docs/([A-Za-z0-9_-]+)\.md#href="../\1.html#g' \
  -e 's#href="teach/index.html"#href="../teaching.html"#' "$site/extra/gallery/index.html"
if grep -q 'href="[^"]*\.md[#"]' "$site/extra/gallery/index.html"; then
  echo "the gallery's index.html still links a Markdown file" >&2
  exit 1
fi

rm -rf "$out"
SHADELAB_SITE_GALLERY="$PWD/$site/extra" \
  "$site/venv/bin/sphinx-build" -q -W --keep-going -b html -c docs/site docs "$out"
# Sphinx checked the pages' links; the gallery's are checked here: every relative link names a
# file of the site, and every #anchor an id in that page.
"$site/venv/bin/python" - "$out/gallery/index.html" <<'PY'
import re, sys
from pathlib import Path
page = Path(sys.argv[1])
broken = []
for href in re.findall(r'href="([^"]+)"', page.read_text(encoding="utf-8")):
    if re.match(r"[a-z]+:", href):
        continue
    target, _, anchor = href.partition("#")
    path = (page.parent / target).resolve()
    if not path.is_file():
        broken.append(href)
    elif anchor and f'id="{anchor}"' not in path.read_text(encoding="utf-8"):
        broken.append(href)
if broken:
    sys.exit(f"{page}: broken links: {', '.join(sorted(set(broken)))}")
PY
echo "the documentation site is in $out (open $out/index.html; the gallery is $out/gallery/index.html)"
