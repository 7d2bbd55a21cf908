#!/usr/bin/env bash
# Runs a command with no Python on PATH: stand-ins for `python3`, `python` and `python3.N`
# first on PATH record every call and exit 1 (an absolute path such as /usr/bin/python3 is
# not caught; the tests name programs, never paths). Exits 1, naming the calls, when anything started Python;
# otherwise with the command's own status.
#
#   tools/no-python.sh cargo test --workspace
set -uo pipefail
stand_in=$(mktemp -d)
trap 'rm -rf "$stand_in"' EXIT
for name in python3 python python3.{8..14}; do
    printf '#!/bin/sh\necho "%s $*" >> "%s/calls"\nexit 1\n' "$name" "$stand_in" > "$stand_in/$name"
    chmod +x "$stand_in/$name"
done
PATH="$stand_in:$PATH" "$@"
status=$?
if [ -s "$stand_in/calls" ]; then
    echo "no-python: the command started Python (which is not reachable here):" >&2
    sed 's/^/    /' "$stand_in/calls" >&2
    exit 1
fi
exit "$status"
