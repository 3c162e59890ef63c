#!/usr/bin/env bash
# Set everything up and run the checks: ruff, then the whole test suite (slow real-model tests included).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh
echo
echo "==> headless Chromium for the web page's browser test"
bash scripts/install-browser.sh
echo
echo "==> ruff"
.venv/bin/ruff check src tests benchmarks
.venv/bin/ruff format --check src tests benchmarks
echo
echo "==> pytest"
.venv/bin/python -m pytest "$@"
