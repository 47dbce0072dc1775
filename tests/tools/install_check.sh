#!/bin/sh
# install_check.sh: cmake --install puts loadid in place (into a scratch
# DESTDIR), and what it installed works: the programs run, the installed
# configuration reads the installed robot, the unit starts the installed
# loadidd, the lcm-spy launcher finds the installed jar, the installed
# `loadid plot` finds its script and draws, and a second install keeps a
# site's own /etc/loadid/loadid.yaml.
# Usage: install_check.sh BUILD_DIR JAR GOLDEN_DIR [PYTHON] (JAR empty: built
# without Java, so no lcm-spy launcher and jar are expected; PYTHON: one with
# numpy and matplotlib for loadid plot, the venv's; empty: the plot is not
# drawn, which is said)
set -eu
build=$1 jar=$2 golden=$3 python=${4:-}
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
DESTDIR=$root cmake --install "$build" --prefix /usr/local >"$root.log" 2>&1 ||
    { cat "$root.log"; rm -f "$root.log"; exit 1; }
fail() { echo "install_check: $*" >&2; exit 1; }
for f in bin/loadidd bin/loadid bin/loadid-traj bin/loadid-sim bin/loadid-kappa bin/loadid-demo \
         bin/loadid-replay bin/loadid-record bin/loadid-modbus-sim; do
    [ -x "$root/usr/local/$f" ] || fail "$f not installed as a program"
done
if [ -n "$jar" ]; then
    [ -x "$root/usr/local/bin/loadid-spy" ] || fail "loadid-spy not installed as a program"
    [ -f "$root/usr/local/share/loadid/loadid_lcmtypes.jar" ] || fail "the lcm-spy jar is missing"
fi
[ -f "$root/etc/loadid/loadid.yaml" ] && [ -f "$root/etc/loadid/robots/rx60.urdf" ] ||
    fail "/etc/loadid is incomplete"
unit=$root/usr/local/lib/systemd/system/loadidd.service
grep -qx 'ExecStart=/usr/local/bin/loadidd --config /etc/loadid/loadid.yaml' "$unit" ||
    fail "the unit does not start the installed loadidd"
"$root/usr/local/bin/loadidd" --help >/dev/null || fail "loadidd --help"
[ -z "$jar" ] || "$root/usr/local/bin/loadid-spy" --help | grep -q "share/loadid" ||
    fail "loadid-spy --help"
# The installed configuration, with its robot, estimates the golden recording.
rec=$root/rec
mkdir "$rec"
gzip -dc "$golden/can.log.gz" >"$rec/can.log"
gzip -dc "$golden/lcm.log.gz" >"$rec/lcm.log"
"$root/usr/local/bin/loadidd" --config "$root/etc/loadid/loadid.yaml" --offline "$rec" \
    --result "$root/result.json" || fail "the installed configuration does not estimate"
grep -q '"method": "RTLS", "load_name": "o1", "samples": 1500' "$root/result.json" ||
    fail "no RTLS estimate of 1500 samples"
# loadid plot as installed: its script in share/loadid, found beside the
# program; the golden recording estimated by the installed loadidd and drawn.
[ -f "$root/usr/local/share/loadid/loadid_plot.py" ] || fail "loadid plot's script is missing"
if [ -n "$python" ]; then
    LOADID_PYTHON=$python "$root/usr/local/bin/loadid" plot --config "$root/etc/loadid/loadid.yaml" \
        "$rec" --out "$root/plots" >"$root/plot.log" 2>&1 || { cat "$root/plot.log"; fail "loadid plot"; }
    for f in trace-estimates.png trace-residual.png trace-residual.csv result.json; do
        [ -s "$root/plots/$f" ] || fail "loadid plot did not write $f"
    done
    plotted="; loadid plot drew the golden recording"
else
    plotted="; loadid plot not drawn (no Python given)"
fi
# A site's configuration survives the next install.
echo "# the site's" >>"$root/etc/loadid/loadid.yaml"
DESTDIR=$root cmake --install "$build" --prefix /usr/local >"$root.log" 2>&1 || fail "reinstall"
grep -q "Kept: $root/etc/loadid/loadid.yaml" "$root.log" || fail "no 'Kept' line"
rm -f "$root.log"
tail -1 "$root/etc/loadid/loadid.yaml" | grep -qx "# the site's" || fail "the site's configuration was overwritten"
echo "install_check: $(find "$root" -type f | wc -l) files installed; all in place and working$plotted"
