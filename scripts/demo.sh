#!/usr/bin/env bash
# Set-up and main job: installs the Vulkan driver if needed, builds in
# release mode and renders the built-in `room` scene into out/room/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --locked
./target/release/shadowlab render --scene room --out out/room "$@"
echo "wrote out/room/image.png, out/room/visibility-0.png, out/room/frame.json"
