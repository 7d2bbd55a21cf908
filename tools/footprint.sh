#!/usr/bin/env bash
# Flash and RAM footprint of firmware examples, from the linked ELF (llvm-size, Berkeley
# format): flash = .text + .data (initialised data is stored in flash), static RAM = .data +
# .bss. The stack is not included. Prints a markdown table.
#
#   tools/footprint.sh [--target TRIPLE] [example ...]
#
# Default example: demo. Default target: thumbv7em-none-eabihf (the Cortex-M4F); any bare-metal
# ARM target the examples build for works (thumbv7m-none-eabi, thumbv6m-none-eabi), and is added
# with rustup where it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
target=thumbv7em-none-eabihf
if [ "${1:-}" = --target ]; then
    target=${2:?usage: tools/footprint.sh [--target TRIPLE] [example ...]}
    shift 2
fi
examples=("${@:-demo}")
size="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-size"
if [ ! -x "$size" ]; then
    echo "llvm-size is missing: rustup component add llvm-tools" >&2
    exit 127
fi
rustup target list --installed | grep -qx "$target" || rustup target add "$target" >&2
echo "| firmware | flash (bytes) | static RAM (bytes) |"
echo "|---|---|---|"
for ex in "${examples[@]}"; do
    cargo build -q --release --target "$target" --example "$ex"
    elf="target/$target/release/examples/$ex"
    read -r text data bss _ < <("$size" -B "$elf" | tail -n 1)
    echo "| \`$ex\` | $((text + data)) | $((data + bss)) |"
done
