"""The examples under examples/python run as written and produce their outputs."""

import pathlib
import subprocess
import sys


def test_fifty_points(root):
    out = subprocess.run(
        [sys.executable, str(root / "examples/python/fifty_points.py")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "all 200 targets solved within 1 µm" in out


def test_workspace_map(root, tmp_path: pathlib.Path):
    png = tmp_path / "map.png"
    subprocess.run(
        [sys.executable, str(root / "examples/python/workspace_map.py"), "--out", str(png)],
        check=True,
        capture_output=True,
    )
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_readme_python_example_runs_as_written(root):
    text = (root / "README.md").read_text()
    blocks = text.split("```python\n")[1:]
    assert blocks, "README.md has a python block"
    for block in blocks:
        code = block.split("```")[0]
        assert len(code.strip().splitlines()) == 5
        subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
