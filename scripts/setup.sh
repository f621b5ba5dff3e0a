#!/usr/bin/env bash
# Installs the Debian packages, configures (Release) and builds p2i into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
# npm interop test clients (tests/js: @mcap/core, @foxglove/ws-protocol, pinned in
# package-lock.json). node/npm are not Debian packages here: without them, or without the
# registry, the two js_interop tests report "Skipped". Nothing downloads at test or run time.
if command -v npm >/dev/null 2>&1 && command -v node >/dev/null 2>&1; then
  (cd tests/js && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "setup: npm ci in tests/js failed: the js_interop tests will be skipped"
else
  echo "setup: node/npm not found: the js_interop tests will be skipped"
fi
