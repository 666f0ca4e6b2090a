#!/usr/bin/env bash
# Installs everything the checks need on a Debian 12 machine, idempotently.
#
#   - Debian packages: the AVR toolchain (firmware link), simavr and the libraries its Rust
#     bindings build against (emulator tests), libudev (serial ports / flashing).
#   - the physics twin: Python's venv module and the libraries of MuJoCo's offscreen
#     rendering (EGL, and OSMesa as the software fallback), then a virtual environment
#     `.venv-twin` at the repository root with the pinned packages of twin/requirements.txt
#     (recreated only when that file changes).
#   - the browser panel (`quadctl serve`): Debian's chromium and chromium-driver (the browser
#     tests drive the headless browser through chromedriver), Node.js and npm, then `npm ci`
#     in web/ (three.js, pinned by web/package-lock.json; rerun only when that file changes).
#   - the Python package `quadkin` (crates/kin-py): a virtual environment `.venv-py` at the
#     repository root with the pinned packages of crates/kin-py/requirements.txt (maturin,
#     numpy, pytest, matplotlib; recreated only when that file changes), then the package's
#     wheel built by maturin (release, target dir target/python; cargo rebuilds only what
#     changed) and installed into it.
#   - rustup: the `nightly` toolchain with `rust-src` (no_std build for avr-none with
#     `-Z build-std=core`), clippy + rustfmt on `stable` (rust-toolchain.toml), and the
#     `wasm32-unknown-unknown` target on `stable` (kin-core in the browser, crates/kin-wasm).
#
# Does nothing (and needs no network) when everything is already present, but for the quadkin
# wheel, rebuilt and reinstalled every run (cargo recompiles only what changed). Installing needs
# root; without it, a missing piece is an error naming the command to run.
set -euo pipefail

APT_PACKAGES=(
    gcc-avr avr-libc binutils-avr
    libelf-dev libclang-dev libzstd-dev zlib1g-dev pkg-config make
    simavr
    libudev-dev
    fonts-dejavu-core
    python3 python3-venv libegl1 libosmesa6
    chromium chromium-driver
)
NIGHTLY=nightly
STABLE_COMPONENTS=(clippy rustfmt)

die() {
    echo "install-deps: error: $*" >&2
    exit 1
}

is_root() { [ "$(id -u)" -eq 0 ]; }

# --- Debian packages -------------------------------------------------------------------------
missing=()
for pkg in "${APT_PACKAGES[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
    if [ "$status" != "install ok installed" ]; then
        missing+=("$pkg")
    fi
done

if [ "${#missing[@]}" -gt 0 ]; then
    command -v apt-get >/dev/null 2>&1 ||
        die "missing packages (${missing[*]}) and no apt-get: this script supports Debian 12"
    is_root ||
        die "missing packages: ${missing[*]}; run as root: apt-get update && apt-get install -y ${missing[*]}"
    echo "install-deps: installing ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q </dev/null
    apt-get install -y -q "${APT_PACKAGES[@]}" </dev/null
else
    echo "install-deps: Debian packages present"
fi

# --- Rust toolchains -------------------------------------------------------------------------
command -v rustup >/dev/null 2>&1 || die "rustup not found on PATH (see https://rustup.rs)"

# The parent cargo exports the toolchain it runs under; queries here name toolchains explicitly.
unset RUSTUP_TOOLCHAIN

has_component() { # toolchain component
    rustup component list --toolchain "$1" --installed 2>/dev/null | grep -q "^$2\(-\|$\)"
}

if ! rustup toolchain list | grep -q "^${NIGHTLY}-"; then
    echo "install-deps: installing toolchain ${NIGHTLY} with rust-src"
    rustup toolchain install "$NIGHTLY" --profile minimal --component rust-src </dev/null
elif ! has_component "$NIGHTLY" rust-src; then
    echo "install-deps: adding rust-src to ${NIGHTLY}"
    rustup component add rust-src --toolchain "$NIGHTLY" </dev/null
else
    echo "install-deps: ${NIGHTLY} with rust-src present"
fi

stable_missing=()
for c in "${STABLE_COMPONENTS[@]}"; do
    has_component stable "$c" || stable_missing+=("$c")
done
if [ "${#stable_missing[@]}" -gt 0 ]; then
    echo "install-deps: adding ${stable_missing[*]} to stable"
    rustup component add "${stable_missing[@]}" --toolchain stable </dev/null
else
    echo "install-deps: stable with ${STABLE_COMPONENTS[*]} present"
fi

if rustup target list --toolchain stable --installed 2>/dev/null | grep -q '^wasm32-unknown-unknown$'; then
    echo "install-deps: stable with wasm32-unknown-unknown present"
else
    echo "install-deps: adding wasm32-unknown-unknown to stable"
    rustup target add wasm32-unknown-unknown --toolchain stable </dev/null
fi

# --- Browser panel: three.js from npm (web/package-lock.json) --------------------------------
# Node.js may come from Debian (nodejs + npm) or from NodeSource (nodejs alone, with npm inside,
# conflicting with Debian's npm): only the command is checked.
if ! command -v npm >/dev/null 2>&1; then
    is_root || die "npm not found; run as root: apt-get install -y nodejs npm"
    echo "install-deps: installing nodejs npm"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q nodejs npm </dev/null
fi
WEB="$(cd "$(dirname "$0")/.." && pwd)/web"
web_want=$(sha256sum "$WEB/package-lock.json" | cut -d' ' -f1)
web_have=$(cat "$WEB/node_modules/.package-lock.sha256" 2>/dev/null || true)
if [ -d "$WEB/node_modules/three" ] && [ "$web_want" = "$web_have" ]; then
    echo "install-deps: web/node_modules present"
else
    echo "install-deps: npm ci in web/"
    (cd "$WEB" && npm ci --no-audit --no-fund --loglevel=error </dev/null)
    echo "$web_want" >"$WEB/node_modules/.package-lock.sha256"
fi

# --- Physics twin: Python virtual environment ------------------------------------------------
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV="$ROOT/.venv-twin"
REQUIREMENTS="$ROOT/twin/requirements.txt"
STAMP="$VENV/.requirements.sha256"
want=$(sha256sum "$REQUIREMENTS" | cut -d' ' -f1)
have=$(cat "$STAMP" 2>/dev/null || true)
if [ -x "$VENV/bin/python" ] && [ "$want" = "$have" ]; then
    echo "install-deps: twin environment .venv-twin present"
else
    echo "install-deps: creating .venv-twin from twin/requirements.txt"
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install --quiet --disable-pip-version-check -r "$REQUIREMENTS" </dev/null
    echo "$want" >"$STAMP"
fi

# --- Python package: quadkin into .venv-py ---------------------------------------------------
PYVENV="$ROOT/.venv-py"
PYREQ="$ROOT/crates/kin-py/requirements.txt"
PYSTAMP="$PYVENV/.requirements.sha256"
want=$(sha256sum "$PYREQ" | cut -d' ' -f1)
have=$(cat "$PYSTAMP" 2>/dev/null || true)
if [ -x "$PYVENV/bin/python" ] && [ "$want" = "$have" ]; then
    echo "install-deps: Python environment .venv-py present"
else
    echo "install-deps: creating .venv-py from crates/kin-py/requirements.txt"
    rm -rf "$PYVENV"
    python3 -m venv "$PYVENV"
    "$PYVENV/bin/pip" install --quiet --disable-pip-version-check -r "$PYREQ" </dev/null
    echo "$want" >"$PYSTAMP"
fi
echo "install-deps: building the quadkin wheel (maturin) into .venv-py"
rm -rf "$ROOT/target/python/wheels"
(
    unset RUSTUP_TOOLCHAIN CARGO_ENCODED_RUSTFLAGS
    cd "$ROOT/crates/kin-py"
    "$PYVENV/bin/maturin" build --quiet --release --interpreter "$PYVENV/bin/python" \
        --target-dir "$ROOT/target/python" --out "$ROOT/target/python/wheels" </dev/null
)
"$PYVENV/bin/pip" install --quiet --disable-pip-version-check --no-deps --force-reinstall \
    "$ROOT"/target/python/wheels/quadkin-*.whl </dev/null
