"""Motion laws sampled to arrays: the same samples as `quadctl motion`'s CSV, bit for bit."""

import csv
import io
import subprocess

import numpy as np
import pytest

import quadkin


def quadctl_motion(quadctl, law, robot, duration_s, rate_hz, *extra):
    out = subprocess.run(
        [
            str(quadctl),
            "motion",
            law,
            "--robot",
            robot,
            "--duration-s",
            str(duration_s),
            "--rate-hz",
            str(rate_hz),
            *extra,
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    lines = [l for l in out.splitlines() if not l.startswith("#")]
    return list(csv.DictReader(io.StringIO("\n".join(lines))))


@pytest.mark.parametrize(
    "law, robot, extra, kwargs",
    [
        ("roll-sway", "fernando2025", (), {}),
        ("yaw-turn", "fernando2025", (), {}),
        ("rect-path", "shahriar2023", (), {}),
        ("trot", "shahriar2023", ("--forward-m-s", "0.1"), {"forward_m_s": 0.1}),
        ("pitch-sway", "shahriar2023", ("--amplitude-rad", "0.2"), {"amplitude_rad": 0.2}),
    ],
)
def test_samples_equal_quadctl_motion(quadctl, law, robot, extra, kwargs):
    m = quadkin.sample_motion(law, robot, duration_s=1.0, rate_hz=40.0, **kwargs)
    rows = quadctl_motion(quadctl, law, robot, 1.0, 40.0, *extra)
    n = len(rows)
    assert m["t_s"].shape == (n,)
    assert m["angles_rad"].shape == (n, 4, 3) and m["angles_rad"].dtype == np.float32
    assert m["feet_in_world_m"].shape == (n, 4, 3) and m["pose"].shape == (n, 6)
    for k, row in enumerate(rows):
        assert m["t_s"][k] == float(row["t_s"])
        if row["status"] == "ok":
            assert m["code"][k] == quadkin.OK and m["leg"][k] == -1
            for i, leg in enumerate(quadkin.LEGS):
                for j, joint in enumerate(quadkin.JOINTS):
                    assert m["angles_rad"][k, i, j] == np.float32(row[f"{leg}_{joint}_rad"])
        else:
            leg, code = row["status"].split(":")
            assert quadkin.LEGS[m["leg"][k]] == leg
            assert quadkin.CODE_NAMES[m["code"][k]] == code
        for i, leg in enumerate(quadkin.LEGS):
            for j, a in enumerate("xyz"):
                assert m["feet_in_world_m"][k, i, j] == np.float32(row[f"{leg}_{a}_m"])
        for j, c in enumerate(["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"]):
            assert m["pose"][k, j] == np.float32(row[c])


def test_laws_and_bad_parameters():
    assert quadkin.motion_laws() == [
        "roll-sway",
        "pitch-sway",
        "yaw-sway",
        "yaw-turn",
        "rect-path",
        "trot",
        "walk",
        "stable-turn",
    ]
    with pytest.raises(ValueError, match="law"):
        quadkin.sample_motion("moonwalk")
    with pytest.raises(ValueError, match="period"):
        quadkin.sample_motion("roll-sway", period_s=-1.0)
    with pytest.raises(ValueError, match="does not apply"):
        quadkin.sample_motion("roll-sway", stride_m=0.1)
