#!/usr/bin/env bash
# The main job: bash run.sh [COMMAND ARGS...]; with no arguments, the default job.
# Installs what it needs on first use (see scripts/env.sh).
source "$(dirname "$0")/scripts/env.sh"
if [ $# -eq 0 ]; then
    set -- study --quick
fi
exec bayes-inerter "$@"
