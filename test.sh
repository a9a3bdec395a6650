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
# Two workers on two cores: each keeps its BLAS to one thread, or the workers' thread pools
# oversubscribe the cores (a test's SVDs ran 3 to 20 times slower beside the other worker).
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" \
    MKL_NUM_THREADS="${MKL_NUM_THREADS:-1}"
exec python -m pytest -m "not slow" -n 2 --dist loadgroup "$@"
