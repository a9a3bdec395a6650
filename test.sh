#!/usr/bin/env bash
# The tests: bash test.sh runs the quick subset (what CI runs); bash test.sh --all runs
# every test, slow ones included. The quick subset runs on two worker processes
# (pytest-xdist; -n 0 after it runs it in one), a module marked with an xdist_group on
# one of them. Extra arguments go to pytest.
# Installs what it needs on first use (see scripts/env.sh).
source "$(dirname "$0")/scripts/env.sh"
if [ "${1:-}" = "--all" ]; then
    shift
    exec python -m pytest "$@"
fi
exec python -m pytest -m "not slow" -n 2 --dist loadgroup "$@"
