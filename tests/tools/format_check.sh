#!/bin/sh
# format_check.sh SOURCE_DIR: every C and C++ file of the repository is as
# clang-format (14, .clang-format at the root) writes it. Exits 1 and names
# the files that differ (fix: clang-format -i FILE), 77 (skipped) when
# clang-format is missing, 1 then under CI=true: tools/setup.sh test
# installs it.
set -eu
src=$1
if ! command -v clang-format >/dev/null 2>&1; then
    echo "clang-format not installed (tools/setup.sh test installs it)" >&2
    [ "${CI:-}" = true ] && exit 1
    exit 77
fi
cd "$src"
files=$(find drivers firmware host proto tests tools -name '*.[ch]' -o -name '*.[ch]pp' | sort)
bad=0
for f in $files; do
    if ! clang-format --dry-run -Werror "$f" >/dev/null 2>&1; then
        echo "not formatted: $f (clang-format -i $f)"
        bad=1
    fi
done
[ "$bad" -eq 0 ] && echo "format_check: $(echo "$files" | wc -l) files formatted"
exit "$bad"
