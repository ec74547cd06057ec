#!/usr/bin/env bash
# Set-up and main job: installs the Vulkan driver if needed, builds in
# release mode, renders the built-in `room` scene with shadow maps into
# out/room/ and measures every technique against the ray-traced reference
# on it into out/compare/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --locked
./target/release/shadowlab render --scene room --technique shadow-map --out out/room "$@"
./target/release/shadowlab compare --scene room --techniques all --out out/compare
echo "wrote out/room/{image.png,visibility-0.png,frame.json} and out/compare/quality.md"
