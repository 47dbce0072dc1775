#!/bin/sh
# The README's main job runs and its RTLS estimate of o1 is close: mass
# within 5 %, the mean eq. (37) error of the ten parameters within 15 %.
# Usage: demo_check.sh LOADID_DEMO
set -eu
out=$("$1" --seed 3)
echo "$out"
echo "$out" | awk '
    $1 == "param" { for (i = 1; i <= NF; ++i) if ($i == "RTLS") col = i + 1 }
    col && $1 ~ /^(m|m\*c[xyz]|I[xyz][xyz])$/ { e[$1] = $col; sum += $col; n++ }
    END {
        if (n != 10) { print "no RTLS column in the table" > "/dev/stderr"; exit 1 }
        printf "RTLS: mass error %s %%, mean error %.2f %%\n", e["m"], sum / n
        if (e["m"] + 0 > 5 || sum / n > 15) { print "RTLS too far from o1" > "/dev/stderr"; exit 1 }
    }'
