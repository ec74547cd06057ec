#!/usr/bin/env bash
# Set-up and the whole test suite: installs the Vulkan driver, Node.js and
# Xvfb if needed, the glTF validator into tools/, builds the browser lab
# (out/web/, which tests/web.rs opens in headless Chromium), then runs
# every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
bash scripts/web.sh
cargo test --release --locked "$@"
