#!/usr/bin/env bash
# Set-up and main job: installs the Vulkan driver if needed, builds in
# release mode and writes the comparison of every technique preset on the
# quick matrix of views into out/report/ (index.html, report.md,
# results.csv, results.json). Extra arguments go to `shadowlab report`
# (e.g. --preset standard); a second run reuses the cells already measured.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# The report needs no window: the viewer (egui, winit) is left out of this
# build; `cargo build --release` adds it.
cargo build --release --locked --no-default-features
./target/release/shadowlab report --preset quick --out out/report "$@"
echo "open out/report/index.html (or read out/report/report.md)"
