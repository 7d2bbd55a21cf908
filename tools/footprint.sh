#!/usr/bin/env bash
# Flash and RAM footprint of firmware examples, from the linked ELF (llvm-size, Berkeley
# format): flash = .text + .data (initialised data is stored in flash), static RAM = .data +
# .bss. The stack is not included. Prints a markdown table.
#
#   tools/footprint.sh [example ...]     default: demo
set -euo pipefail
cd "$(dirname "$0")/.."
examples=("${@:-demo}")
size="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-size"
if [ ! -x "$size" ]; then
    echo "llvm-size is missing: rustup component add llvm-tools" >&2
    exit 127
fi
echo "| firmware | flash (bytes) | static RAM (bytes) |"
echo "|---|---|---|"
for ex in "${examples[@]}"; do
    cargo build -q --release --target thumbv7em-none-eabihf --example "$ex"
    elf="target/thumbv7em-none-eabihf/release/examples/$ex"
    read -r text data bss _ < <("$size" -B "$elf" | tail -n 1)
    echo "| \`$ex\` | $((text + data)) | $((data + bss)) |"
done
