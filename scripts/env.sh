# Sourced by run.sh and test.sh: make (once) and activate the project's virtual
# environment in .venv, installing the package and its dependencies on first use and
# again whenever pyproject.toml changes.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PYTHON="${PYTHON:-python3}"
VENV="${BAYES_INERTER_VENV:-$ROOT/.venv}"
if [ ! -x "$VENV/bin/python" ]; then
    echo "setting up $VENV (first use) ..." >&2
    "$PYTHON" -m venv "$VENV"
fi
STAMP="$VENV/.bayes-inerter-installed"
WANT="$(sha256sum "$ROOT/pyproject.toml" | cut -c1-16)"
if [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$WANT" ]; then
    echo "installing bayes-inerter and its dependencies into $VENV ..." >&2
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -e "$ROOT[test,dask]" 2> >(grep -v '^WARNING: Location' >&2)
    echo "$WANT" > "$STAMP"
fi
export PATH="$VENV/bin:$PATH"
cd "$ROOT"
