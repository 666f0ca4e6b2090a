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
