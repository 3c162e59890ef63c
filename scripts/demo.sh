#!/usr/bin/env bash
# Set everything up, check it, and run the main job on the embedded defaults (no keys, no network).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh
echo
.venv/bin/conceptbot doctor
echo
echo '$ conceptbot plan "I would like a hollandaise sauce" --scene kitchen'
echo '(first run: one scored question per object of the 25-object kitchen, about half a minute on'
echo ' 2 cores; later runs come from the cache in seconds)'
.venv/bin/conceptbot plan "I would like a hollandaise sauce" --scene kitchen
