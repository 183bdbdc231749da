#!/usr/bin/env bash
# Every check a release's registries would make, without uploading anything (docs/releasing.md):
# the one-version test (with the changelog's section for the version), CITATION.cff against its
# schema, `cargo publish --dry-run` of the workspace's crates, the Python sdist and wheel through `twine check
# --strict`, the sdist installed by pip into a fresh venv (compiled from source, as a lab
# without a wheel for its platform gets it) with the sdist's own test suite run against it, and
# the documentation site. It stops at the first step that fails and names it; it publishes
# nothing and changes no tracked file (checked at the end). Scratch and tools go to
# target/release-dry-run/. Needs a Rust toolchain, Python >= 3.9 with venv, network for pip,
# and a committed tree (cargo publish packages what git tracks).
# Usage: .ci/release-dry-run.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export CARGO_TERM_COLOR=never
current="starting"
step() {
  current=$*
  echo "== [$SECONDS s] $*"
}
trap 'echo "release dry run FAILED at step: $current (after $SECONDS s)" >&2' ERR
work=$root/target/release-dry-run
before=$(git status --porcelain)
rm -rf "$work/dist" "$work/sdist-venv" "$work/sdist" "$work/home"
mkdir -p "$work/dist" "$work/sdist" "$work/home"
version=$(cargo metadata --no-deps --format-version 1 \
  | python3 -c 'import json, sys; print(next(p["version"] for p in json.load(sys.stdin)["packages"] if p["name"] == "shadelab"))')
echo "shadelab $version"

step "one version everywhere, and CHANGELOG.md's section for $version (tests/release.rs)"
cargo test --release --test tests -- release

step "release tools: cffconvert, twine, maturin ($work/tools)"
if [[ ! -x $work/tools/bin/python ]]; then
  python3 -m venv "$work/tools"
fi
"$work/tools/bin/python" -m pip install --quiet --disable-pip-version-check \
  cffconvert twine "maturin>=1.14,<2"

step "cffconvert --validate CITATION.cff"
"$work/tools/bin/cffconvert" --validate -i CITATION.cff

step "cargo publish --dry-run --workspace (the six floors and the shadelab crate, in order; python/ and web/engine/ are publish = false)"
# It says what it packaged for each crate ("Packaged N files, … compressed"), builds each against
# the others as packaged, and keeps no .crate file.
cargo publish --dry-run --workspace --exclude shadelab-python --exclude shadelab-web

step "maturin sdist and wheel of the Python package"
"$work/tools/bin/maturin" sdist -m python/Cargo.toml --out "$work/dist"
# In the root's target folder, as tests/python.rs builds it: the same compiled dependencies.
CARGO_TARGET_DIR=$root/target "$work/tools/bin/maturin" build --release --quiet \
  -m python/Cargo.toml --out "$work/dist"
ls -l "$work/dist"
sdist=$work/dist/shadelab-$version.tar.gz

step "twine check --strict (the metadata and long description PyPI validates) of both"
"$work/tools/bin/twine" check --strict "$work/dist"/*

step "the sdist installed by pip into a fresh venv, compiled from source"
python3 -m venv "$work/sdist-venv"
# What the suite uses beside the package: pytest, stimupy 1.2.0 (the comparisons with it) and
# nbclient with a kernel (the tutorial notebook); PsychoPy is left to .ci/run.
"$work/sdist-venv/bin/python" -m pip install --quiet --disable-pip-version-check \
  numpy pytest "stimupy==1.2.0" nbclient nbformat ipykernel
# pip unpacks the sdist into a temporary folder and builds it there with the maturin it
# installs for the build; the sdist's own crates are compiled anew (their folder is new), the
# registry's crates they depend on are taken compiled from the root's target folder (the same
# versions, from the same lock file).
CARGO_TARGET_DIR=$root/target "$work/sdist-venv/bin/python" -m pip install \
  --disable-pip-version-check --no-cache-dir "$sdist"
# The package is the installed one, in the venv's site-packages, and says this version.
(cd "$work/home" && "$work/sdist-venv/bin/python" - "$version" <<'PY'
import sys, importlib.metadata, shadelab
print(shadelab.__file__)
assert "site-packages" in shadelab.__file__, shadelab.__file__
assert shadelab.__version__ == importlib.metadata.version("shadelab") == sys.argv[1]
PY
)

step "the sdist's own test suite against the installed package"
tar xzf "$sdist" -C "$work/sdist"
tests=$work/sdist/shadelab-$version/python/tests
# The command line the suite compares with (SHADELAB_BIN): the program the first step's
# `cargo test` built from this commit (a `cargo build` would compile it again, without the
# tests' features of the shared dependencies).
test -x target/release/shadelab
# From a folder of its own, so that `import shadelab` is the installed package (the unpacked
# sdist's shadelab/ has no compiled module); a home of its own, as tests/python.rs runs the
# suite. PsychoPy is not installed here and ../shared's data is not beside the sdist, so the
# tests that need them say why they skip (-rs); those of stimupy and the notebook must run.
(cd "$work/home" && HOME="$work/home" PSYCHOPY_USERDIR="$work/home/.psychopy3" \
  SHADELAB_BIN="$root/target/release/shadelab" SHADELAB_REQUIRE_STIMUPY=1 \
  "$work/sdist-venv/bin/python" -m pytest -q -rs -p no:cacheprovider "$tests") \
  | tee "$work/pytest.txt"
if grep -E "^SKIPPED.*(stimupy|nbformat|nbclient|ipykernel)" "$work/pytest.txt"; then
  echo "tests skipped above although their packages were installed" >&2
  false
fi

step "the documentation site (docs/site/build.sh)"
bash docs/site/build.sh

step "nothing tracked changed, nothing published"
after=$(git status --porcelain)
if [[ $after != "$before" ]]; then
  echo "the dry run changed the working tree:" >&2
  diff <(echo "$before") <(echo "$after") >&2
  false
fi

step "all dry runs passed (shadelab $version, $SECONDS s)"
