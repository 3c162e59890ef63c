#!/usr/bin/env bash
# Install headless Chromium and its WebDriver from Debian for the web page's browser test.
# Pinned to the version the test was written against; when the archive has moved on (Debian replaces
# security builds), the current build is installed instead and its version is printed.
set -euo pipefail
PIN=156.0.8078.79-1~deb12u1
if command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1; then
  echo "chromium already installed: $(chromium --version 2>/dev/null || true)"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
if ! $SUDO apt-get install -y -qq "chromium=$PIN" "chromium-common=$PIN" "chromium-driver=$PIN" >/dev/null; then
  echo "chromium $PIN is no longer in the archive; installing the current build" >&2
  $SUDO apt-get install -y -qq chromium chromium-driver >/dev/null
fi
echo "installed: $(chromium --version 2>/dev/null || echo chromium)"
