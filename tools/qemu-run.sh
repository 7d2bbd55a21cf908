#!/usr/bin/env bash
# Run a thumbv7em-none-eabihf firmware ELF on QEMU's emulated Cortex-M4F (Arm MPS2 AN386).
# Builds for thumbv7m-none-eabi and thumbv6m-none-eabi (Cortex-M3, Cortex-M0+) run on it too:
# their instructions are a subset of the Cortex-M4F's.
#
#   tools/qemu-run.sh path/to/firmware.elf
#
# Cargo calls this as the runner for bare-metal ARM (.cargo/config.toml), so
# `cargo qemu selftest` builds the `selftest` example and ends up here.
#
# - Semihosting is on: the firmware writes its defmt frames to the host's stdout and ends the
#   run with a semihosting exit, whose status becomes this script's exit status.
# - `-icount shift=0`: one executed instruction per virtual nanosecond, so the AN386 SysTick
#   (25 MHz reference) decrements once per 40 executed instructions. Instruction counts measured
#   this way are instruction counts, not cycles.
# - When the ELF carries a `.defmt` section, stdout is decoded with `defmt-print`.
# - A run that does not end within QEMU_RUN_TIMEOUT seconds (default 120) is killed; the
#   script then prints a line saying so and exits 124.
#
# Missing tools are installed where that is possible without asking (root or passwordless sudo
# for apt-get; cargo for defmt-print). Otherwise the script prints the one command to run and
# exits 127.
set -euo pipefail

elf=${1:?usage: tools/qemu-run.sh FIRMWARE.elf}
timeout_s=${QEMU_RUN_TIMEOUT:-120}

say() { printf 'qemu-run: %s\n' "$*" >&2; }

install_qemu() {
    command -v qemu-system-arm >/dev/null 2>&1 && return 0
    local cmd="apt-get install -y qemu-system-arm"
    if command -v apt-get >/dev/null 2>&1; then
        if [ "$(id -u)" -eq 0 ]; then
            say "qemu-system-arm is missing; installing it: $cmd"
            (apt-get update -qq && DEBIAN_FRONTEND=noninteractive $cmd -qq) >&2 && return 0
        elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            say "qemu-system-arm is missing; installing it: sudo $cmd"
            (sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive $cmd -qq) >&2 && return 0
        fi
    fi
    say "qemu-system-arm is missing; install it with: sudo $cmd"
    exit 127
}

install_defmt_print() {
    command -v defmt-print >/dev/null 2>&1 && return 0
    local cargo_bin="${CARGO_HOME:-$HOME/.cargo}/bin"
    if [ -x "$cargo_bin/defmt-print" ]; then
        PATH="$cargo_bin:$PATH"
        return 0
    fi
    local cmd="cargo install defmt-print --locked"
    if command -v cargo >/dev/null 2>&1; then
        say "defmt-print is missing; installing it: $cmd"
        # Outside this workspace, so that its rust-toolchain.toml does not apply.
        (cd / && cargo install defmt-print --locked --quiet) >&2 && PATH="$cargo_bin:$PATH" && return 0
    fi
    say "defmt-print is missing; install it with: $cmd"
    exit 127
}

# Does the ELF have a `.defmt` section? readelf (binutils) when present, else the section-name
# string table read as bytes.
has_defmt() {
    if command -v readelf >/dev/null 2>&1; then
        readelf -S -W "$elf" | grep -q '[[:space:]]\.defmt[[:space:]]'
    else
        LC_ALL=C grep -q -a -F '.defmt' "$elf"
    fi
}

[ -f "$elf" ] || { say "no such file: $elf"; exit 2; }
install_qemu

qemu=(qemu-system-arm
    -machine mps2-an386 -cpu cortex-m4
    -nographic -monitor none -serial none
    -semihosting-config enable=on,target=native
    -icount shift=0
    -kernel "$elf")

set +e
if has_defmt; then
    install_defmt_print
    timeout --foreground "$timeout_s" "${qemu[@]}" | defmt-print -e "$elf"
    codes=("${PIPESTATUS[@]}")
    status=${codes[0]}
    if [ "$status" -eq 0 ] && [ "${codes[1]}" -ne 0 ]; then
        say "defmt-print failed (status ${codes[1]})"
        status=${codes[1]}
    fi
else
    timeout --foreground "$timeout_s" "${qemu[@]}"
    status=$?
fi
set -e

case $status in
    0) ;;
    124) say "timeout: $elf did not exit within ${timeout_s} s (QEMU_RUN_TIMEOUT)" ;;
    *) say "$elf exited with status $status" ;;
esac
exit "$status"
