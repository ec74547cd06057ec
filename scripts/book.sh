#!/usr/bin/env bash
# Regenerates the guide's generated pages from the binary (the technique
# reference and the CLI reference) and builds the guide into out/book.
# Usage: scripts/book.sh [--figures]   (after `cargo build --release`;
# mdbook from `scripts/setup.sh --test`, in tools/mdbook). --figures also
# re-renders the failure figures and their captions (about a minute).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/shadowlab
$bin techniques --markdown > docs/book/src/techniques/parameters.md
$bin cli-markdown > docs/book/src/cli-reference.md
if [[ "${1:-}" == "--figures" ]]; then
  $bin guide-figures --out docs/book/src
fi
tools/mdbook/bin/mdbook build docs/book --dest-dir out/book
echo "book: out/book/index.html"
