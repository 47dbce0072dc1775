#!/bin/sh
# update_golden.sh: writes tests/data/golden/expected.json, the result of
# loadidd --offline on the committed golden recording (test_golden.py
# compares every run to it to 1e-9). Run it only when a change is meant to
# alter the estimates, and say why in the commit that updates the file.
# Usage: tests/tools/update_golden.sh [LOADIDD] (default: the release build's)
set -eu
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
    sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
    exit 0
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
loadidd=${1:-$root/build/release/host/loadidd}
golden=$root/tests/data/golden
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gzip -dc "$golden/can.log.gz" > "$tmp/can.log"
gzip -dc "$golden/lcm.log.gz" > "$tmp/lcm.log"
"$loadidd" --config "$golden/loadid.yaml" --offline "$tmp" --result "$golden/expected.json"
echo "update_golden.sh: wrote $golden/expected.json"
