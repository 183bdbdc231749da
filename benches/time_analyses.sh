#!/bin/bash
# Times every `analyze` subcommand on every gallery stimulus (the PNGs `shadelab gallery --out
# GALLERYDIR` wrote), 2 threads: wall seconds, peak RSS and the load average before each run
# (docs/performance.md, "Commands and analyses").
# usage: benches/time_analyses.sh BINARY GALLERYDIR OUTCSV [subcommands...]
# subcommands default to: lightness-retinex lightness-odog fading prior-sweep observer
B=$1; G=$2; OUT=$3; shift 3
SUBS=${@:-lightness-retinex lightness-odog fading prior-sweep observer}
W=$(mktemp -d)
echo "subcommand,stimulus,seconds,maxrss_kb,rc,load" > $OUT
for sub in $SUBS; do
  for f in $G/*.png; do
    s=$(basename $f .png)
    case $s in *_mask|gallery) continue;; esac
    case $sub in
      lightness-*) args="lightness --model ${sub#lightness-}";;
      *) args=$sub;;
    esac
    rm -rf $W/o
    load=$(cut -d' ' -f1 /proc/loadavg)
    /usr/bin/time -f "%e %M" -o $W/t $B --threads 2 --quiet analyze $args $f --out $W/o >/dev/null 2>$W/err
    rc=$?
    read sec rss < <(tail -1 $W/t)
    [ $rc -ne 0 ] && { sec=NA; msg=$(tail -1 $W/err | cut -c1-100); }
    echo "$sub,$s,$sec,$rss,$rc,$load${msg:+,$msg}" | tee -a $OUT
    msg=
  done
done
rm -rf $W
