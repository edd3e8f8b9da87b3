#!/usr/bin/env bash
# Update constraints.txt on purpose: install the newest versions that
# pyproject.toml allows into a scratch venv, run the whole test suite with it,
# and rewrite constraints.txt only when the suite passes.  Run from anywhere,
# after scripts/install.sh has installed the system packages.
#   bash scripts/update_constraints.sh            # update when green
#   bash scripts/update_constraints.sh --check    # only report (exit 1 when the newest versions fail)
set -euo pipefail
cd "$(dirname "$0")/.."
check_only=0
[ "${1:-}" = "--check" ] && check_only=1
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
python3 -m venv "$scratch/venv"
"$scratch/venv/bin/python" -m pip install -q --upgrade pip setuptools
"$scratch/venv/bin/python" -m pip install -q -e '.[test,docs]'
echo "update_constraints: newest allowed versions:"
"$scratch/venv/bin/python" -m pip freeze --exclude-editable | sed 's/^/  /'
if ! "$scratch/venv/bin/python" -m pytest -q -p no:cacheprovider; then
    echo "update_constraints: the suite FAILS with the newest allowed versions; constraints.txt unchanged" >&2
    exit 1
fi
if [ "$check_only" = 1 ]; then
    echo "update_constraints: the suite passes with the newest allowed versions (--check: nothing written)"
    exit 0
fi
{
    sed -n '/^#/p' constraints.txt | sed '/^# build backend/,$d'
    "$scratch/venv/bin/python" -m pip freeze --exclude-editable
    echo "# build backend of \`pip install -e .\` (pyproject.toml: setuptools>=77) and the installer"
    "$scratch/venv/bin/python" -m pip list --format=freeze | grep -E '^(setuptools|pip)=='
} > constraints.txt.new
mv constraints.txt.new constraints.txt
echo "update_constraints: constraints.txt rewritten; reinstall with scripts/install.sh and commit it"
