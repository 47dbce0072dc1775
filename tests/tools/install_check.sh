#!/bin/sh
# install_check.sh: cmake --install puts loadid in place (into a scratch
# DESTDIR), and what it installed works: the programs run, the installed
# configuration reads the installed robot, the unit starts the installed
# loadidd, the lcm-spy launcher finds the installed jar, and a second
# install keeps a site's own /etc/loadid/loadid.yaml.
# Usage: install_check.sh BUILD_DIR JAR GOLDEN_DIR (JAR empty: built without
# Java, so no lcm-spy launcher and jar are expected)
set -eu
build=$1 jar=$2 golden=$3
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
# A site's configuration survives the next install.
echo "# the site's" >>"$root/etc/loadid/loadid.yaml"
DESTDIR=$root cmake --install "$build" --prefix /usr/local >"$root.log" 2>&1 || fail "reinstall"
grep -q "Kept: $root/etc/loadid/loadid.yaml" "$root.log" || fail "no 'Kept' line"
rm -f "$root.log"
tail -1 "$root/etc/loadid/loadid.yaml" | grep -qx "# the site's" || fail "the site's configuration was overwritten"
echo "install_check: $(find "$root" -type f | wc -l) files installed; all in place and working"
