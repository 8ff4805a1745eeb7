#!/usr/bin/env bash
# Draws an antenna array file of share/arrays/ as seen from above, in the sensor's frame (x
# forward = up in the picture, y left = left), each element with its index (= receive core)
# and position, plus the mirror ambiguity of a linear array.
#   bash scripts/draw-array.sh share/arrays/rt-ac86u.yaml docs/img/rt-ac86u-array.png
set -euo pipefail
in=${1:?usage: draw-array.sh ARRAY.yaml OUT.png}
out=${2:?usage: draw-array.sh ARRAY.yaml OUT.png}
[ -r "$in" ] || { echo "draw-array.sh: cannot read $in" >&2; exit 1; }
command -v gnuplot >/dev/null || { echo "draw-array.sh: gnuplot is not installed (Debian: gnuplot-nox)" >&2; exit 1; }
name=$(sed -n 's/^name: *//p' "$in")
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# elements: "  - [x, y]" lines after "elements:" -> "index x_mm y_mm"
awk '/^elements:/ {on = 1; next}
     on && /^ *- *\[/ {sub(/^ *- */, ""); gsub(/[][,]/, " "); split($0, v, " ");
                        printf "%d %.1f %.1f\n", n++, v[1] * 1000, v[2] * 1000; next}
     on {on = 0}' "$in" >"$tmp/elements.txt"
[ -s "$tmp/elements.txt" ] || { echo "draw-array.sh: no elements in $in" >&2; exit 1; }
ymax=$(awk 'BEGIN {m = 0} {if ($3 > m) m = $3} END {print m}' "$tmp/elements.txt")
gnuplot <<GP
set terminal pngcairo size 760,560 font "DejaVu Sans,11"
set output "$out"
set title "$name antenna array seen from above (sensor frame; file $(basename "$in"))"
set size ratio -1
unset key; unset border; unset xtics; unset ytics
# picture x = -y (left is left), picture y = x (forward is up); mm
set xrange [-$ymax - 45 : 95]
set yrange [-60 : 70]
set arrow 1 from 60,-30 to 60,30 lw 2 lc rgb "black"
set label 1 "x: forward" at 60,36 center
set arrow 2 from 60,-30 to 20,-30 lw 2 lc rgb "black"
set label 2 "y: left" at 20,-38 center
set label 3 "the sensor's axes" at 40,-50 center font ",9"
set arrow 3 from 12,0 to -$ymax - 12,0 nohead dt 2 lc rgb "gray50"
set label 4 "array axis: a transmitter at {/Symbol q} and at 180°-{/Symbol q} (its mirror) give the same CSI" at -$ymax/2 + 20,-58 center font ",10" tc rgb "gray30"
set label 5 "AoA {/Symbol q}: from x (forward), counter-clockwise; element 0 is the sensor's origin" at -$ymax/2 + 20,60 center font ",10" tc rgb "gray30"
plot "$tmp/elements.txt" using (-\$3):(\$2) with points pt 7 ps 3 lc rgb "#1f77b4", \
     "" using (-\$3):(\$2 + 16):(sprintf("element %d\\ncore %d", \$1, \$1)) with labels font ",10", \
     "" using (-\$3):(\$2 - 13):(sprintf("y = %g mm", \$3)) with labels font ",9"
GP
echo "wrote $out"
