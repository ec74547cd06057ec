#!/usr/bin/env bash
# Builds the lab for the browser into out/web/: static files only (the
# page, its script and style, wasm-bindgen's JS glue and the wasm), servable
# by any static server, nothing fetched at run time. Installs what it needs
# as setup.sh does: Debian's browser-vendor Rust (rustc-web, with the
# standard library's sources, since rustup's toolchain has no wasm32
# target here), lld's wasm-ld, and wasm-bindgen-cli of the version in
# Cargo.lock (into tools/wasm-bindgen). Serve with, e.g.,
#   python3 -m http.server -d out/web 8000
# and open http://127.0.0.1:8000/?scene=room&light=point&compare=1
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/packages.sh
need=()
for p in rustc-web cargo-web rust-web-src lld; do
  have_pkg "$p" || need+=("$p")
done
install_missing web "${need[@]}"

# wasm-bindgen's CLI must be exactly the crate's version.
BINDGEN_VERSION=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' Cargo.lock)
BINDGEN=tools/wasm-bindgen/bin/wasm-bindgen
if [[ "$("$BINDGEN" --version 2>/dev/null)" != "wasm-bindgen $BINDGEN_VERSION" ]]; then
  echo "web: installing wasm-bindgen-cli $BINDGEN_VERSION into tools/wasm-bindgen"
  cargo install wasm-bindgen-cli --quiet --version "$BINDGEN_VERSION" --root tools/wasm-bindgen
fi

echo "web: building the library for wasm32 (target/web)"
start=$(date +%s)
PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 \
  CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld \
  RUSTFLAGS='--cfg getrandom_backend="wasm_js"' \
  /usr/bin/cargo rustc --quiet --lib --release --no-default-features \
  --target wasm32-unknown-unknown -Zbuild-std=std,panic_abort \
  --target-dir target/web --crate-type cdylib

rm -rf out/web
mkdir -p out/web
"$BINDGEN" --target web --no-typescript --out-dir out/web --out-name shadowlab \
  target/web/wasm32-unknown-unknown/release/shadowlab.wasm
cp web/index.html web/main.js web/style.css out/web/
echo "web: out/web/ in $(($(date +%s) - start)) s, $(du -sh out/web | cut -f1): $(ls out/web | tr '\n' ' ')"
