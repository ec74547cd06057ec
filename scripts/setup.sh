#!/usr/bin/env bash
# Installs the system packages shadowlab needs on Debian/Ubuntu: a Vulkan
# driver (Mesa's lavapipe runs everywhere, GPU or not), Embree 3 and, for the tests,
# Node.js (the Khronos glTF validator), Xvfb (the viewer test), Chromium
# (the report's HTML opened in a real browser) and mdBook (the guide).
# Usage: scripts/setup.sh [--test]
set -euo pipefail

source "$(dirname "$0")/packages.sh"
need=()
have_pkg mesa-vulkan-drivers || need+=(mesa-vulkan-drivers)
have_pkg libvulkan1 || need+=(libvulkan1)
# Embree 3: the reference's fast ray-tracing kernel (loaded at run time;
# without it the reference falls back to its pure-Rust kernel).
have_pkg libembree3-3 || need+=(libembree3-3)
if [[ "${1:-}" == "--test" ]]; then
  command -v node >/dev/null || need+=(nodejs)
  command -v npm >/dev/null || need+=(npm)
  have_pkg xvfb || need+=(xvfb)
  have_pkg xauth || need+=(xauth)
  command -v chromium >/dev/null || need+=(chromium)
fi

install_missing setup "${need[@]}"

if [[ "${1:-}" == "--test" ]]; then
  cd "$(dirname "$0")/.."
  npm ci --prefix tools --no-audit --no-fund --silent
  # mdBook builds the user guide (docs/book) in the tests; a pinned
  # version from crates.io, without its server and file watcher.
  MDBOOK_VERSION=0.5.4
  if [[ "$(tools/mdbook/bin/mdbook --version 2>/dev/null)" != "mdbook v$MDBOOK_VERSION" ]]; then
    echo "setup: installing mdbook $MDBOOK_VERSION into tools/mdbook"
    cargo install mdbook --locked --quiet --version "$MDBOOK_VERSION" \
      --no-default-features --features search --root tools/mdbook
  fi
fi
