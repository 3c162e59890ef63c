#!/usr/bin/env bash
# Set everything up, check it, and run the main job on the embedded defaults (no keys, no network).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh
echo
.venv/bin/conceptbot doctor
echo
echo '$ conceptbot llm --system "You are a kitchen robot..." "I would like a hollandaise sauce. ..."'
.venv/bin/conceptbot llm \
  --system "You are a kitchen robot. You can pick up objects and place them somewhere. Be brief." \
  "I would like a hollandaise sauce. Which of these should you bring me: eggs, butter, lemon, chips, sponge?" \
  --max-tokens 120
