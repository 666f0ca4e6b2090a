"""The conformance kit (docs/conformance.md) replayed through the package's protocol functions:
every recorded request's JSON fields encode to its recorded bytes, and every recorded answer's
bytes decode to its JSON fields within the recorded tolerances."""

import json
import math
from pathlib import Path

import pytest

import quadkin

KIT = Path(__file__).resolve().parents[3] / "docs" / "conformance"


def records():
    files = sorted(KIT.glob("*.jsonl"))
    assert files, f"no conformance files in {KIT}"
    for f in files:
        for n, line in enumerate(f.read_text().splitlines(), start=1):
            yield pytest.param(json.loads(line), id=f"{f.name}:{n}")


def same(got, want, tolerance, ignore, key=None):
    if key in ignore:
        return True
    if isinstance(want, dict):
        return isinstance(got, dict) and got.keys() == want.keys() and all(
            same(got[k], want[k], tolerance, ignore, k) for k in want
        )
    if isinstance(want, list):
        return (
            isinstance(got, list)
            and len(got) == len(want)
            and all(same(g, w, tolerance, ignore, key) for g, w in zip(got, want))
        )
    if isinstance(want, float) or isinstance(got, float):
        return math.isclose(got, want, rel_tol=0.0, abs_tol=tolerance.get(key, 0.0))
    return got == want


@pytest.mark.parametrize("record", list(records()))
def test_the_kit_replays(record):
    if record["request"] is not None:
        frame = quadkin.encode_request(json.dumps(record["request"]))
        assert frame.hex(" ") == record["request_hex"], record["name"]
    answer = json.loads(quadkin.decode_answer(bytes.fromhex(record["answer_hex"])))
    assert same(answer, record["answer"], record["tolerance"], set(record["ignore"])), (
        record["name"],
        answer,
    )


def test_bad_input_names_the_problem():
    with pytest.raises(ValueError, match="host-to-device"):
        quadkin.encode_request('{"seq": 1, "request": "no_such_request"}')
    with pytest.raises(ValueError):
        quadkin.decode_answer(bytes.fromhex("00 05 01 01 c1 e1 00"))
