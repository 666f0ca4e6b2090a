#!/usr/bin/env bash
# Builds the firmware and writes it to an Arduino Mega 2560 through its USB bootloader.
#
#   scripts/flash.sh [--baud 115200|1000000] [--dry-run] PORT
#
#   PORT       the Mega's serial port, e.g. /dev/ttyACM0
#   --baud     line rate the firmware will talk at (default 115200: firmware.elf;
#              1000000: firmware-1mbaud.elf). quadctl must use the same --baud.
#   --dry-run  build, then print the avrdude command instead of running it.
#
# Needs what scripts/install-deps.sh installs (nightly with rust-src, gcc-avr, avr-libc) and
# avrdude (Debian: apt-get install avrdude). The bootloader itself always talks at 115200 baud
# (avrdude -b 115200), whatever the firmware's line rate. See docs/hardware.md.
set -euo pipefail

die() {
    echo "flash: error: $*" >&2
    exit 2
}

baud=115200
dry_run=0
port=""
while [ $# -gt 0 ]; do
    case "$1" in
        --baud)
            [ $# -ge 2 ] || die "--baud needs a value"
            baud="$2"
            shift 2
            ;;
        --dry-run)
            dry_run=1
            shift
            ;;
        -h | --help)
            sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'
            exit 0
            ;;
        -*) die "unknown option $1" ;;
        *)
            [ -z "$port" ] || die "more than one port given"
            port="$1"
            shift
            ;;
    esac
done
[ -n "$port" ] || die "no port given (usage: scripts/flash.sh [--baud B] [--dry-run] PORT)"

case "$baud" in
    115200) bin=firmware ;;
    1000000) bin=firmware-1mbaud ;;
    *) die "--baud $baud: the firmware is built for 115200 or 1000000" ;;
esac

cd "$(dirname "$0")/../firmware-avr"
# Started from another cargo (e.g. a test), its toolchain selection must not leak in: this
# directory's rust-toolchain.toml decides.
unset RUSTUP_TOOLCHAIN CARGO_TARGET_DIR RUSTFLAGS CARGO_BUILD_TARGET
echo "flash: building the firmware (cargo build --release in firmware-avr/)"
cargo build --release
elf="$PWD/target/avr-none/release/$bin.elf"
[ -f "$elf" ] || die "$elf was not built"

cmd=(avrdude -c wiring -p atmega2560 -P "$port" -b 115200 -D -U "flash:w:$elf:e")
if [ "$dry_run" -eq 1 ]; then
    echo "${cmd[*]}"
    exit 0
fi
command -v avrdude >/dev/null 2>&1 || die "avrdude not found (Debian: apt-get install avrdude)"
echo "flash: writing $bin.elf to the ATmega2560 on $port"
"${cmd[@]}"
echo "flash: done; the firmware talks at $baud baud (quadctl ... --port $port --baud $baud)"
