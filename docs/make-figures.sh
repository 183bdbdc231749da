#!/usr/bin/env bash
# Makes every figure of docs/ with shadelab itself: nothing in docs/images/ is drawn by hand.
#
#   cargo build --release && bash docs/make-figures.sh
#
# Each figure's caption in the docs repeats the command below that made it. The work happens in
# a temporary folder; only the PNGs the pages show are copied to docs/images/. Stimulus pictures
# are written as 8-bit PNGs with display gamma 2.2 (as the gallery's thumbnails), so they look
# right on an ordinary screen; the real stimuli are linear (see docs/conventions.md).
# SHADELAB=path/to/shadelab uses another binary.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
S=${SHADELAB:-$root/target/release/shadelab}
if [[ ! -x $S ]]; then
  echo "no shadelab binary at $S: run cargo build --release first" >&2
  exit 1
fi
S=$(cd "$(dirname "$S")" && pwd)/$(basename "$S")
img=$root/docs/images
mkdir -p "$img"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

shadelab() { "$S" --quiet "$@"; }
# keep FILE NAME: copy one output into docs/images/NAME.
keep() { cp "$1" "$img/$2"; }
# show NAME ARGS...: render a stimulus picture for display (8-bit, gamma 2.2) as NAME.png.
show() {
  local name=$1
  shift
  shadelab render "$@" --bit-depth 8 --gamma 2.2 --out "$name.png"
  keep "$name.png" "$name.png"
}

echo "== the problem (docs/problem.md)"
shadelab render reflectance-map --light above-left --size 384 --bit-depth 8 --out rm-pq.png
keep rm-pq.png reflectance-map-pq.png
show sphere-above-left sphere --light above-left --size 192

echo "== f-g space (docs/fg-space.md)"
shadelab render reflectance-map --space fg --light above-left --size 384 --bit-depth 8 --out rm-fg.png
keep rm-fg.png reflectance-map-fg.png
shadelab render reflectance-map --space fg --light tilt=90,slant=75 --size 384 --bit-depth 8 --out rm-fg-grazing.png
keep rm-fg-grazing.png reflectance-map-fg-grazing.png
shadelab render reflectance-map --space pq --light tilt=90,slant=75 --size 384 --bit-depth 8 --out rm-pq-grazing.png
keep rm-pq-grazing.png reflectance-map-pq-grazing.png

echo "== priors (docs/priors.md)"
show prior-bumps --spec "$root/stimuli/bumps.json" --ppd 24
shadelab render bumps --set rows=1 --set columns=2 --set pattern=alternate --set spacing=3 \
  --size 96x48 --ppd 16 --out pair.png
shadelab analyze prior-sweep pair.png --mask pair_mask.png --out pair-sweep
keep pair-sweep/sweep.png prior-bumps-sweep.png
shadelab analyze observer --stimulus bumps --set rows=1 --set columns=1 --set pattern=bumps \
  --size 96 --ppd 32 --prior-kappa 1,2,4 --out bump-observer
keep bump-observer/p_convex.png prior-bumps-observer.png

show prior-crater --spec "$root/stimuli/crater.json" --ppd 24
show prior-crater-rotated --spec "$root/stimuli/crater-rotated.json" --ppd 24
shadelab analyze prior-sweep --stimulus crater --set rotation=180 --size 64 --ppd 10 --out crater-sweep
keep crater-sweep/sweep.png prior-crater-sweep.png

show prior-sideways --spec "$root/stimuli/sideways.json" --ppd 24
shadelab analyze prior-sweep --stimulus sideways --set rows=2 --set columns=1 --set pattern=rows \
  --size 64x128 --ppd 24 --out sideways-sweep
keep sideways-sweep/sweep.png prior-sideways-sweep.png

show prior-circles --spec "$root/stimuli/circles-gradient.json" --ppd 24
show prior-strips --spec "$root/stimuli/strips.json" --ppd 24
shadelab analyze prior-sweep --stimulus circles-gradient --set rows=2 --set columns=2 --ppd 16 \
  --tilts 0:360:15 --binding 0 --out circles-sweep
keep circles-sweep/sweep.png prior-circles-sweep.png

show prior-boundary-strips --spec "$root/stimuli/boundary-strips.json" --ppd 24
# The engine on the same strips: each strip solved on its own pixels, its outline an occluding
# boundary, the shading read as light from the left.
shadelab render boundary-strips --set boundary=sinusoidal,sawtooth --size 264x192 --ppd 24 --out strips2.png
shadelab solve strips2.png --mask strips2_mask.png --light left --boundary occluding --out strips2-sfs
keep strips2-sfs/normals.png prior-boundary-normals.png
shadelab analyze outline --stimulus boundary-strips --out strips-outline
for f in sinusoidal-strip-shape sinusoidal-strip-paint sawtooth-strip-shape sawtooth-strip-shading sawtooth-strip-paint; do
  keep "strips-outline/$f.png" "outline-$f.png"
done

show prior-hollow-mask --spec "$root/stimuli/hollow-mask.json" --ppd 24
show prior-hollow-mask-convex --spec "$root/stimuli/hollow-mask-convex.json" --ppd 24
show prior-hollow-mask-pair --spec "$root/stimuli/hollow-mask-pair.json" --ppd 24
shadelab analyze observer --stimulus hollow-mask --set face_width=4 --size 48x64 --ppd 10 \
  --domain tokens --convexity-bias 0 \
  --out mask-observer-0
keep mask-observer-0/p_convex.png prior-hollow-mask-observer.png
shadelab analyze observer --stimulus hollow-mask --set face_width=4 --size 48x64 --ppd 10 \
  --domain tokens --convexity-bias 4 \
  --out mask-observer-4
keep mask-observer-4/p_convex.png prior-hollow-mask-observer-bias4.png

echo "== Ikeuchi-Horn (docs/ikeuchi-horn.md)"
# The vase with the default multigrid iteration, and with plain Jacobi sweeps (the iteration
# as Ikeuchi and Horn wrote it, made stable); the bunny with multigrid.
for run in "vase multigrid" "vase jacobi" "bunny multigrid"; do
  read -r object method <<< "$run"
  if [[ ! -f $object.png ]]; then
    shadelab render "$object" --light above-left --size 256 --layers --out "$object.png"
    shadelab render "$object" --light above-left --size 256 --bit-depth 8 --gamma 2.2 --out "$object-show.png"
    keep "$object-show.png" "ih-$object-input.png"
    # The true depth under a light from the right, to compare the reconstruction with.
    shadelab render heightfield --set path="${object}_depth.npy" --light above-right \
      --bit-depth 8 --gamma 2.2 --out "$object-true-relit.png"
    keep "$object-true-relit.png" "ih-$object-true-relit.png"
  fi
  shadelab solve "$object.png" --mask "${object}_mask.png" --light above-left --method "$method" \
    --out "$object-$method"
  if [[ $object == vase ]]; then
    keep "$object-$method/convergence.png" "ih-$object-$method-convergence.png"
  fi
  if [[ $method == multigrid ]]; then
    keep "$object-$method/normals.png" "ih-$object-normals.png"
    # The recovered depth under a light from the right: a view the input never showed.
    shadelab render heightfield --set path="$object-$method/depth.npy" --light above-right \
      --bit-depth 8 --gamma 2.2 --out "$object-relit.png"
    keep "$object-relit.png" "ih-$object-relit.png"
  fi
done

echo "== lightness (docs/lightness.md)"
show checker-shadow --spec "$root/stimuli/checker-shadow.json"
shadelab analyze lightness --stimulus checker-shadow --model all --out checker
for model in odog flodog retinex; do
  keep "checker/lightness_$model.png" "checker-shadow-$model.png"
done
show fading-disk --spec "$root/stimuli/fading-disk.json"
shadelab analyze fading --stimulus fading-disk --ppd 12 --out fading
keep fading/fading.gif fading-disk-animation.gif

echo "== experiments.md: the worked example (Mamassian & Goutcher's design, simulated)"
# The page's own pilot mode answers the trials (headless Chromium); without Chromium the same
# model is simulated by the library (examples/fit_recovery.rs), with other random draws.
shadelab experiment --out mg --repeats 20 >/dev/null
# The study runs on jsPsych, which `shadelab experiment` installs with npm (mg/node_modules).
if command -v chromium >/dev/null && [[ -d mg/node_modules/jspsych ]]; then
  chromium --headless --no-sandbox --disable-gpu --virtual-time-budget=10000 --dump-dom \
    "file://$work/mg/index.html?simulate=tilt:26,kappa:2,convex:0.6,lapse:0.03,seed:1" 2>/dev/null |
    python3 -c 'import html, re, sys; print(html.unescape(re.search(r"<pre id=\"results\">(.*?)</pre>", sys.stdin.read(), re.S).group(1)), end="")' \
    >responses.csv
else
  echo "chromium or jsPsych (npm) not found: the worked example's responses come from the library instead" >&2
  (cd "$root" && cargo run --quiet --release --example fit_recovery -- worked "$work/responses.csv")
fi
shadelab fit observer responses.csv --include-simulated --out mg-fit --design mg/design.json
keep mg-fit/fit.png experiments-fit.png

echo "== the tutorial (docs/tutorial.md): its own sh blocks, run as written"
mkdir tutorial
(cd tutorial && PATH="$(dirname "$S"):$PATH" bash -euo pipefail -c \
  "$(awk '/^```sh$/{on=1; next} /^```$/{on=0} on' "$root/docs/tutorial.md")" > /dev/null)
keep tutorial/sweep/sweep.png tutorial-sweep.png
keep tutorial/observer/p_convex.png tutorial-observer.png
keep tutorial/bump.png tutorial-bump.png

du -ch "$img"/* | tail -1
