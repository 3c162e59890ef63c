#!/usr/bin/env bash
# Build ros2/conceptbot_interfaces (the Plan action, the Answer service, Detection and Scene) with the
# ROS wheels' ament_cmake and rosidl generators, and install it into .venv, so that
# `from conceptbot_interfaces.action import Plan` works there. No ROS installation and no colcon:
# CMake finds the wheels' packages under .venv/share. Skipped when the installed build is of the
# same interface files (a stamp holds their hash); FORCE=1 rebuilds. About 30 s on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=$(pwd)/.venv
SOURCE=ros2/conceptbot_interfaces
BUILD=build/conceptbot_interfaces
STAMP=$VENV/share/conceptbot_interfaces/source.sha256

hash=$(cat "$SOURCE"/CMakeLists.txt "$SOURCE"/package.xml "$SOURCE"/*/*.msg "$SOURCE"/*/*.srv \
  "$SOURCE"/*/*.action | sha256sum | cut -d' ' -f1)
if [ "${FORCE:-0}" != 1 ] && [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$hash" ] \
  && "$VENV/bin/python" -c 'import conceptbot_interfaces.action' 2>/dev/null; then
  echo "conceptbot_interfaces is built from these files already"
  exit 0
fi
command -v cmake >/dev/null || { echo "building conceptbot_interfaces needs cmake (apt-get install cmake)" >&2; exit 1; }

# ament_cmake finds the typesupports through the ament index, which it reads from AMENT_PREFIX_PATH.
export AMENT_PREFIX_PATH=$VENV PATH=$VENV/bin:$PATH
rm -rf "$BUILD"
mkdir -p "$BUILD"
cmake -S "$SOURCE" -B "$BUILD" -DCMAKE_PREFIX_PATH="$VENV" -DCMAKE_INSTALL_PREFIX="$VENV" \
  -DPython3_EXECUTABLE="$VENV/bin/python" -DBUILD_TESTING=OFF >"$BUILD.log" 2>&1 \
  || { tail -30 "$BUILD.log" >&2; echo "configuring conceptbot_interfaces failed: $BUILD.log" >&2; exit 1; }
cmake --build "$BUILD" -j "$(nproc)" >>"$BUILD.log" 2>&1 \
  || { tail -30 "$BUILD.log" >&2; echo "building conceptbot_interfaces failed: $BUILD.log" >&2; exit 1; }
cmake --install "$BUILD" >>"$BUILD.log" 2>&1 \
  || { tail -30 "$BUILD.log" >&2; echo "installing conceptbot_interfaces failed: $BUILD.log" >&2; exit 1; }
"$VENV/bin/python" -c 'from conceptbot_interfaces.action import Plan; from conceptbot_interfaces.srv import Answer'
echo "$hash" >"$STAMP"
echo "conceptbot_interfaces built and installed into .venv"
