"""Shared fixtures of the quadkin tests: the repository root and the `quadctl` binary (built by
cargo when missing; the Rust side's answers for the round trips)."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def quadctl() -> pathlib.Path:
    """The workspace's debug `quadctl` (the `test` step of `cargo xtask ci` has built it)."""
    env = {k: v for k, v in os.environ.items() if k != "RUSTUP_TOOLCHAIN"}
    subprocess.run(
        ["cargo", "build", "--quiet", "-p", "quadctl"], cwd=ROOT, check=True, env=env
    )
    exe = ROOT / "target" / "debug" / "quadctl"
    assert exe.is_file(), exe
    return exe


@pytest.fixture(scope="session")
def link_bridge() -> pathlib.Path:
    """The workspace's debug `quad-link-bridge`, which runs the firmware in simavr for
    `quadkin.Device.emulator` (the test step of `cargo xtask ci` has built it)."""
    env = {k: v for k, v in os.environ.items() if k != "RUSTUP_TOOLCHAIN"}
    subprocess.run(
        ["cargo", "build", "--quiet", "-p", "quad-link-bridge"], cwd=ROOT, check=True, env=env
    )
    exe = ROOT / "target" / "debug" / "quad-link-bridge"
    assert exe.is_file(), exe
    return exe


@pytest.fixture(scope="session")
def firmware_elf() -> pathlib.Path:
    """The firmware ELF built by the CI's `firmware` step (`cd firmware-avr && cargo build
    --release`); missing is a failure, not a skip."""
    elf = ROOT / "firmware-avr" / "target" / "avr-none" / "release" / "firmware.elf"
    assert elf.is_file(), f"{elf}: build the firmware first (cd firmware-avr && cargo build --release)"
    return elf
