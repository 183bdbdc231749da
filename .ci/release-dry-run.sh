#!/usr/bin/env bash
# Every check a release's registries would make, without uploading anything (docs/releasing.md):
# the one-version test, CITATION.cff against its schema, `cargo publish --dry-run` of the crate,
# the Python sdist and wheel through `twine check`, and the sdist installed by pip into a fresh
# venv (compiled from source) with the Python test suite run against it. Scratch and tools go to
# target/release-dry-run/. Needs a Rust toolchain, Python >= 3.9 with venv, and network for pip.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
step() { echo "== [$SECONDS s] $*"; }
work=target/release-dry-run
rm -rf "$work/dist" "$work/sdist-venv" "$work/home"
mkdir -p "$work/dist"

step "one version everywhere (tests/release.rs)"
cargo test --release --test tests -- release

step "release tools: cffconvert, twine, maturin ($work/tools)"
if [[ ! -x $work/tools/bin/python ]]; then
  python3 -m venv "$work/tools"
fi
"$work/tools/bin/python" -m pip install --quiet --disable-pip-version-check \
  cffconvert twine "maturin>=1.5,<2"

step "cffconvert --validate CITATION.cff"
"$work/tools/bin/cffconvert" --validate -i CITATION.cff

step "cargo publish --dry-run (the shadelab crate; python/ and web/engine/ are publish = false)"
cargo publish --dry-run
crate=$(ls -t target/package/shadelab-*.crate | head -1)
echo "$crate: $(du -k "$crate" | cut -f1) KiB, $(tar tzf "$crate" | wc -l) files"

step "maturin sdist and wheel of the Python package"
"$work/tools/bin/maturin" sdist -m python/Cargo.toml --out "$work/dist"
"$work/tools/bin/maturin" build --release --quiet -m python/Cargo.toml --out "$work/dist"
ls -l "$work/dist"

step "twine check (the metadata and long description PyPI validates)"
"$work/tools/bin/twine" check --strict "$work/dist"/*

step "the sdist installed by pip into a fresh venv (compiled from source) and the Python suite"
python3 -m venv "$work/sdist-venv"
"$work/sdist-venv/bin/python" -m pip install --quiet --disable-pip-version-check numpy pytest
"$work/sdist-venv/bin/python" -m pip install --disable-pip-version-check \
  "$(ls "$work"/dist/shadelab-*.tar.gz)"
cargo build --release --quiet --bin shadelab
mkdir -p "$work/home"
# From outside python/, so that `import shadelab` is the installed package; a home of its own,
# as tests/python.rs runs the suite; PsychoPy, stimupy and nbclient are not installed here, so
# their tests say why they skip.
(cd "$work" && HOME="$PWD/home" PSYCHOPY_USERDIR="$PWD/home/.psychopy3" \
  SHADELAB_BIN="$OLDPWD/target/release/shadelab" \
  sdist-venv/bin/python -m pytest -q -p no:cacheprovider "$OLDPWD/python/tests")

step "all dry runs passed"
